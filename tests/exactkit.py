"""Assert on the exact finding a user sees: code, severity, subject, file, line, evidence.

A test that only asserts "some finding of this code fired" lets a wrong severity, subject, line
or number pass. :func:`assert_exact` names every field a reader acts on and fails on any
difference, showing the findings of that code as they are.

``tests/project/test_exact_findings.py`` requires, for every rule of the catalogue, at least
one exact assertion: an ``[exact]`` table in a rule case's ``fixture.toml``
(``tests/checks/test_fixtures.py`` runs it through :func:`assert_exact`), or a call
``assert_exact(..., code="DAEnnn", ...)`` with the code written as a literal in a test module.
"""
from __future__ import annotations

import math
from typing import Any, Iterable, Mapping

from conformance.report.findings import Finding, FmuReport, Severity

UNSET: Any = object()   # a field the caller does not constrain (only `part` and `message`)


def _findings(where: FmuReport | Iterable[Finding]) -> list[Finding]:
    return list(where.findings) if isinstance(where, FmuReport) else list(where)


def _same(expected: Any, actual: Any, rel: float) -> bool:
    """Equal; floats within ``rel`` (relative) of each other; containers element by element."""
    if isinstance(expected, float) and isinstance(actual, (int, float)) \
            and not isinstance(actual, bool):
        if math.isnan(expected):
            return math.isnan(actual)
        return math.isclose(expected, actual, rel_tol=rel, abs_tol=0.0) or expected == actual
    if isinstance(expected, Mapping) and isinstance(actual, Mapping):
        return expected.keys() == actual.keys() and all(
            _same(expected[k], actual[k], rel) for k in expected)
    if isinstance(expected, (list, tuple)) and isinstance(actual, (list, tuple)):
        return len(expected) == len(actual) and all(
            _same(e, a, rel) for e, a in zip(expected, actual))
    return expected == actual


def evidence_differences(expected: Mapping[str, Any], finding: Finding,
                         rel: float = 1e-9) -> list[str]:
    """The evidence keys whose value differs from the expected one (every expected key must
    be present; keys not named are not compared)."""
    actual = finding.evidence_dict()
    out = []
    for key, value in expected.items():
        if key not in actual:
            out.append(f"{key}: missing")
        elif not _same(value, _plain(actual[key]), rel):
            out.append(f"{key}: expected {value!r}, got {_plain(actual[key])!r}")
    return out


def _plain(value: Any) -> Any:
    """Evidence values are tuples of pairs where a report has a mapping; compare as lists."""
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _describe(f: Finding) -> str:
    return (f"  {f.code} {f.severity.name.lower()} subject={f.subject!r} "
            f"at {f.location.file}:{f.location.line} part={f.part!r}\n"
            f"    message: {f.message}\n    evidence: {dict(f.evidence)!r}")


def assert_exact(where: FmuReport | Iterable[Finding], *, code: str, severity: str,
                 subject: str | None, file: str | None, line: int | None,
                 evidence: Mapping[str, Any], part: str | None = UNSET,
                 message: str = UNSET, rel: float = 1e-9) -> Finding:
    """The one finding of ``code`` whose subject, file and line are these, with this
    severity (``"error"``, ``"warning"`` or ``"info"``), these evidence values (floats within
    ``rel``) and, when given, this part and a message containing ``message``. Returns it.
    Several findings at one place (two attributes of one variable) are told apart by their
    evidence."""
    want = Severity[severity.upper()]
    of_code = [f for f in _findings(where) if f.code == code]
    placed = [f for f in of_code if f.subject == subject and f.location.file == file
              and f.location.line == line]
    shown = "\n".join(_describe(f) for f in of_code) or "  (none)"
    assert placed, (f"{code}: no finding of subject {subject!r} at {file}:{line}; the findings "
                    f"of {code}:\n{shown}")
    problems = []
    for found in placed:
        wrong = [f"evidence {d}" for d in evidence_differences(evidence, found, rel)]
        if found.severity != want:
            wrong.append(f"severity {found.severity.name.lower()}, expected {severity}")
        if part is not UNSET and found.part != part:
            wrong.append(f"part {found.part!r}, expected {part!r}")
        if message is not UNSET and message not in found.message:
            wrong.append(f"message lacks {message!r}")
        problems.append(wrong)
    matching = [f for f, wrong in zip(placed, problems) if not wrong]
    assert len(matching) == 1, (
        f"{code}: {len(matching)} findings at {file}:{line} of subject {subject!r} match "
        f"exactly; differences: {'; '.join(w for ws in problems for w in ws)}\n{shown}")
    return matching[0]
