"""Render the rule catalogue as Markdown (docs/rules.md is generated from it, never by hand)."""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from ..model.drafts.names import DRAFT_LABELS
from ..probes.machinery.registry import FAMILY_PACKAGE, MODULE_OF
from ..report.catalogue import Catalogue, RuleSpec

#: The rules that no registered check or probe emits: the engine's stages and the probe
#: driver's deaths, by name -> the module that emits them (tests/checks/test_catalogue.py
#: checks that each module names its rule).
EMITTED_BY: dict[str, str] = {
    **dict.fromkeys(("archive-unreadable", "unsafe-archive-path", "archive-duplicate-entry",
                     "archive-too-large", "archive-compression-method"),
                    "conformance.intake.archive.base"),
    **dict.fromkeys(("xml-not-well-formed", "xml-unsafe-construct"), "conformance.intake.xmlsafe"),
    "xml-encoding": "conformance.intake.xml_encoding",
    **dict.fromkeys(("schema-violation", "build-description-invalid"),
                    "conformance.intake.schemas"),
    "legacy-draft-shape": "conformance.model.drafts.migrate",
    "draft-unrecognised": "conformance.model.drafts.detect",
    **dict.fromkeys(("model-description-missing", "manifest-missing", "fmi-version-unsupported"),
                    "conformance.run.reading"),
    "internal-error": "conformance.run.engine",
    **dict.fromkeys(("binary-crashed", "binary-timed-out", "binary-memory-limit",
                     "binary-not-loadable"), "conformance.probes.machinery.deaths"),
}


_PACKAGE = Path(__file__).resolve().parents[1]


@lru_cache(maxsize=1)
def _check_modules() -> dict[str, str]:
    """code -> module of its static check, read from the text of each family's ``CHECKS`` dict
    (importing ``conformance.checks`` would load lxml into ``lsdae rules``)."""
    found: dict[str, str] = {}
    for path in sorted((_PACKAGE / "checks").glob("*.py")):
        for code in re.findall(r'^\s+"(DAE\d{3})":', path.read_text(encoding="utf-8"), re.M):
            found[code] = f"conformance.checks.{path.stem}"
    return found


def rule_home(rule: RuleSpec) -> str | None:
    """The source file of the code that decides ``rule`` (a path from the project's root), or
    None for a rule of a catalogue of one's own that lsdae does not know."""
    if rule.stage == "static" and rule.code in _check_modules():
        module = _check_modules()[rule.code]
    elif rule.code in MODULE_OF:
        module = f"{FAMILY_PACKAGE}.{MODULE_OF[rule.code]}"
    else:
        module = EMITTED_BY.get(rule.name)
    return module.replace(".", "/") + ".py" if module else None

HEADER = """# lsdae rules

Generated from `rules/*.toml` by `lsdae rules --format markdown > docs/rules.md`; do not edit.
`lsdae explain CODE` shows the same text in a terminal.

Each rule's severity follows from its *basis*, the kind of text its verdict rests on, read in
the originals (FMI 3.0.2, fmi-ls-dae 1.0.0-alpha.1 and its schema, the 2026 paper) and quoted
with its section: `must` (MUST, SHALL or REQUIRED in normative text), `definition` (normative
declarative text the FMU contradicts) and `contradiction` (the FMU contradicts itself) give an
error; `should` (SHOULD, RECOMMENDED) and `interop` (named importers reject or misread it) a
warning; `advice` (a note, a remark or no text) information; `limit` (lsdae's own limits) a
warning that never calls the FMU non-conformant. A sub-check whose basis differs is a *part*
with its own basis and severity.
"""


def _drafts(rule: RuleSpec) -> str:
    return ", ".join("all drafts" if d == "*" else f"`{d}`" for d in rule.drafts)


def _fence(text: str) -> str:
    lang = "xml" if text.lstrip().startswith("<") else "text"
    return f"```{lang}\n{text}\n```"


def _section(rule: RuleSpec) -> str:
    lines = [
        f"## {rule.code} `{rule.name}`",
        "",
        f"**{rule.severity}** ({rule.basis.kind if rule.basis else 'no basis'}) · "
        f"stage {rule.stage} · "
        f"{_drafts(rule)} · spec: {rule.spec}",
        "",
        rule.summary,
        "",
        *([f"Basis: {rule.basis.describe()}", ""] if rule.basis else []),
        *[f"- part `{b.part}` ({b.what}): **{b.severity}**, {b.describe()}"
          for b in rule.parts],
        *([""] if rule.parts else []),
        rule.rationale,
        "",
        "Fails:",
        "",
        _fence(rule.bad),
        "",
        "Passes:",
        "",
        _fence(rule.good),
    ]
    if rule.fix:
        kind, _, how = rule.fix.partition(":")
        lines += ["", f"Fix ({kind}, `lsdae fix`): {how.strip()}"]
    if rule.aliases:
        lines += ["", f"Aliases: {', '.join(f'`{a}`' for a in rule.aliases)}"]
    home = rule_home(rule)
    if home:
        lines += ["", f"Code: `{home}`"]
    if rule.options:
        lines += ["", "Options:", ""] + [f"- `{k}` = `{v!r}`" for k, v in rule.options]
    return "\n".join(lines)


def render_markdown(catalogue: Catalogue) -> str:
    table = ["| code | name | severity | basis | stage | summary |",
             "|---|---|---|---|---|---|"]
    table += [f"| [{r.code}](#{r.code.lower()}-{r.name}) | `{r.name}` | {r.severity} | "
              f"{r.basis.kind if r.basis else ''} | {r.stage} | {r.summary} |"
              for r in catalogue]
    drafts = ["| draft id | shape |", "|---|---|"]
    drafts += [f"| `{k}` | {v} |" for k, v in DRAFT_LABELS.items()]
    body = "\n\n".join(_section(r) for r in catalogue)
    return "\n".join([HEADER, "\n".join(table), "", "Draft ids:", "", "\n".join(drafts), "",
                      body, ""])
