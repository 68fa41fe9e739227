"""Baselines: accept today's findings, fail only on new ones.

A baseline file lists the findings of one run by a key that survives edits elsewhere in the FMU:
the FMU (its path relative to the baseline file), the rule code, and a stable identity, which is
the finding's ``subject`` (usually a variable name), else its XPath-like ``location.path``, else
its message. Line numbers are deliberately not part of the key: adding a variable above a known
fault must not turn it into a "new" finding.

Keys are counted, not just collected: a baseline that accepts two findings with one key does not
accept a third.

Applying a baseline never changes what is shown, only what fails: baselined findings are kept in
the report and marked with ``evidence["baselined"] = True``; :class:`BaselineResult` also holds a
filtered report of the new findings, from which the exit code is computed.
"""
from __future__ import annotations

import json
import os
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .findings import Finding, FmuReport, Report, evidence

BASELINE_VERSION = 1
MARK = "baselined"

Key = tuple[str, str, str]  # (fmu, code, identity)


class BaselineError(Exception):
    """The baseline file cannot be read or is not a baseline."""


def identity(finding: Finding) -> str:
    """The stable identity of a finding within its FMU and rule (never its line)."""
    return finding.subject or finding.location.path or finding.message


def fmu_key(path: str, anchor: Path) -> str:
    """The FMU's path relative to the baseline file's folder, with forward slashes.

    Relative to the baseline rather than to the working directory, so a baseline committed to a
    repository matches whichever folder the checker is started from.
    """
    p = Path(path)
    try:
        rel = os.path.relpath(p.resolve(), anchor.resolve())
    except ValueError:  # another drive on Windows
        rel = str(p.resolve())
    return rel.replace(os.sep, "/")


def finding_key(fmu: FmuReport, finding: Finding, anchor: Path) -> Key:
    return (fmu_key(fmu.path, anchor), finding.code, identity(finding))


@dataclass(frozen=True)
class Baseline:
    """Accepted findings, counted by key."""

    counts: Counter[Key]
    anchor: Path  # the folder FMU paths are relative to

    @classmethod
    def from_report(cls, report: Report, anchor: Path) -> Baseline:
        counts: Counter[Key] = Counter()
        for fmu in report.fmus:
            for f in fmu.findings:
                counts[finding_key(fmu, f, anchor)] += 1
        return cls(counts, anchor)

    def to_json(self, report: Report | None = None) -> str:
        """The file's text; ``report``, when given, adds each finding's message for readers."""
        messages: dict[Key, str] = {}
        if report is not None:
            for fmu in report.fmus:
                for f in fmu.findings:
                    messages.setdefault(finding_key(fmu, f, self.anchor), f.message)
        entries = []
        for key in sorted(self.counts):
            entry: dict[str, Any] = {"fmu": key[0], "code": key[1], "identity": key[2],
                                     "count": self.counts[key]}
            if key in messages:
                entry["message"] = messages[key]
            entries.append(entry)
        doc = {"tool": "lsdae", "baseline_version": BASELINE_VERSION, "findings": entries}
        return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"


def load(path: Path) -> Baseline:
    """Read a baseline file written by :func:`write`."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BaselineError(f"cannot read baseline {path}: {exc}") from None
    if not isinstance(doc, dict) or doc.get("baseline_version") != BASELINE_VERSION:
        raise BaselineError(f"{path} is not an lsdae baseline (version {BASELINE_VERSION})")
    counts: Counter[Key] = Counter()
    for entry in doc.get("findings", ()):
        try:
            key = (str(entry["fmu"]), str(entry["code"]), str(entry["identity"]))
            counts[key] += int(entry.get("count", 1))
        except (KeyError, TypeError, ValueError):
            raise BaselineError(f"{path}: malformed entry {entry!r}") from None
    return Baseline(counts, Path(path).resolve().parent)


def write(report: Report, path: Path) -> Baseline:
    """Accept every finding of ``report``: write them to ``path`` and return the baseline."""
    path = Path(path)
    baseline = Baseline.from_report(report, path.resolve().parent)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(baseline.to_json(report), encoding="utf-8")
    except OSError as exc:
        raise BaselineError(f"cannot write baseline {path}: {exc}") from None
    return baseline


@dataclass(frozen=True)
class BaselineResult:
    """A report with baselined findings marked, and the report of new findings only."""

    marked: Report     # every finding; baselined ones carry evidence["baselined"] = True
    new: Report        # only the findings not in the baseline: the exit code looks at this
    baselined: int     # findings accepted by the baseline
    stale: int         # baseline entries that no longer occur (fixed since)

    def summary(self) -> dict[str, int]:
        new = sum(len(f.findings) for f in self.new.fmus)
        return {"baselined": self.baselined, "new": new, "stale": self.stale}


def apply(report: Report, baseline: Baseline, *, file: str | None = None) -> BaselineResult:
    """Split ``report`` into accepted and new findings (order within each FMU kept)."""
    left = Counter(baseline.counts)
    marked_fmus, new_fmus = [], []
    accepted = 0
    for fmu in report.fmus:
        marked, new = [], []
        for f in fmu.findings:
            key = finding_key(fmu, f, baseline.anchor)
            if left[key] > 0:
                left[key] -= 1
                accepted += 1
                marked.append(replace(f, evidence=f.evidence + evidence({MARK: True})))
            else:
                marked.append(f)
                new.append(f)
        marked_fmus.append(replace(fmu, findings=tuple(marked)))
        new_fmus.append(replace(fmu, findings=tuple(new)))
    stale = sum(n for n in left.values() if n > 0)
    result = BaselineResult(replace(report, fmus=tuple(marked_fmus)),
                            replace(report, fmus=tuple(new_fmus)), accepted, stale)
    note = {"file": file, **result.summary()} if file else result.summary()
    return replace(result, marked=replace(result.marked,
                                          options=report.options + evidence(baseline=note)))


def is_baselined(finding: Finding) -> bool:
    return bool(finding.evidence_dict().get(MARK))
