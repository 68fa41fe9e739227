"""GitHub Actions workflow commands: findings as annotations on the run and on the files.

``::error file=F,line=L,title=CODE name::message`` (``::warning``, ``::notice`` for info). GitHub
shows at most 10 annotations of each kind per step (and 50 per job); the findings beyond that are
printed as plain lines in a collapsed log group, and a last notice says how many there are and
where the full report is. Data is escaped as GitHub's runner expects (``%``, CR, LF), properties
also ``:`` and ``,``, so a hostile variable name can neither break a command nor start one.

The annotated file is the FMU as the repository holds it (see ``sarif.annotated_file``): the
``.fmu`` archive, or the XML file with its line when the FMU is an unpacked folder. Findings a
baseline accepted are listed in their own log group, never annotated.
"""
from __future__ import annotations

import os
from typing import Any, Mapping

from ..report.catalogue import Catalogue
from ..report.findings import Finding, FmuReport, Report, RunInfo, Severity
from .markdown import plural
from .sarif import annotated_file, inner_location, is_baselined

#: Annotations GitHub shows per step for each of error, warning and notice.
PER_STEP_LIMIT = 10
COMMAND = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "notice"}
_KINDS = ("error", "warning", "notice")


def escape_data(text: str) -> str:
    """Escape a command's message (what follows the second ``::``)."""
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def escape_property(text: str) -> str:
    """Escape a property value (``file=``, ``title=``, ...)."""
    return escape_data(text).replace(":", "%3A").replace(",", "%2C")


def command(kind: str, message: str, **properties: object) -> str:
    """One workflow command line; properties that are None are left out, order is kept."""
    props = ",".join(f"{k}={escape_property(str(v))}" for k, v in properties.items()
                     if v is not None)
    return f"::{kind}{' ' + props if props else ''}::{escape_data(message)}"


def _annotation(fmu: FmuReport, f: Finding, root: str | None) -> str:
    path, _, lines_apply = annotated_file(fmu, f, root=root)
    message = f.message
    where = inner_location(f)
    line = col = None
    if lines_apply:
        line, col = f.location.line, f.location.column
    elif where:
        message = f"{message} (in {where})"
    return command(COMMAND[f.severity], message, file=path, line=line, col=col,
                   title=f"{f.code} {f.name}")


def _plain(fmu: FmuReport, f: Finding) -> str:
    """A log line that cannot be mistaken for a command: no line breaks, never '::' first."""
    where = fmu.path + (f"!{inner_location(f)}" if inner_location(f) else "")
    text = f"{f.severity}[{f.code} {f.name}]: {f.message} --> {where}"
    return text.replace("\r", "\\r").replace("\n", "\\n")


def _run_url(environ: Mapping[str, str]) -> str | None:
    server, repo, run_id = (environ.get(k) for k in
                            ("GITHUB_SERVER_URL", "GITHUB_REPOSITORY", "GITHUB_RUN_ID"))
    if server and repo and run_id:
        return f"{server}/{repo}/actions/runs/{run_id}"
    return None


def _caps(totals: dict[str, int]) -> dict[str, int]:
    """How many of each kind to annotate; one notice slot is kept for the pointer if needed."""
    caps = dict.fromkeys(_KINDS, PER_STEP_LIMIT)
    if any(n > PER_STEP_LIMIT for n in totals.values()):
        caps["notice"] = PER_STEP_LIMIT - 1
    return caps


def _pointer(totals: dict[str, int], hidden: int, fmus: int, url: str | None) -> str:
    counts = (f"{plural(totals['error'], 'error')}, {plural(totals['warning'], 'warning')}, "
              f"{totals['notice']} info in {plural(fmus, 'FMU')}")
    where = (f"the full report: {url}" if url else
             "the full report: run lsdae with --format json:FILE or --format markdown:FILE")
    return command("notice", f"lsdae found {counts}; GitHub shows {PER_STEP_LIMIT} "
                             f"annotations of each kind per step, so {hidden} are only in the "
                             f"log group above. See {where}", title="lsdae: more findings")


def render(report: Report, catalogue: Catalogue | None = None, *, run: RunInfo | None = None,
           root: str | None = None, report_url: str | None = None,
           environ: Mapping[str, str] | None = None, **_: Any) -> str:
    """``report_url`` names the full report; by default the workflow run's page (whose job
    summary the lsdae Action fills), read from the ``GITHUB_*`` variables in ``environ``."""
    env = os.environ if environ is None else environ
    # Findings a baseline accepted are not annotated: they fail nothing and would drown the new.
    accepted = [_plain(fmu, f) for fmu in report.fmus for f in fmu.findings if is_baselined(f)]
    totals = dict.fromkeys(_KINDS, 0)
    for f in report.all_findings():
        if not is_baselined(f):
            totals[COMMAND[f.severity]] += 1
    caps = _caps(totals)
    shown = dict.fromkeys(_KINDS, 0)
    lines: list[str] = []
    hidden: list[str] = []
    # Errors first: past 50 annotations per job GitHub drops the later ones.
    ordered = sorted(((fmu, f) for fmu in report.fmus for f in fmu.findings
                      if not is_baselined(f)), key=lambda item: -item[1].severity)
    for fmu, f in ordered:
        kind = COMMAND[f.severity]
        if shown[kind] < caps[kind]:
            shown[kind] += 1
            lines.append(_annotation(fmu, f, root))
        else:
            hidden.append(_plain(fmu, f))
    for fmu in report.fmus:
        if fmu.binary_not_checked:
            lines.append(command("notice", f"{fmu.path}: binary not checked: "
                                           f"{fmu.binary_not_checked}",
                                 title="lsdae: binary not checked"))
    if accepted:
        title = f"lsdae: {plural(len(accepted), 'finding')} accepted by the baseline"
        lines += [f"::group::{escape_data(title)}", *accepted, "::endgroup::"]
    if hidden:
        title = f"lsdae: {plural(len(hidden), 'more finding')} (not annotated)"
        lines.append(f"::group::{escape_data(title)}")
        lines.extend(hidden)
        lines.append("::endgroup::")
        lines.append(_pointer(totals, len(hidden), len(report.fmus),
                              report_url or _run_url(env)))
    else:
        lines.append(f"lsdae: checked {plural(len(report.fmus), 'FMU')}: "
                     f"{plural(totals['error'], 'error')}, "
                     f"{plural(totals['warning'], 'warning')}, {totals['notice']} info"
                     + (f"; {len(accepted)} accepted by the baseline" if accepted else ""))
    return "\n".join(lines) + "\n"
