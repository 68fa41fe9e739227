"""JUnit XML for CI test views (Jenkins, GitLab, Azure DevOps, ...): one test case per rule.

Each FMU is a ``<testsuite>``; each rule that applied to it (the rules run, plus the archive, XML
and schema pseudo-rules that fired) is a ``<testcase>`` named ``CODE name`` with the FMU as its
class. A rule with an error-level finding fails (``<failure>``); a crashed, hung or
memory-hungry binary and a failure of lsdae itself are ``<error>``; warnings and info leave the
case passing and are written to its ``<system-out>``, which Jenkins and GitLab show beside it,
as are errors a baseline accepted.
Rules that did not apply (no manifest, no binary, ``--no-probes``, another draft) are
``<skipped>`` with the reason.

The attributes are those the strict Ant schema, Jenkins and GitLab require; our own XSD in
``tests/reporters/schemas/junit.xsd`` describes the result. Only ``time`` and ``timestamp``
(from :class:`~conformance.report.findings.RunInfo`) change between two runs on the same input.
"""
from __future__ import annotations

import posixpath
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any

from ..report.catalogue import Catalogue
from ..model.drafts.names import DRAFT_LABELS
from ..report.findings import Finding, FmuReport, Report, RunInfo, Severity
from .markdown import plural
from .sarif import is_baselined

#: Rules whose error-level findings mean the check could not run, not that the FMU is wrong.
CRASH_NAMES = frozenset({"binary-crashed", "binary-timed-out", "binary-memory-limit",
                         "internal-error"})
_NO_TIMESTAMP = "1970-01-01T00:00:00"
# Characters XML 1.0 cannot carry, not even as character references.
_NOT_XML = re.compile("[^\t\n\r\u0020-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_text(text: str) -> str:
    """Text that XML 1.0 can hold: forbidden characters are spelled out as ``\\xNN``."""
    return _NOT_XML.sub(lambda m: f"\\x{ord(m.group()):02x}", text)


@dataclass(frozen=True)
class _Case:
    code: str
    name: str
    findings: tuple[Finding, ...] = ()
    skipped: str | None = None

    @property
    def errors(self) -> tuple[Finding, ...]:
        """The findings that fail the case: error level and not accepted by a baseline."""
        return tuple(f for f in self.findings
                     if f.severity is Severity.ERROR and not is_baselined(f))

    @property
    def outcome(self) -> str:
        """'skipped', 'error', 'failure' or 'passed'."""
        if self.skipped is not None:
            return "skipped"
        errors = self.errors
        if not errors:
            return "passed"
        return "error" if any(f.name in CRASH_NAMES for f in errors) else "failure"


def cases(fmu: FmuReport, catalogue: Catalogue | None = None) -> list[_Case]:
    """The test cases of one FMU in code order: applied rules, then skipped ones among them."""
    by_code: dict[str, list[Finding]] = {}
    for finding in fmu.findings:
        by_code.setdefault(finding.code, []).append(finding)
    applied = set(fmu.rules_run) | set(by_code)
    reasons: dict[str, list[str]] = {}
    failed = set(fmu.rules_not_run)
    for code, reason in fmu.rules_skipped:
        if code not in applied:
            shown = f"not run: {reason}" if (code, reason) in failed else reason
            reasons.setdefault(code, []).append(shown)
    out = []
    for code in sorted(applied | set(reasons)):
        findings = tuple(by_code.get(code, ()))
        rule = catalogue.get(code) if catalogue is not None else None
        name = findings[0].name if findings else (rule.name if rule else "")
        skipped = "; ".join(reasons[code]) if code in reasons else None
        out.append(_Case(code, name, findings, skipped))
    return out


def _timestamp(run: RunInfo | None) -> str:
    """ISO 8601 in UTC without an offset: the strict Ant schema allows no zone."""
    if run is None or not run.timestamp:
        return _NO_TIMESTAMP
    try:
        moment = datetime.fromisoformat(run.timestamp.replace("Z", "+00:00"))
    except ValueError:
        return _NO_TIMESTAMP
    if moment.tzinfo is not None:
        moment = moment.astimezone(timezone.utc).replace(tzinfo=None)
    return moment.replace(microsecond=0).isoformat()


def _seconds(value: float) -> str:
    return f"{value:.3f}"


def _classnames(report: Report) -> dict[int, str]:
    """The FMU's file name without ``.fmu``; its whole path when two FMUs share a name."""
    stems = [posixpath.basename(_posix(f.path).rstrip("/")) for f in report.fmus]
    stems = [s[:-4] if s.lower().endswith(".fmu") else s for s in stems]
    out = {}
    for i, (fmu, stem) in enumerate(zip(report.fmus, stems, strict=True)):
        if stems.count(stem) > 1:
            stem = _posix(fmu.path).strip("/")
            stem = stem[:-4] if stem.lower().endswith(".fmu") else stem
        out[i] = stem or f"fmu{i}"
    return out


def _posix(path: str) -> str:
    return path.replace("\\", "/")


def _package(path: str) -> str:
    parent = posixpath.dirname(_posix(path).rstrip("/"))
    return parent or "."


def finding_text(fmu: FmuReport, f: Finding) -> str:
    """A finding as plain text: headline, where, the element path and the source line."""
    mark = " (accepted by the baseline)" if is_baselined(f) else ""
    lines = [f"{f.severity}[{f.code} {f.name}]{mark}: {f.message}"]
    loc = f.location
    where = fmu.path + (f"!{loc.file}" if loc.file else "") + (
        f":{loc.line}" if loc.file and loc.line else "")
    lines.append(f"  --> {where}")
    if loc.path:
        lines.append(f"  at {loc.path}")
    if loc.snippet is not None and loc.line:
        lines.append(f"  {loc.line} | {loc.snippet.strip()}")
    return "\n".join(lines)


def _headline(findings: tuple[Finding, ...]) -> str:
    first = findings[0].message
    return first if len(findings) == 1 else f"{len(findings)} findings; first: {first}"


def _testcase(parent: ET.Element, fmu: FmuReport, case: _Case, classname: str) -> None:
    # Per-rule times are not measured; the suite carries the FMU's duration.
    element = ET.SubElement(parent, "testcase", name=f"{case.code} {case.name}".strip(),
                            classname=classname, file=fmu.path, time=_seconds(0.0))
    outcome = case.outcome
    if outcome == "skipped":
        ET.SubElement(element, "skipped", message=case.skipped or "")
    elif outcome in ("failure", "error"):
        errors = case.errors
        detail = ET.SubElement(element, outcome, message=_headline(errors),
                               type=case.name or case.code)
        detail.text = "\n\n".join(finding_text(fmu, f) for f in errors)
    failing = set(map(id, case.errors))
    rest = [f for f in case.findings if id(f) not in failing]
    if rest:
        ET.SubElement(element, "system-out").text = "\n\n".join(
            finding_text(fmu, f) for f in rest)


def _properties(report: Report, fmu: FmuReport) -> list[tuple[str, str]]:
    props = [("lsdae.version", report.tool_version), ("draft", fmu.draft or "none")]
    if fmu.draft:
        props.append(("draft.label", DRAFT_LABELS.get(fmu.draft, fmu.draft)))
    for key, value in fmu.info:
        if isinstance(value, (str, int, float, bool)):
            props.append((f"info.{key}", str(value)))
    return props


def _counts(all_cases: list[_Case]) -> dict[str, int]:
    outcomes = [c.outcome for c in all_cases]
    return {"tests": len(outcomes), "failures": outcomes.count("failure"),
            "errors": outcomes.count("error"), "skipped": outcomes.count("skipped")}


def _attrs(counts: dict[str, int]) -> dict[str, str]:
    return {k: str(v) for k, v in counts.items()}


def build(report: Report, catalogue: Catalogue | None = None, *,
          run: RunInfo | None = None) -> ET.Element:
    """The ``<testsuites>`` element for a report."""
    timestamp = _timestamp(run)
    hostname = (run.hostname if run and run.hostname else "localhost")
    classnames = _classnames(report)
    root = ET.Element("testsuites", name="lsdae")
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    total_time = 0.0
    for i, fmu in enumerate(report.fmus):
        fmu_cases = cases(fmu, catalogue)
        counts = _counts(fmu_cases)
        seconds = run.duration(fmu.path) if run else 0.0
        total_time += seconds
        for key in totals:
            totals[key] += counts[key]
        attrib = {"name": fmu.path, "package": _package(fmu.path), "id": str(i),
                  "hostname": hostname, "timestamp": timestamp, **_attrs(counts),
                  "time": _seconds(seconds)}
        suite = ET.SubElement(root, "testsuite", attrib)
        properties = ET.SubElement(suite, "properties")
        for name, value in _properties(report, fmu):
            ET.SubElement(properties, "property", name=name, value=value)
        for case in fmu_cases:
            _testcase(suite, fmu, case, classnames[i])
        accepted = sum(1 for f in fmu.findings if is_baselined(f))
        ET.SubElement(suite, "system-out").text = (
            f"{fmu.path}: draft {fmu.draft or 'none'}; "
            f"{plural(fmu.count(Severity.ERROR), 'error')}, "
            f"{plural(fmu.count(Severity.WARNING), 'warning')}, {fmu.count(Severity.INFO)} info"
            + (f" ({accepted} accepted by the baseline)" if accepted else "")
            + f"; {plural(len(fmu.rules_run), 'rule')} run, {len(fmu.rules_skipped)} skipped")
        ET.SubElement(suite, "system-err")
    root.attrib.update(_attrs(totals))
    root.set("time", _seconds(total_time))
    root.set("timestamp", timestamp)
    return root


def _sanitise(element: ET.Element) -> None:
    for node in element.iter():
        if node.text:
            node.text = xml_text(node.text)
        for key, value in node.attrib.items():
            node.attrib[key] = xml_text(value)


def render(report: Report, catalogue: Catalogue | None = None, *, run: RunInfo | None = None,
           **_: Any) -> str:
    root = build(report, catalogue, run=run)
    _sanitise(root)
    ET.indent(root, space="  ")
    body = ET.tostring(root, encoding="unicode")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + body + "\n"
