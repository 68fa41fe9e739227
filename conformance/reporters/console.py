"""Console output in the style of compiler diagnostics, coloured only when asked to."""
from __future__ import annotations

from ..report.catalogue import Catalogue
from ..model.drafts.names import DRAFT_LABELS
from ..report.findings import Finding, FmuReport, Report, Severity, thaw

_COLOURS = {Severity.ERROR: "\033[1;31m", Severity.WARNING: "\033[1;33m",
            Severity.INFO: "\033[1;36m"}
_BOLD, _DIM, _RESET = "\033[1m", "\033[2m", "\033[0m"


# Findings of these stages are measurements: their evidence is shown, not only in JSON.
EVIDENCE_STAGES = ("probe", "simulation")
EVIDENCE_ITEMS = 12       # at most this many evidence items per finding
EVIDENCE_WIDTH = 100      # long values are cut here


def render(report: Report, catalogue: Catalogue | None = None, *, color: bool = False,
           **_: object) -> str:
    measured = {r.code for r in catalogue or () if r.stage in EVIDENCE_STAGES}
    names = {r.code: r.name for r in catalogue or ()}
    out: list[str] = []
    for fmu in report.fmus:
        out.extend(_fmu(fmu, color, measured, names))
    errors = sum(f.count(Severity.ERROR) for f in report.fmus)
    warnings = sum(f.count(Severity.WARNING) for f in report.fmus)
    unchecked = sum(1 for f in report.fmus if f.binary_not_checked and not f.not_checked)
    skipped = sum(1 for f in report.fmus if f.not_checked)
    binaries = (f"; the binary of {_plural(unchecked, 'FMU')} was not checked" if unchecked
                else "")
    not_run = sum(len(f.rules_not_run) for f in report.fmus)
    binaries = (f", {_plural(not_run, 'rule')} not run" if not_run else "") + binaries
    if skipped:
        binaries += f"; {_plural(skipped, 'FMU')} not checked (FMI version)"
    out.append(f"checked {len(report.fmus)} FMU{'s' if len(report.fmus) != 1 else ''}: "
               f"{_plural(errors, 'error')}, {_plural(warnings, 'warning')}{binaries}")
    if report.interrupted:
        more = ", …" if len(report.not_checked) > 3 else ""
        out.append(f"interrupted: {_plural(len(report.not_checked), 'FMU')} not checked "
                   f"({', '.join(report.not_checked[:3])}{more})")
    return "\n".join(out) + "\n"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _paint(text: str, code: str, color: bool) -> str:
    return f"{code}{text}{_RESET}" if color else text


def _fmu(fmu: FmuReport, color: bool, measured: set[str], names: dict[str, str]) -> list[str]:
    lines: list[str] = []
    for finding in fmu.findings:
        lines.extend(_finding(fmu, finding, color))
        if finding.code in measured and finding.evidence:
            lines.extend(_evidence(finding, color))
        lines.append("")
    if fmu.draft:
        draft = DRAFT_LABELS.get(fmu.draft, fmu.draft)
    elif dict(fmu.info).get("manifest"):
        draft = f"fmi-ls-dae manifest {dict(fmu.info)['manifest']}"
    else:
        draft = "no fmi-ls-dae manifest"
    summary = (f"{fmu.path}: {draft}; {_plural(fmu.count(Severity.ERROR), 'error')}, "
               f"{_plural(fmu.count(Severity.WARNING), 'warning')}, "
               f"{fmu.count(Severity.INFO)} info")
    if fmu.rules_not_run:
        summary += f", {_plural(len(fmu.rules_not_run), 'rule')} not run"
    if fmu.not_checked:
        summary = f"{fmu.path}: not checked ({fmu.not_checked})"
    lines.extend(_not_run(fmu, names))
    lines.append(_paint(summary, _BOLD, color))
    if fmu.binary_not_checked:
        lines.append(f"  binary not checked: {fmu.binary_not_checked}")
    lines.append("")
    return lines


NOT_RUN_LISTED = 3   # rules named one per line; more with the same reason share a line


def _not_run(fmu: FmuReport, names: dict[str, str]) -> list[str]:
    """One line per rule that could not run, with its reason; rules sharing a reason share a
    line when there are many of them."""
    by_reason: dict[str, list[str]] = {}
    for code, reason in fmu.rules_not_run:
        by_reason.setdefault(reason, []).append(code)
    lines = []
    for reason, codes in by_reason.items():
        if len(codes) <= NOT_RUN_LISTED:
            lines += [f"not run: {c} {names.get(c, '')}".rstrip() + f": {reason}" for c in codes]
        else:
            lines.append(f"not run ({len(codes)} rules: {', '.join(codes)}): {reason}")
    return lines + ([""] if lines else [])


def _finding(fmu: FmuReport, f: Finding, color: bool) -> list[str]:
    head = f"{f.severity}[{f.code} {f.name}]"
    lines = [f"{_paint(head, _COLOURS[f.severity], color)}: {f.message}"]
    loc = f.location
    if loc.file:
        where = f"{fmu.path}!{loc.file}" + (f":{loc.line}" if loc.line else "")
        lines.append(f"  {_paint('-->', _DIM, color)} {where}")
        if loc.snippet is not None and loc.line:
            gutter = " " * len(str(loc.line))
            lines.append(f" {gutter} |")
            lines.append(f" {loc.line} | {loc.snippet.strip()}")
            lines.append(f" {gutter} |")
    else:
        lines.append(f"  {_paint('-->', _DIM, color)} {fmu.path}")
    return lines


def _evidence(f: Finding, color: bool) -> list[str]:
    """The numbers behind a measured finding, one ``key: value`` per line."""
    items = thaw(f.evidence)
    lines = [f"  {_paint('= evidence:', _DIM, color)}"]
    for key, value in list(items.items())[:EVIDENCE_ITEMS]:
        lines.append(f"      {key}: {_short(value)}")
    if len(items) > EVIDENCE_ITEMS:
        lines.append(f"      … {len(items) - EVIDENCE_ITEMS} more in the JSON report")
    return lines


def _short(value: object, nested: bool = False) -> str:
    if isinstance(value, float):
        text = f"{value:.6g}"
    elif isinstance(value, dict):
        text = ", ".join(f"{k}={_short(v, True)}" for k, v in value.items())
        text = f"({text})" if nested else text
    elif isinstance(value, list):
        text = "[" + ", ".join(_short(v, True) for v in value) + "]"
    else:
        text = str(value)
    return text if len(text) <= EVIDENCE_WIDTH else text[:EVIDENCE_WIDTH - 1] + "…"
