"""A Markdown job summary (GitHub's ``$GITHUB_STEP_SUMMARY``, or any Markdown viewer).

A table with one row per FMU (verdict, counts by severity, draft), then per FMU its findings
grouped by severity with code, rule, message and location, and the rules that were skipped.
Findings a baseline accepted are listed, marked, but counted apart and never fail an FMU.
Text from the FMU is escaped, so a variable called ``<b>|x`` can neither open HTML nor split a
table cell. GitHub accepts at most 1 MiB of summary per step: past a budget the details stop
with a line saying how many findings were left out.
"""
from __future__ import annotations

import re
from typing import Any

from ..report.catalogue import Catalogue
from ..model.drafts.names import DRAFT_LABELS
from ..report.findings import Finding, FmuReport, Report, RunInfo, Severity
from .sarif import inner_location, is_baselined
from .sarif_rules import RULES_DOC_URL, rule_url

#: Bytes of summary we allow ourselves; GitHub's limit is 1 MiB per step.
BUDGET = 900_000
_HEADINGS = {Severity.ERROR: "Errors", Severity.WARNING: "Warnings", Severity.INFO: "Info"}
# Markup that works anywhere in a line (lines and cells here never start with user text);
# '@' and '#' would turn names into mentions and issue links.
_SPECIAL = re.compile(r"([\\`*_\[\]|~@#])")


def text(value: str) -> str:
    """Escape text for Markdown (tables included): HTML entities, backslash before markup."""
    value = value.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    value = _SPECIAL.sub(r"\\\1", value)
    return re.sub(r"\s+", " ", value)


def message(value: str) -> str:
    """A finding's message: its `quoted` parts as code spans, the rest escaped text.

    Messages quote XML in backticks; with an odd number of backticks nothing is taken as code.
    """
    parts = value.split("`")
    if len(parts) % 2 == 0:
        return text(value).strip()
    out = [text(part) if i % 2 == 0 else (code(part) if part.strip() else text(f"`{part}`"))
           for i, part in enumerate(parts)]
    return "".join(out).strip()


def code(value: str, *, cell: bool = False) -> str:
    """A code span that holds any text: fenced with more backticks than it contains.

    In a table ``cell`` a pipe must be escaped even inside the span (GitHub removes the
    backslash there); elsewhere the backslash would show.
    """
    value = " ".join(value.split())
    if cell:
        value = value.replace("|", "\\|")
    longest = max((len(m) for m in re.findall(r"`+", value)), default=0)
    fence = "`" * (longest + 1)
    pad = " " if value.startswith("`") or value.endswith("`") else ""
    return f"{fence}{pad}{value}{pad}{fence}"


def plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def count(fmu: FmuReport, severity: Severity) -> int:
    """Findings of one severity that a baseline did not accept."""
    return sum(1 for f in fmu.findings if f.severity == severity and not is_baselined(f))


def accepted(fmu: FmuReport) -> int:
    return sum(1 for f in fmu.findings if is_baselined(f))


def verdict(fmu: FmuReport) -> str:
    return "fail" if count(fmu, Severity.ERROR) else "pass"


def _draft(fmu: FmuReport, *, cell: bool = False) -> str:
    if not fmu.draft:
        return "no manifest"
    return f"{text(DRAFT_LABELS.get(fmu.draft, fmu.draft))} ({code(fmu.draft, cell=cell)})"


def _table(report: Report) -> list[str]:
    """One row per FMU; a 'baselined' column only when a baseline accepted something."""
    baseline = any(accepted(f) for f in report.fmus)
    extra = (" baselined |", "---:|") if baseline else ("", "")
    rows = [f"| FMU | verdict | errors | warnings | info |{extra[0]} draft |",
            f"|---|---|---:|---:|---:|{extra[1]}---|"]
    for fmu in report.fmus:
        cells = [code(fmu.path, cell=True), verdict(fmu),
                 *(str(count(fmu, s)) for s in _HEADINGS)]
        if baseline:
            cells.append(str(accepted(fmu)))
        cells.append(_draft(fmu, cell=True))
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def _totals(report: Report) -> str:
    failed = sum(1 for f in report.fmus if verdict(f) == "fail")
    n = len(report.fmus)
    counts = [sum(count(f, s) for f in report.fmus) for s in _HEADINGS]
    base = sum(accepted(f) for f in report.fmus)
    return (f"{plural(n, 'FMU')} checked: {n - failed} passed, {failed} failed; "
            f"{plural(counts[0], 'error')}, {plural(counts[1], 'warning')}, {counts[2]} info"
            + (f"; {base} more accepted by the baseline." if base else "."))


def _finding(f: Finding, catalogue: Catalogue | None) -> str:
    where = inner_location(f)
    known = catalogue is None or catalogue.get(f.code) is not None
    link = (f"[{f.code}]({rule_url(f.code, f.name, docs_url=RULES_DOC_URL)})" if known
            else f.code)  # a rule our docs do not have yet gets no dead link
    mark = " (accepted by the baseline)" if is_baselined(f) else ""
    line = f"- **{link}** {code(f.name)}{mark}: {message(f.message)}"
    if where:
        line += f" — {code(where)}"
    if f.location.path:
        line += f" at {code(f.location.path)}"
    return line


def _details(fmu: FmuReport, catalogue: Catalogue | None) -> tuple[list[str], list[str]]:
    """The FMU's heading block, and one line per finding (in severity order)."""
    unchecked = ", binary not checked" if fmu.binary_not_checked else ""
    head = [f"### {code(fmu.path)}: {verdict(fmu)}{unchecked}", ""]
    facts = [f"draft: {_draft(fmu)}"]
    info = dict(fmu.info)
    if isinstance(info.get("model_name"), str):
        facts.append(f"model {code(info['model_name'])}")
    facts.append(f"{plural(len(fmu.rules_run), 'rule')} run, {len(fmu.rules_skipped)} skipped")
    head += ["; ".join(facts) + ".", ""]
    if fmu.binary_not_checked:
        head += [f"**Binary not checked:** {text(fmu.binary_not_checked)}.", ""]
    if fmu.rules_not_run:
        head += [f"**Not run ({len(fmu.rules_not_run)}):**", ""]
        head += [f"- {code(c)}: {text(r)}" for c, r in fmu.rules_not_run[:20]]
        head += [f"- … {len(fmu.rules_not_run) - 20} more in the JSON report"
                 ] if len(fmu.rules_not_run) > 20 else []
        head.append("")
    if not fmu.findings:
        head += ["No findings.", ""]
    lines: list[str] = []
    for severity in _HEADINGS:
        group = [f for f in fmu.findings if f.severity == severity]
        if group:
            lines += [f"#### {_HEADINGS[severity]} ({len(group)})", ""]
            lines += [_finding(f, catalogue) for f in group]
            lines.append("")
    return head, lines


def _skipped(fmu: FmuReport) -> list[str]:
    """Skipped rules, one line per reason."""
    if not fmu.rules_skipped:
        return []
    by_reason: dict[str, list[str]] = {}
    for rule, reason in fmu.rules_skipped:
        by_reason.setdefault(reason, []).append(rule)
    items = [f"- {text(reason)}: {', '.join(code(c) for c in codes)}"
             for reason, codes in by_reason.items()]
    return [f"<details><summary>Skipped rules ({len(fmu.rules_skipped)})</summary>", "",
            *items, "", "</details>", ""]


def render(report: Report, catalogue: Catalogue | None = None, *, run: RunInfo | None = None,
           budget: int = BUDGET, **_: Any) -> str:
    out = ["## lsdae: fmi-ls-dae conformance", "", *_table(report), "", _totals(report), ""]
    if report.interrupted:
        out += [f"**Interrupted:** {plural(len(report.not_checked), 'FMU')} not checked: "
                + ", ".join(code(p) for p in report.not_checked[:20]), ""]
    size = sum(len(line.encode()) + 1 for line in out)
    left_out = 0
    for fmu in report.fmus:
        head, lines = _details(fmu, catalogue)
        block = head + lines + _skipped(fmu)
        cost = sum(len(line.encode()) + 1 for line in block)
        if size + cost <= budget:
            out += block
            size += cost
            continue
        # Over budget: keep the FMU's heading, then as many findings as still fit.
        out += head
        size += sum(len(line.encode()) + 1 for line in head)
        for line in lines:
            if not line.startswith("- "):
                continue
            if size + len(line.encode()) + 1 > budget:
                left_out += 1
                continue
            out.append(line)
            size += len(line.encode()) + 1
        out.append("")
    if left_out:
        out += [f"**{plural(left_out, 'finding')} left out** to keep this summary under GitHub's "
                "1 MiB limit; the JSON report has them all.", ""]
    footer = f"lsdae {text(report.tool_version)}"
    if run is not None and run.timestamp:
        footer += f", {text(run.timestamp)}"
    out.append(f"<sub>{footer}</sub>")
    return "\n".join(out) + "\n"
