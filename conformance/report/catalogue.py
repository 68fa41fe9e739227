"""Load the rule catalogue (``rules/*.toml``) into :class:`RuleSpec` objects.

The catalogue is the single source of truth for codes, names, default severities, the drafts a
rule applies to, spec references, docs and options. Nothing else in the code base states them.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping

from .findings import Severity
from .paths import rules_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

STAGES = ("archive", "xml", "schema", "static", "probe", "simulation")
NEEDS = ("model-description", "manifest", "dae-layer", "binary")
FIX_KINDS = ("safe:", "unsafe:", "none:")
REQUIRED = ("code", "name", "severity", "stage", "drafts", "spec", "summary", "rationale",
            "bad", "good")


class CatalogueError(Exception):
    """The catalogue itself is inconsistent (a defect of ours, caught by the tests)."""


@dataclass(frozen=True, slots=True)
class RuleSpec:
    code: str
    name: str
    severity: Severity
    stage: str
    drafts: tuple[str, ...]
    needs: tuple[str, ...]
    spec: str
    summary: str
    rationale: str
    bad: str
    good: str
    aliases: tuple[str, ...] = ()
    options: tuple[tuple[str, Any], ...] = ()
    source: str = ""
    fix: str | None = None      # "safe: how", "unsafe: how" or "none: why no fix can exist"

    @property
    def fix_kind(self) -> str | None:
        """``"safe"``, ``"unsafe"`` or None (no fix): what ``lsdae fix`` can do for this rule."""
        kind = self.fix.split(":", 1)[0] if self.fix else None
        return kind if kind in ("safe", "unsafe") else None

    def applies_to(self, draft: str | None) -> bool:
        return "*" in self.drafts or (draft is not None and draft in self.drafts)

    @property
    def option_values(self) -> dict[str, Any]:
        return dict(self.options)


class Catalogue:
    """All rules, addressable by code, name or alias; iteration is in code order."""

    def __init__(self, rules: Iterable[RuleSpec]):
        self._by_code: dict[str, RuleSpec] = {}
        self._by_name: dict[str, RuleSpec] = {}
        for rule in rules:
            if rule.code in self._by_code:
                raise CatalogueError(f"duplicate rule code {rule.code} ({rule.source})")
            self._by_code[rule.code] = rule
            for name in (rule.name, *rule.aliases):
                if name in self._by_name:
                    raise CatalogueError(f"duplicate rule name {name} ({rule.source})")
                self._by_name[name] = rule

    def __iter__(self) -> Iterator[RuleSpec]:
        return iter(sorted(self._by_code.values(), key=lambda r: r.code))

    def __len__(self) -> int:
        return len(self._by_code)

    def get(self, key: str) -> RuleSpec | None:
        """Look a rule up by code (case-insensitive), name or alias."""
        return self._by_code.get(key.upper()) or self._by_name.get(key.lower())

    def __getitem__(self, key: str) -> RuleSpec:
        rule = self.get(key)
        if rule is None:
            raise KeyError(key)
        return rule

    def matching(self, pattern: str) -> list[RuleSpec]:
        """Rules selected by a pattern: a code, a name, or a code prefix such as ``DAE2``."""
        exact = self.get(pattern)
        if exact is not None:
            return [exact]
        prefix = pattern.upper()
        return [r for r in self if r.code.startswith(prefix)] if prefix else []


def _rule(table: Mapping[str, Any], source: str) -> RuleSpec:
    missing = [k for k in REQUIRED if k not in table]
    if missing:
        raise CatalogueError(f"{source}: rule {table.get('code', '?')} lacks {', '.join(missing)}")
    stage = table["stage"]
    if stage not in STAGES:
        raise CatalogueError(f"{source}: rule {table['code']} has unknown stage {stage!r}")
    needs = tuple(table.get("needs", ()))
    for need in needs:
        if need not in NEEDS:
            raise CatalogueError(f"{source}: rule {table['code']} has unknown need {need!r}")
    fix = table.get("fix")
    if fix is not None and (not isinstance(fix, str)
                            or not fix.startswith(FIX_KINDS) or not fix.split(":", 1)[1].strip()):
        raise CatalogueError(f"{source}: rule {table['code']} has fix {fix!r}; write "
                             '"safe: how", "unsafe: how" or "none: why"')
    return RuleSpec(
        code=table["code"], name=table["name"], severity=Severity.parse(table["severity"]),
        stage=stage, drafts=tuple(table["drafts"]), needs=needs, spec=table["spec"],
        summary=table["summary"].strip(), rationale=table["rationale"].strip(),
        bad=table["bad"].strip("\n"), good=table["good"].strip("\n"),
        aliases=tuple(table.get("aliases", ())),
        options=tuple(sorted(table.get("options", {}).items())), source=source,
        fix=" ".join(fix.split()) if fix else None,
    )


def load_catalogue(directory: Path | None = None) -> Catalogue:
    """Read every ``*.toml`` in the rules directory."""
    directory = directory or rules_dir()
    rules = []
    for path in sorted(directory.glob("*.toml")):
        with path.open("rb") as fh:
            data = tomllib.load(fh)
        for table in data.get("rule", []):
            rules.append(_rule(table, path.name))
    return Catalogue(rules)


@lru_cache(maxsize=1)
def default_catalogue() -> Catalogue:
    return load_catalogue()


def _same_type(value: Any, default: Any) -> bool:
    if isinstance(default, bool) or isinstance(value, bool):
        return isinstance(value, bool) and isinstance(default, bool)
    if isinstance(default, float):
        return isinstance(value, (int, float))
    return isinstance(value, type(default))


def with_options(catalogue: Catalogue, overrides: Mapping[str, Mapping[str, Any]]) -> Catalogue:
    """A copy of ``catalogue`` whose rules take the option values in ``overrides``
    ({rule code or name: {option: value}}); ValueError for an unknown rule or option, or a
    value of another type than the option's default."""
    changed: dict[str, dict[str, Any]] = {}
    for key, values in overrides.items():
        rule = catalogue.get(key)
        if rule is None:
            raise ValueError(f"no rule {key!r} (see `lsdae rules`)")
        defaults = rule.option_values
        for name, value in values.items():
            if name not in defaults:
                known = ", ".join(sorted(defaults)) or "none"
                raise ValueError(f"{rule.code} {rule.name} has no option {name!r} "
                                 f"(its options: {known})")
            if not _same_type(value, defaults[name]):
                raise ValueError(f"{rule.code} {rule.name}: option {name} takes a "
                                 f"{type(defaults[name]).__name__}, not {value!r}")
            if isinstance(defaults[name], float) and not isinstance(value, bool):
                value = float(value)
            changed.setdefault(rule.code, dict(defaults))[name] = value
    if not changed:
        return catalogue
    return Catalogue(replace(r, options=tuple(sorted(changed[r.code].items())))
                     if r.code in changed else r for r in catalogue)
