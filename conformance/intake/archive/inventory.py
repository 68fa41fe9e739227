"""What listing an FMU builds up, ZIP archive or folder alike: the inventory and its result.

:class:`Inventory` collects the usable members, the excluded entries and the violations about
them while :mod:`conformance.intake.archive.zipped` or :mod:`conformance.intake.archive.folder`
walks the entries;
:meth:`Inventory.finish` adds the checks that need the whole listing (names that differ only in
letter case, a name that is both a file and a folder, the total size).
"""
from __future__ import annotations

import zipfile
from dataclasses import dataclass
from typing import Any

from conformance.intake.archive.base import (
    DUPLICATE,
    TOO_LARGE,
    ArchiveLimits,
    Member,
    archive_violation,
    normalise_name,
    show_name,
)
from conformance.report.findings import Location, Violation, evidence


@dataclass(slots=True)
class ScanResult:
    """What :func:`~conformance.intake.archive.scan.scan` found; ``kind`` is None when nothing is
    usable.

    For a ZIP archive ``zf`` is the open archive, which the caller must close (an
    :class:`~conformance.intake.archive.source.FmuSource` takes it over); for a folder ``root`` is
    its real path.
    """

    kind: str | None
    violations: list[Violation]
    members: dict[str, Member]
    excluded: dict[str, str]
    zf: zipfile.ZipFile | None = None
    root: str | None = None


def unusable(*violations: Violation) -> ScanResult:
    return ScanResult(None, list(violations), {}, {})


class Inventory:
    """The usable members found so far, the excluded ones, and the violations about them."""

    def __init__(self, limits: ArchiveLimits):
        self.limits = limits
        self.members: dict[str, Member] = {}
        self.raw_names: dict[str, str] = {}
        self.dirs: set[str] = set()
        self.excluded: dict[str, str] = {}
        self.violations: list[Violation] = []
        self.total = 0

    def report(self, rule: str, message: str, raw: str, *, part: str | None = None,
               **ev: Any) -> None:
        self.violations.append(_member_violation(rule, message, raw, part=part, **ev))

    def exclude(self, rule: str, message: str, raw: str, *, part: str | None = None,
                **ev: Any) -> None:
        self.report(rule, message, raw, part=part, **ev)
        self.excluded[show_name(raw)] = rule

    def add(self, raw: str, size: int, ref: Any, *, executable: bool) -> None:
        if size > self.limits.max_member:
            self.exclude(TOO_LARGE, f"{{subject}} is {size} bytes uncompressed, more than the "
                         f"per-member limit of {self.limits.max_member} bytes", raw,
                         size=size, limit=self.limits.max_member)
            return
        name = normalise_name(raw)
        if name in self.members:
            first = self.raw_names[name]
            how = ("occurs more than once" if first == raw else
                   f"is the same name as '{show_name(first)}' once normalised")
            self.report(DUPLICATE, f"{{subject}} {how}; importers disagree on which copy they "
                        "use (lsdae reads the last one)", raw)
        self.members[name] = Member(name, size, ref, executable)
        self.raw_names[name] = raw

    def finish(self) -> None:
        by_fold: dict[str, list[str]] = {}
        for name in self.members:
            by_fold.setdefault(name.casefold(), []).append(name)
        for names in by_fold.values():
            if len(names) > 1:
                others = ", ".join(f"'{show_name(n)}'" for n in sorted(names)[1:])
                self.report(DUPLICATE, f"{{subject}} and {others} differ only in letter case; "
                            "they overwrite each other when extracted on Windows or macOS",
                            sorted(names)[0], names=[show_name(n) for n in sorted(names)])
        parents = set(self.dirs)
        for name in self.members:
            parts = name.split("/")
            parents.update("/".join(parts[:i]) for i in range(1, len(parts)))
        for name in sorted(self.members):
            if name in parents:
                self.report(DUPLICATE, "{subject} is both a file and a folder; it cannot be "
                            "extracted", name)
        if self.total > self.limits.max_total_uncompressed:
            self.violations.append(archive_violation(
                TOO_LARGE, f"the entries add up to {self.total} bytes uncompressed, more than the "
                f"limit of {self.limits.max_total_uncompressed} bytes",
                total=self.total, limit=self.limits.max_total_uncompressed))


def too_many(count: int, limits: ArchiveLimits) -> Violation:
    return archive_violation(TOO_LARGE, f"the FMU has {count} or more entries, more than the "
                             f"limit of {limits.max_members}; it is not checked further",
                             entries=count, limit=limits.max_members)


def _member_violation(rule: str, message: str, name: str, *, part: str | None = None,
                      **ev: Any) -> Violation:
    """A violation about one entry; its (escaped) name is the subject, so the engine can group."""
    return Violation(message, Location(), evidence(ev), subject=show_name(name), rule=rule,
                     part=part)
