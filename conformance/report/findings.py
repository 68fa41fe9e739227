"""Immutable result types: what a check yields and what the report holds.

A check yields :class:`Violation` objects (message, location, evidence). It never decides
severity or rule code: the engine looks both up in the catalogue and builds a :class:`Finding`.
Every type here is frozen, so reporters can rely on a report never changing under them.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

# Evidence is stored as a tuple of (key, value) pairs so findings stay hashable.
Evidence = tuple[tuple[str, Any], ...]


def evidence(mapping: Mapping[str, Any] | None = None, **items: Any) -> Evidence:
    """Build an evidence tuple from a mapping and/or keyword items, in insertion order."""
    pairs: dict[str, Any] = dict(mapping or {})
    pairs.update(items)
    return tuple((k, _freeze(v)) for k, v in pairs.items())


def thaw(value: Any) -> Any:
    """The inverse of :func:`evidence`'s freezing: pairs with string keys become dicts,
    other tuples lists (for reporters that write JSON-like structures)."""
    if isinstance(value, tuple):
        if value and all(isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], str)
                         for v in value):
            return {k: thaw(v) for k, v in value}
        return [thaw(v) for v in value]
    return value


def _freeze(value: Any) -> Any:
    if isinstance(value, list):
        return tuple(_freeze(v) for v in value)
    if isinstance(value, dict):
        return tuple((k, _freeze(v)) for k, v in value.items())
    return value


class Severity(enum.IntEnum):
    """Finding severity; the order is the order of importance."""

    INFO = 0
    WARNING = 1
    ERROR = 2

    @classmethod
    def parse(cls, text: str) -> Severity:
        try:
            return cls[text.strip().upper()]
        except KeyError:
            raise ValueError(f"unknown severity {text!r} (use info, warning or error)") from None

    def __str__(self) -> str:
        return self.name.lower()


@dataclass(frozen=True, slots=True)
class Location:
    """Where a finding points: a file inside the FMU, a line, and an XPath-like path."""

    file: str | None = None
    line: int | None = None
    column: int | None = None
    path: str | None = None
    snippet: str | None = None  # the source line, filled in by the engine for reporters

    def sort_key(self) -> tuple[str, int, int]:
        return (self.file or "", self.line or 0, self.column or 0)


@dataclass(frozen=True, slots=True)
class Violation:
    """What a check yields: a plain statement of one problem.

    ``message`` may contain ``{subject}``; the engine fills it with the quoted subject, or, when
    many violations share the message, with a count and the first few subjects.
    ``subject`` is the stable identity of what is wrong (usually a variable name); baselines key on it.
    ``rule`` is set only by loaders and stages that emit several pseudo-rules (archive, XML,
    schema); ordinary checks leave it empty and the engine knows which rule it ran. ``part``
    names the sub-check of the rule whose basis (and so severity) differs from the rule's own
    (``[[rule.parts]]`` in the catalogue); None is the rule's own verdict. ``cause`` names the
    defect itself, where several probes can see one defect (the same derivative entry and
    deviation in several functions, modes or states): one key, or several (an entry names its
    unknown and its known). Violations that share a key are one finding, the others listed in
    its evidence (``conformance.run.causes``).
    """

    message: str
    location: Location = field(default_factory=Location)
    evidence: Evidence = ()
    subject: str | None = None
    rule: str | None = None
    part: str | None = None
    cause: str | tuple[str, ...] | None = None

    @property
    def text(self) -> str:
        """The message as one finding shows it: ``{subject}`` filled with the quoted subject."""
        return self.message.replace("{subject}", f"'{self.subject}'" if self.subject else "")


@dataclass(frozen=True, slots=True)
class Finding:
    """A violation with its rule code, name and effective severity attached by the engine."""

    code: str
    name: str
    severity: Severity
    message: str
    location: Location = field(default_factory=Location)
    evidence: Evidence = ()
    subject: str | None = None
    count: int = 1
    part: str | None = None     # the sub-check whose basis gave the severity (catalogue parts)

    def sort_key(self) -> tuple[str, int, int, str, str]:
        f, line, col = self.location.sort_key()
        return (f, line, col, self.code, self.message)

    def evidence_dict(self) -> dict[str, Any]:
        return dict(self.evidence)


@dataclass(frozen=True, slots=True)
class FmuReport:
    """The result for one FMU: where it was, which draft it follows, and its findings."""

    path: str
    draft: str | None
    findings: tuple[Finding, ...]
    rules_run: tuple[str, ...] = ()
    rules_skipped: tuple[tuple[str, str], ...] = ()  # (code, reason)
    info: Evidence = ()
    # the part of rules_skipped that should have run but could not (an earlier failure, a
    # missing capability, a budget); the rest does not apply (draft, no DAE layer, --no-probes)
    rules_not_run: tuple[tuple[str, str], ...] = ()

    def count(self, severity: Severity) -> int:
        return sum(1 for f in self.findings if f.severity == severity)

    @property
    def worst(self) -> Severity | None:
        return max((f.severity for f in self.findings), default=None)

    @property
    def not_checked(self) -> str | None:
        """Why the FMU as a whole was not checked (an FMI 2.0 FMU), or None."""
        text = dict(self.info).get("not_checked")
        return text if isinstance(text, str) else None

    @property
    def binary_not_checked(self) -> str | None:
        """Why the probes did not run on this FMU's binary (``info["probes"]``), or None when
        they ran: every reporter says it, so that a clean result is never taken for a verified
        binary."""
        text = dict(self.info).get("probes")
        if isinstance(text, str) and text.startswith("not run"):
            return text.removeprefix("not run").lstrip(": ") or "not run"
        return None


@dataclass(frozen=True, slots=True)
class Report:
    """The whole run: tool version and one :class:`FmuReport` per FMU checked."""

    tool_version: str
    fmus: tuple[FmuReport, ...]
    options: Evidence = ()
    not_checked: tuple[str, ...] = ()   # paths left unchecked when the run was interrupted
    # only in a report of ``lsdae check --shard I/N``: which share of the inputs it holds and
    # what ``lsdae merge`` needs to put the shards back together (conformance/run/fleet.py)
    shard: Evidence = ()

    @property
    def interrupted(self) -> bool:
        return bool(self.not_checked)

    def all_findings(self) -> Iterable[Finding]:
        for fmu in self.fmus:
            yield from fmu.findings

    def has_at_least(self, severity: Severity) -> bool:
        return any(f.severity >= severity for f in self.all_findings())


@dataclass(frozen=True, slots=True)
class RunInfo:
    """Facts about one run that are not part of the findings: when, where, how long.

    Passed to reporters next to the report (JUnit and HTML show them), never stored in it, so
    the report itself, and the JSON written from it, is the same for the same input.
    """

    timestamp: str | None = None               # ISO 8601, when the run started
    hostname: str | None = None
    durations: tuple[tuple[str, float], ...] = ()  # (FMU path, seconds)

    def duration(self, path: str) -> float:
        return dict(self.durations).get(path, 0.0)
