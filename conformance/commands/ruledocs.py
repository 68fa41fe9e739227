"""Render the rule catalogue as Markdown (docs/rules.md is generated from it, never by hand)."""
from __future__ import annotations

from ..report.catalogue import Catalogue, RuleSpec
from ..model.drafts.names import DRAFT_LABELS

HEADER = """# lsdae rules

Generated from `rules/*.toml` by `lsdae rules --format markdown > docs/rules.md`; do not edit.
`lsdae explain CODE` shows the same text in a terminal.
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
        f"**{rule.severity}** · stage {rule.stage} · {_drafts(rule)} · spec: {rule.spec}",
        "",
        rule.summary,
        "",
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
    if rule.options:
        lines += ["", "Options:", ""] + [f"- `{k}` = `{v!r}`" for k, v in rule.options]
    return "\n".join(lines)


def render_markdown(catalogue: Catalogue) -> str:
    table = ["| code | name | severity | stage | summary |", "|---|---|---|---|---|"]
    table += [f"| [{r.code}](#{r.code.lower()}-{r.name}) | `{r.name}` | {r.severity} | "
              f"{r.stage} | {r.summary} |" for r in catalogue]
    drafts = ["| draft id | shape |", "|---|---|"]
    drafts += [f"| `{k}` | {v} |" for k, v in DRAFT_LABELS.items()]
    body = "\n\n".join(_section(r) for r in catalogue)
    return "\n".join([HEADER, "\n".join(table), "", "Draft ids:", "", "\n".join(drafts), "",
                      body, ""])
