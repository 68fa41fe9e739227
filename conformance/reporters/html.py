"""A self-contained HTML page per run: verdict, findings with their source lines, and plots.

Nothing is fetched when the page is viewed: the CSS is inline, plots are data: URIs, there is no
script, and a Content-Security-Policy forbids anything else, so the page reads the same offline,
as a CI artifact, or attached to an e-mail. Apart from the run facts (time, host, durations) the
page is the same for the same report.

Plots (conformance/reporters/html_plots.py) come from the probes' per-FMU ``info``; when no probe
ran, the page says why instead of drawing an empty plot.
"""
from __future__ import annotations

import logging
from html import escape
from typing import Any, Iterable

from ..report.catalogue import Catalogue
from ..model.drafts.names import DRAFT_LABELS
from ..report.findings import Finding, FmuReport, Report, RunInfo, Severity, thaw
from . import html_plots

log = logging.getLogger(__name__)

_CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"
_SEVERITIES = (Severity.ERROR, Severity.WARNING, Severity.INFO)
_MAX_EVIDENCE_TEXT = 400

_CSS = """
:root{--err:#b42318;--warn:#93370d;--info:#175cd3;--ok:#067647;--line:#d0d5dd;--muted:#475467}
*{box-sizing:border-box}
body{font:15px/1.5 system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;
 color:#101828;margin:0;background:#f9fafb}
header.page,main,footer{max-width:1100px;margin:0 auto;padding:0 24px}
header.page{padding-top:24px}
h1{font-size:24px;margin:0 0 8px}h2{font-size:19px;margin:0 0 4px;word-break:break-all}
h3{font-size:16px;margin:20px 0 8px}
.verdict{font-size:18px;font-weight:600;padding:12px 16px;border-radius:8px;margin:12px 0;
 border:1px solid}
.verdict.fail{background:#fef3f2;color:var(--err);border-color:#fecdca}
.verdict.warn{background:#fffaeb;color:var(--warn);border-color:#fedf89}
.verdict.pass{background:#ecfdf3;color:var(--ok);border-color:#abefc6}
table{border-collapse:collapse;background:#fff;width:100%}
th,td{border:1px solid var(--line);padding:4px 8px;text-align:left;vertical-align:top}
th{background:#f2f4f7;font-weight:600}td.num{text-align:right;font-variant-numeric:tabular-nums}
section.fmu{background:#fff;border:1px solid var(--line);border-radius:10px;padding:16px 20px;
 margin:20px 0}
.meta{color:var(--muted);margin:0 0 8px}
.badge{display:inline-block;font-size:12px;font-weight:600;padding:1px 8px;border-radius:10px;
 vertical-align:middle;border:1px solid;white-space:nowrap}
.badge.fail,.badge.error{color:var(--err);border-color:#fecdca;background:#fef3f2}
.badge.warn,.badge.warning{color:var(--warn);border-color:#fedf89;background:#fffaeb}
.badge.info{color:var(--info);border-color:#b2ddff;background:#eff8ff}
.badge.pass{color:var(--ok);border-color:#abefc6;background:#ecfdf3}
.badge.baselined{color:var(--muted);border-color:var(--line);background:#f2f4f7}
article.finding{border-left:4px solid var(--line);padding:6px 12px;margin:10px 0;
 background:#fcfcfd}
article.error{border-left-color:var(--err)}article.warning{border-left-color:#f79009}
article.info{border-left-color:var(--info)}article.baselined{opacity:.72}
.finding .head{font-weight:600}.finding .msg{margin:2px 0}
.where{color:var(--muted);font-size:13px;word-break:break-all}
pre.snippet{background:#101828;color:#f2f4f7;padding:6px 10px;border-radius:6px;overflow-x:auto;
 margin:6px 0;font-size:13px}
pre.snippet .ln{color:#98a2b3;user-select:none;margin-right:12px}
code{font-family:ui-monospace,"DejaVu Sans Mono",Menlo,Consolas,monospace;font-size:13px}
details{margin:4px 0}summary{cursor:pointer;color:var(--muted)}
details table{width:auto;font-size:13px}
figure{margin:8px 0}figure img{max-width:100%;height:auto;border:1px solid var(--line);
 border-radius:6px;background:#fff}figcaption{color:var(--muted);font-size:13px}
.noplot{color:var(--muted);font-style:italic;margin:4px 0}
footer{color:var(--muted);font-size:13px;padding:16px 24px 32px}
"""


def render(report: Report, catalogue: Catalogue | None = None, *, run: RunInfo | None = None,
           **_: object) -> str:
    """The whole page as one string."""
    counts = _counts(f for fmu in report.fmus for f in fmu.findings)
    verdict, css = _verdict(counts)
    title = f"lsdae: {verdict}"
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{escape(title)}</title>", f"<style>{_CSS}</style>", "</head>", "<body>",
        '<header class="page">', "<h1>fmi-ls-dae conformance report</h1>",
        f'<p class="verdict {css}">{escape(verdict)}</p>',
        _overview(report, run), _run_facts(report, run), "</header>", "<main>",
    ]
    for index, fmu in enumerate(report.fmus, 1):
        parts.append(_fmu_section(index, fmu, catalogue))
    footer = (f"<footer>lsdae {escape(report.tool_version)} · self-contained page: nothing is "
              "loaded from the network.</footer>")
    parts += ["</main>", footer, "</body>", "</html>"]
    return "\n".join(parts) + "\n"


def _is_baselined(f: Finding) -> bool:
    return bool(f.evidence_dict().get("baselined"))


def _counts(findings: Iterable[Finding]) -> dict[str, int]:
    counts = {str(s): 0 for s in _SEVERITIES} | {"baselined": 0}
    for f in findings:
        counts["baselined" if _is_baselined(f) else str(f.severity)] += 1
    return counts


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _verdict(counts: dict[str, int]) -> tuple[str, str]:
    accepted = f" ({counts['baselined']} more accepted by the baseline)" \
        if counts["baselined"] else ""
    if counts["error"]:
        text = (f"Not conformant: {_plural(counts['error'], 'error')}, "
                f"{_plural(counts['warning'], 'warning')}{accepted}")
        return text, "fail"
    if counts["warning"]:
        return (f"Conformant, with {_plural(counts['warning'], 'warning')}{accepted}", "warn")
    return f"Conformant: no errors or warnings{accepted}", "pass"


def _overview(report: Report, run: RunInfo | None) -> str:
    timed = run is not None and bool(run.durations)
    head = "<tr><th>FMU</th><th>draft</th><th>errors</th><th>warnings</th><th>infos</th>" \
           "<th>baselined</th>" + ("<th>seconds</th>" if timed else "") + "<th>verdict</th></tr>"
    rows = [head]
    for index, fmu in enumerate(report.fmus, 1):
        c = _counts(fmu.findings)
        _, css = _verdict(c)
        label = {"fail": "fails", "warn": "warnings", "pass": "passes"}[css]
        seconds = f'<td class="num">{run.duration(fmu.path):.2f}</td>' if timed and run else ""
        rows.append(
            f'<tr><td><a href="#fmu-{index}">{escape(fmu.path)}</a></td>'
            f"<td>{escape(fmu.draft or '—')}</td>"
            + "".join(f'<td class="num">{c[k]}</td>' for k in ("error", "warning", "info",
                                                               "baselined"))
            + f'{seconds}<td><span class="badge {css}">{label}</span></td></tr>')
    return f"<table class=\"overview\">{''.join(rows)}</table>"


def _run_facts(report: Report, run: RunInfo | None) -> str:
    facts: list[tuple[str, str]] = [("lsdae", report.tool_version)]
    if run is not None:
        facts += [(k, v) for k, v in (("started", run.timestamp), ("host", run.hostname)) if v]
    facts += [(k, _text(v)) for k, v in report.options if v not in ((), None, "")]
    rows = "".join(f"<tr><th>{escape(k)}</th><td>{escape(str(v))}</td></tr>" for k, v in facts)
    return f"<details><summary>Run and options</summary><table>{rows}</table></details>"


def _fmu_section(index: int, fmu: FmuReport, catalogue: Catalogue | None) -> str:
    c = _counts(fmu.findings)
    verdict, css = _verdict(c)
    info = thaw(fmu.info)
    info = info if isinstance(info, dict) else {}
    draft = DRAFT_LABELS.get(fmu.draft, fmu.draft) if fmu.draft else "no fmi-ls-dae manifest"
    meta = [f"draft: {draft}"]
    meta += [f"{k.replace('_', ' ')}: {info[k]}" for k in ("model_name", "fmi_version",
                                                            "variables") if k in info]
    out = [f'<section class="fmu" id="fmu-{index}">',
           f'<h2>{escape(fmu.path)} <span class="badge {css}">{escape(verdict)}</span></h2>',
           f'<p class="meta">{escape(" · ".join(meta))}</p>']
    if fmu.binary_not_checked:
        out.append(f'<p class="meta"><strong>Binary not checked:</strong> '
                   f'{escape(fmu.binary_not_checked)}</p>')
    if fmu.rules_not_run:
        items = "".join(f"<li><code>{escape(c)}</code>: {escape(r)}</li>"
                        for c, r in fmu.rules_not_run)
        out.append(f'<p class="meta"><strong>Not run ({len(fmu.rules_not_run)}):</strong></p>'
                   f"<ul>{items}</ul>")
    out.append(f"<h3>Findings ({len(fmu.findings)})</h3>")
    if fmu.findings:
        out += [_finding(f, catalogue) for f in fmu.findings]
    else:
        out.append('<p class="noplot">No findings.</p>')
    out += _plots(fmu, info)
    if isinstance(info.get("simulation"), dict) and info["simulation"].get("times"):
        out += ["<h3>Simulation</h3>",
                _plot(lambda: html_plots.trajectory(info["simulation"]))]
    out.append(_rules_run(fmu))
    out.append("</section>")
    return "\n".join(out)


def _finding(f: Finding, catalogue: Catalogue | None) -> str:
    sev = str(f.severity)
    baselined = _is_baselined(f)
    badges = f'<span class="badge {sev}">{sev}</span>'
    if baselined:
        badges += ' <span class="badge baselined">baselined</span>'
    loc = f.location
    where = [p for p in (loc.file and (loc.file + (f":{loc.line}" if loc.line else "")),
                         loc.path) if p]
    head = f'<div class="head">{badges} <code>{escape(f.code)}</code> {escape(f.name)}</div>'
    out = [f'<article class="finding {sev}{" baselined" if baselined else ""}">', head,
           f'<p class="msg">{escape(f.message)}</p>']
    if where:
        out.append(f'<div class="where">{escape(" · ".join(where))}</div>')
    if loc.snippet is not None and loc.line:
        out.append(f'<pre class="snippet"><span class="ln">{loc.line}</span>'
                   f"<code>{escape(loc.snippet.strip())}</code></pre>")
    ev = [(k, v) for k, v in f.evidence if k != "baselined"]
    if ev:
        rows = "".join(f"<tr><th>{escape(k)}</th><td><code>{escape(_text(v))}</code></td></tr>"
                       for k, v in ev)
        out.append(f"<details><summary>Evidence</summary><table>{rows}</table></details>")
    rule = catalogue.get(f.code) if catalogue is not None else None
    if rule is not None:
        out.append(f"<details><summary>Rule: {escape(rule.summary)}</summary>"
                   f"<p><b>Basis:</b> {escape(_basis(rule, f.part))}</p>"
                   f"<p><b>Spec:</b> {escape(rule.spec)}</p><p>{escape(rule.rationale)}</p>"
                   f"<p><b>Fix:</b> see <code>lsdae explain {escape(rule.code)}</code></p>"
                   "</details>")
    out.append("</article>")
    return "\n".join(out)


def _plots(fmu: FmuReport, info: dict[str, Any]) -> list[str]:
    jacobian, entries = info.get("jacobian"), info.get("probe_errors")
    has_jacobian = isinstance(jacobian, dict)
    has_errors = isinstance(entries, list) and bool(entries)
    if not has_jacobian and not has_errors:
        return ["<h3>Probe plots</h3>", _no_plot(_no_probe_reason(fmu))]
    none = "No probe data for this plot: the probes that ran recorded none."
    which = "ODE-mode" if has_jacobian and jacobian.get("mode") == "ode" else "DAE"
    return [f"<h3>{which} Jacobian: declared versus observed sparsity</h3>",
            _plot(lambda: html_plots.sparsity(jacobian)) if has_jacobian else _no_plot(none),
            "<h3>Probe errors against tolerance</h3>",
            _plot(lambda: html_plots.probe_errors(entries)) if has_errors else _no_plot(none)]


def _no_probe_reason(fmu: FmuReport) -> str:
    reasons = sorted({r for code, r in fmu.rules_skipped if code.startswith("DAE7")})
    if reasons:
        return f"No probe data: {'; '.join(reasons)}."
    if any(code.startswith("DAE7") for code in fmu.rules_run):
        return "No probe data: the probes that ran recorded none."
    return "No probe data: no dynamic probe ran on this FMU."


def _no_plot(reason: str) -> str:
    return f'<p class="noplot">{escape(reason)}</p>'


def _plot(draw) -> str:
    try:
        plot = draw()
    except ImportError:
        return _no_plot("Plots need matplotlib, which is not installed.")
    except Exception as exc:  # malformed probe data must not cost the whole page
        log.debug("plot failed", exc_info=True)
        return _no_plot(f"The probe data could not be plotted: {type(exc).__name__}: {exc}")
    return (f'<figure><img src="{plot.uri}" alt="{escape(plot.alt)}">'
            f"<figcaption>{escape(plot.caption)}</figcaption></figure>")


def _basis(rule: Any, part: str | None) -> str:
    """What this finding's verdict rests on: its part's basis, else the rule's."""
    basis = rule.part(part)
    return f"{basis.describe()} ({basis.severity})" if basis else "none recorded"


def _rules_run(fmu: FmuReport) -> str:
    run = ", ".join(fmu.rules_run) or "none"
    skipped = "".join(f"<tr><td><code>{escape(c)}</code></td><td>{escape(r)}</td></tr>"
                      for c, r in fmu.rules_skipped)
    table = f"<table><tr><th>rule</th><th>reason</th></tr>{skipped}</table>" if skipped else ""
    return (f"<details><summary>Rules run ({len(fmu.rules_run)}) and skipped "
            f"({len(fmu.rules_skipped)})</summary><p><code>{escape(run)}</code></p>{table}"
            "</details>")


def _text(value: Any) -> str:
    text = str(thaw(value))
    return text if len(text) <= _MAX_EVIDENCE_TEXT else text[:_MAX_EVIDENCE_TEXT] + " …"
