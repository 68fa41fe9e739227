"""The wire between the supervisor (parent) and the worker (child).

The parent hands the child a pickled :class:`Job` (parent to child only). The child answers with
one JSON line per event on its private channel, never pickle: it runs foreign code. What the
events are is up to the job's entry point; the supervisor knows only that each is a JSON object.
Violations travel as :func:`violation_json` and come back with :func:`violation_from_json`.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any

from ..report.findings import Location, Violation

MEMORY_EXIT = 86           # the child's exit status after a MemoryError in Python


@dataclass
class Job:
    """What the supervisor hands the worker (pickled: parent to child only).

    The child imports ``entry`` ("package.module:function") after it has limited its memory and
    calls it with the job and a ``send(event: dict)`` function; ``payload`` is the entry's own.
    """

    directory: str                 # where binaries/ and resources/ were extracted
    call_file: str                 # the shared CallRecord
    entry: str
    payload: Any
    blocked: list[str] = field(default_factory=list)  # FMI functions that hung earlier


def json_default(value: Any) -> Any:
    """JSON default for numpy scalars and arrays in evidence."""
    np = sys.modules.get("numpy")  # a numpy value comes only from a child that loaded numpy
    if np is not None and isinstance(value, np.ndarray):
        return value.tolist()
    if np is not None and isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    return str(value)


def violation_json(v: Any) -> dict[str, Any]:
    loc = v.location
    return {"message": v.message, "location": [loc.file, loc.line, loc.column, loc.path],
            "evidence": [[k, val] for k, val in v.evidence], "subject": v.subject,
            "rule": v.rule, "part": v.part, "cause": v.cause}


def _tuples(value: Any) -> Any:
    if isinstance(value, list):
        return tuple(_tuples(v) for v in value)
    return value


def violation_from_json(data: dict[str, Any]) -> Any:
    """The inverse of :func:`violation_json` (lists become tuples, as in evidence)."""
    file, line, column, path = (list(data.get("location") or []) + [None] * 4)[:4]
    return Violation(str(data.get("message", "")), Location(file, line, column, path),
                     _tuples(data.get("evidence") or []), data.get("subject"), data.get("rule"),
                     data.get("part"), _tuples(data.get("cause")))
