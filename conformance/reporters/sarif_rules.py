"""SARIF rule descriptors: the catalogue's rules (and rules it does not know) as SARIF
``reportingDescriptor`` objects, with the help text GitHub code scanning shows, and the links to
the generated rule docs."""
from __future__ import annotations

from typing import Any

from ..report.catalogue import Catalogue, RuleSpec
from ..report.findings import Finding, Report, Severity

#: Where the rule documentation is published (docs/rules.md, generated from the catalogue).
PROJECT_URL = "https://github.com/lsdae/lsdae"
RULES_DOC_URL = f"{PROJECT_URL}/blob/main/docs/rules.md"
#: GitHub cuts rule descriptions at 1024 characters; we cut first, at a word.
DESCRIPTION_LIMIT = 1024

LEVEL = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "note"}
_PROBLEM_SEVERITY = {Severity.ERROR: "error", Severity.WARNING: "warning",
                     Severity.INFO: "recommendation"}


def rule_url(code: str, name: str, *, docs_url: str = RULES_DOC_URL) -> str:
    """The rule's section in docs/rules.md (GitHub's anchor for '## CODE `name`')."""
    return f"{docs_url}#{code.lower()}-{name}"


# -- rules -----------------------------------------------------------------------------------

def _cut(text: str, limit: int = DESCRIPTION_LIMIT) -> str:
    text = " ".join(text.split())
    if len(text) <= limit:
        return text
    return text[:limit - 1].rsplit(" ", 1)[0] + "…"


def _fence(text: str) -> str:
    lang = "xml" if text.lstrip().startswith("<") else "text"
    return f"```{lang}\n{text}\n```"


def _basis_lines(rule: RuleSpec) -> list[str]:
    """What the verdict rests on: the rule's basis and each part's, one line each."""
    lines = [f"Basis: {rule.basis.describe()}"] if rule.basis else []
    lines += [f"Part {b.part} ({b.what}, {b.severity}): {b.describe()}" for b in rule.parts]
    return lines


def _help_text(rule: RuleSpec, url: str) -> str:
    return "\n".join([
        rule.summary, "", rule.rationale, "",
        *_basis_lines(rule),
        f"Spec: {rule.spec}", f"Applies to drafts: {', '.join(rule.drafts)}", "",
        "Fails:", rule.bad, "", "Passes:", rule.good, "", f"Documentation: {url}",
    ])


def _help_markdown(rule: RuleSpec, url: str) -> str:
    drafts = ", ".join("all drafts" if d == "*" else f"`{d}`" for d in rule.drafts)
    return "\n".join([
        f"**{rule.code} `{rule.name}`** ({rule.severity}, {rule.stage} stage)", "",
        rule.summary, "", rule.rationale, "",
        *[f"**{line.split(':', 1)[0]}:**{line.split(':', 1)[1]}  " for line in _basis_lines(rule)],
        f"**Spec:** {rule.spec}  ", f"**Applies to:** {drafts}", "",
        "Fails:", "", _fence(rule.bad), "", "Passes:", "", _fence(rule.good), "",
        f"[Full documentation]({url})",
    ])


def _descriptor(rule: RuleSpec, docs_url: str) -> dict[str, Any]:
    url = rule_url(rule.code, rule.name, docs_url=docs_url)
    return {
        "id": rule.code,
        "name": rule.name,
        "shortDescription": {"text": _cut(rule.summary)},
        "fullDescription": {"text": _cut(rule.rationale or rule.summary)},
        "helpUri": url,
        "help": {"text": _help_text(rule, url), "markdown": _help_markdown(rule, url)},
        "defaultConfiguration": {"level": LEVEL[rule.severity]},
        "properties": {
            "tags": ["fmi-ls-dae", rule.stage],
            "precision": "high" if rule.stage in ("probe", "simulation") else "very-high",
            "problem.severity": _PROBLEM_SEVERITY[rule.severity],
            "spec": rule.spec,
            **({"basis": rule.basis.kind} if rule.basis else {}),
            "drafts": list(rule.drafts),
        },
    }


def _unknown_descriptor(finding: Finding) -> dict[str, Any]:
    """For a finding whose code the catalogue does not know (a newer engine's pseudo-rule)."""
    text = finding.name or finding.code
    return {
        "id": finding.code, "name": finding.name or finding.code,
        "shortDescription": {"text": text}, "fullDescription": {"text": text},
        "help": {"text": f"{finding.code} {text}: not in this lsdae's rule catalogue."},
        "defaultConfiguration": {"level": LEVEL[finding.severity]},
    }


def descriptors(report: Report, catalogue: Catalogue | None, docs_url: str
                 ) -> tuple[list[dict[str, Any]], dict[str, int]]:
    rules = [_descriptor(r, docs_url) for r in catalogue or ()]
    index = {d["id"]: i for i, d in enumerate(rules)}
    unknown: dict[str, Finding] = {}
    for finding in report.all_findings():
        if finding.code not in index:
            unknown.setdefault(finding.code, finding)
    for code in sorted(unknown):
        index[code] = len(rules)
        rules.append(_unknown_descriptor(unknown[code]))
    return rules, index


# -- results ---------------------------------------------------------------------------------
