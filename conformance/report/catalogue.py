"""Load the rule catalogue (``rules/*.toml``) into :class:`RuleSpec` objects.

The catalogue is the single source of truth for codes, names, the basis of each verdict and the
severity it gives, the drafts a rule applies to, spec references, docs and options. Nothing
else in the code base states them.
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
REQUIRED = ("code", "name", "basis", "stage", "drafts", "spec", "summary", "rationale", "bad",
            "good")

#: What a verdict rests on, and the severity it gives; the one place severity is decided.
#: ``must``: MUST, SHALL or REQUIRED in normative text; ``definition``: normative declarative
#: text the FMU contradicts; ``contradiction``: the FMU contradicts itself (two declarations, a
#: declaration and its binary, its two modes at one point); ``should``: SHOULD or RECOMMENDED;
#: ``interop``: what named importers do with it; ``advice``: a note, a bracketed remark or no
#: text (our recommendation, or a call the importer must not make: robustness); ``limit``:
#: lsdae's own limits (time, memory, size), a warning that names the limit and never calls the
#: FMU non-conformant.
BASIS_SEVERITY: dict[str, Severity] = {
    "must": Severity.ERROR, "definition": Severity.ERROR, "contradiction": Severity.ERROR,
    "should": Severity.WARNING, "interop": Severity.WARNING, "limit": Severity.WARNING,
    "advice": Severity.INFO,
}

#: What each kind says, for the rule docs, ``lsdae explain``, SARIF's help and the HTML report.
BASIS_MEANING: dict[str, str] = {
    "must": "the text requires it",
    "definition": "the text defines it so, and the FMU contradicts the definition",
    "contradiction": "the FMU contradicts itself",
    "should": "the text recommends it",
    "interop": "named importers reject or misread it",
    "advice": "a note, a remark or no text: a recommendation, not a requirement",
    "limit": "lsdae's own limit, not a verdict on the FMU",
}

#: The documents a basis may name: the originals (by version), the importers, lsdae itself
#: (a limit), or none (advice with no text).
DOCUMENTS = ("FMI 3.0.2", "fmi-ls-dae 1.0.0-alpha.1", "fmi-ls-dae 1.0.0-alpha.1 schema",
             "paper 2026", "importers", "lsdae", "none")

#: The words a basis of kind must or should quotes (RFC 2119, as the FMI text uses them).
KEYWORDS = {"must": ("must", "shall", "required", "has to"),
            "should": ("should", "recommended")}


@dataclass(frozen=True, slots=True)
class Basis:
    """What one verdict rests on: its kind, and where the text is (document and version,
    section, the words as written). A rule has one; a sub-check whose basis differs has its
    own, named by ``part`` (the id a check sets on its violations) and described by ``what``."""

    kind: str
    document: str
    section: str
    word: str
    part: str = ""
    what: str = ""

    @property
    def severity(self) -> Severity:
        return BASIS_SEVERITY[self.kind]

    def describe(self) -> str:
        """The kind, what it means, and where the text is: one line for docs and reporters."""
        return f"{self.kind} ({BASIS_MEANING[self.kind]}); {self.cite()}"

    def cite(self) -> str:
        """One line: the document, the section and the words, as far as there are any."""
        where = ", ".join(x for x in (self.document if self.document != "none" else "",
                                      self.section) if x)
        return f"{where}: \u201c{self.word}\u201d" if where else self.word


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
    basis: Basis | None = None  # what the verdict rests on; severity is basis.severity
    parts: tuple[Basis, ...] = ()   # sub-checks whose basis differs, by Basis.part

    def part(self, name: str | None) -> Basis | None:
        """The basis of sub-check ``name`` (None or unknown: the rule's own)."""
        for basis in self.parts:
            if basis.part == name:
                return basis
        return self.basis

    def severity_of(self, part: str | None) -> Severity:
        """The severity of a violation of sub-check ``part`` (None: the rule's)."""
        basis = self.part(part) if part else None
        return basis.severity if basis is not None else self.severity

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
    for old in ("severity", "force", "force_spec"):
        if old in table:
            raise CatalogueError(f"{source}: rule {table['code']} sets {old!r}; the severity "
                                 "follows from [rule.basis] kind alone")
    basis = _basis(table["basis"], f"{source}: rule {table['code']}")
    parts = tuple(_basis(part, f"{source}: rule {table['code']} part", part=True)
                  for part in table.get("parts", ()))
    if len({p.part for p in parts}) != len(parts):
        raise CatalogueError(f"{source}: rule {table['code']} names a part twice")
    fix = table.get("fix")
    if fix is not None and (not isinstance(fix, str)
                            or not fix.startswith(FIX_KINDS) or not fix.split(":", 1)[1].strip()):
        raise CatalogueError(f"{source}: rule {table['code']} has fix {fix!r}; write "
                             '"safe: how", "unsafe: how" or "none: why"')
    return RuleSpec(
        code=table["code"], name=table["name"], severity=basis.severity,
        stage=stage, drafts=tuple(table["drafts"]), needs=needs, spec=table["spec"],
        summary=table["summary"].strip(), rationale=table["rationale"].strip(),
        bad=table["bad"].strip("\n"), good=table["good"].strip("\n"),
        aliases=tuple(table.get("aliases", ())),
        options=tuple(sorted(table.get("options", {}).items())), source=source,
        fix=" ".join(fix.split()) if fix else None,
        basis=basis, parts=parts,
    )


def _basis(table: Mapping[str, Any], where: str, *, part: bool = False) -> Basis:
    """A ``[rule.basis]`` or ``[[rule.parts]]`` table, refused when it lacks a kind, a
    location, or (must, should) the keyword it rests on."""
    if not isinstance(table, Mapping):
        raise CatalogueError(f"{where}: basis must be a table")
    fields = ("kind", "document", "section", "word") + (("part", "what") if part else ())
    missing = [k for k in fields if not isinstance(table.get(k), str)]
    unknown = set(table) - set(fields)
    if missing or unknown:
        raise CatalogueError(f"{where}: basis lacks {', '.join(missing) or '-'}"
                             f"{'; unknown ' + ', '.join(sorted(unknown)) if unknown else ''}")
    basis = Basis(**{k: " ".join(table[k].split()) for k in fields})
    if basis.kind not in BASIS_SEVERITY:
        raise CatalogueError(f"{where}: basis kind {basis.kind!r}; use one of "
                             f"{', '.join(BASIS_SEVERITY)}")
    if basis.document not in DOCUMENTS:
        raise CatalogueError(f"{where}: basis document {basis.document!r}; use one of "
                             f"{', '.join(DOCUMENTS)}")
    if not basis.word:
        raise CatalogueError(f"{where}: basis gives no word (the text as written, or why none)")
    original = basis.document not in ("importers", "lsdae", "none")
    if basis.kind in ("must", "should", "definition") and not (original and basis.section):
        raise CatalogueError(f"{where}: a {basis.kind} basis names the original's section")
    if basis.kind in KEYWORDS and not any(w in basis.word.lower() for w in KEYWORDS[basis.kind]):
        raise CatalogueError(f"{where}: a {basis.kind} basis quotes its keyword "
                             f"({' or '.join(KEYWORDS[basis.kind])}); it reads {basis.word!r}")
    if basis.kind == "interop" and basis.document != "importers":
        raise CatalogueError(f"{where}: an interop basis names the importers")
    if basis.kind == "limit" and basis.document != "lsdae":
        raise CatalogueError(f"{where}: a limit is lsdae's own (document \"lsdae\")")
    return basis


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
