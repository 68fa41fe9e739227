"""Read a JSON report (the output of :mod:`conformance.reporters.json_report`) back into a Report.

The inverse of the JSON reporter, for ``lsdae merge`` (shard reports) and the result cache
(:mod:`conformance.run.result_cache`): everything the reporters read comes back as it was written.
Fields the JSON reporter derives (``summary``, ``draft_label``, ``fix``) are not read, the
reporters derive them again. Two things the JSON of an ordinary run does not hold are read when
present: a finding's ``snippet`` (its source line) and the top-level ``shard`` section, both
written for shard reports and cache entries.

Evidence is frozen again with :func:`~conformance.report.findings.evidence`, so it compares and
renders as the engine's did. Non-finite numbers, written as the strings ``"nan"``, ``"inf"`` and
``"-inf"`` for strict JSON, come back as floats (a probe's measured error may be NaN; a string
``"nan"`` in evidence reads back as a float, which renders the same).
"""
from __future__ import annotations

import math
from typing import Any

from .findings import Finding, FmuReport, Location, Report, Severity, evidence

#: The version of the JSON report this reader understands (reporters/json_report.py writes it).
SCHEMA_VERSION = 1
_NON_FINITE = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf}


class ReportFormatError(ValueError):
    """The data is not an lsdae JSON report this version can read."""


def read_report(data: Any) -> Report:
    """The :class:`Report` a JSON report (already parsed with :func:`json.loads`) describes."""
    if not isinstance(data, dict) or data.get("tool") != "lsdae":
        raise ReportFormatError("not an lsdae JSON report (no \"tool\": \"lsdae\")")
    if data.get("schema_version") != SCHEMA_VERSION:
        raise ReportFormatError(f"JSON report schema version {data.get('schema_version')!r}; "
                                f"this lsdae reads version {SCHEMA_VERSION}")
    try:
        fmus = tuple(read_fmu(f) for f in _list(data["fmus"], "fmus"))
        interrupted = data.get("interrupted") or {}
        return Report(
            tool_version=_str(data["version"], "version"), fmus=fmus,
            options=evidence(_dict(data.get("options") or {}, "options")),
            not_checked=tuple(_str(p, "not_checked") for p in
                              _list(interrupted.get("not_checked", []), "not_checked")),
            shard=evidence(_restore(_dict(data.get("shard") or {}, "shard"))))
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, ReportFormatError):
            raise
        raise ReportFormatError(f"not an lsdae JSON report: {type(exc).__name__}: {exc}") \
            from None


def read_fmu(data: Any) -> FmuReport:
    """One entry of ``fmus[]``."""
    data = _dict(data, "fmus[]")
    return FmuReport(
        path=_str(data["path"], "path"), draft=data["draft"],
        findings=tuple(read_finding(f) for f in _list(data["findings"], "findings")),
        rules_run=tuple(_str(c, "rules_run") for c in _list(data["rules_run"], "rules_run")),
        rules_skipped=_pairs(data["rules_skipped"], "rules_skipped"),
        info=evidence(_restore(_dict(data.get("info") or {}, "info"))),
        rules_not_run=_pairs(data.get("rules_not_run", []), "rules_not_run"))


def read_finding(data: Any) -> Finding:
    """One entry of ``findings[]``."""
    data = _dict(data, "findings[]")
    location = Location(file=data["file"], line=data["line"], column=data["column"],
                        path=data["path"], snippet=data.get("snippet"))
    ev = data.get("evidence") or {}
    return Finding(
        code=_str(data["code"], "code"), name=_str(data["name"], "name"),
        severity=Severity.parse(_str(data["severity"], "severity")),
        message=_str(data["message"], "message"), location=location,
        evidence=evidence(_restore(_dict(ev, "evidence"))) if ev else (),
        subject=data["subject"], count=int(data["count"]),
        part=_str(data["part"], "part") if data.get("part") is not None else None)


def _restore(value: Any) -> Any:
    """Undo the JSON reporter's strings for non-finite floats, anywhere in a structure."""
    if isinstance(value, dict):
        return {k: _restore(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_restore(v) for v in value]
    if isinstance(value, str) and value in _NON_FINITE:
        return _NON_FINITE[value]
    return value


def _pairs(items: Any, what: str) -> tuple[tuple[str, str], ...]:
    return tuple((_str(i["code"], what), _str(i["reason"], what)) for i in _list(items, what))


def _dict(value: Any, what: str) -> dict:
    if not isinstance(value, dict):
        raise ReportFormatError(f"not an lsdae JSON report: {what} is not an object")
    return value


def _list(value: Any, what: str) -> list:
    if not isinstance(value, list):
        raise ReportFormatError(f"not an lsdae JSON report: {what} is not a list")
    return value


def _str(value: Any, what: str) -> str:
    if not isinstance(value, str):
        raise ReportFormatError(f"not an lsdae JSON report: {what} is not a string")
    return value
