"""Apply the fixers one at a time, each kept only when the re-check proves it.

After each fixer the candidate is written to a private temporary place and re-checked (the
caller passes ``recheck``: this package sits below the engine). A change is kept when the
findings it claimed are gone, every rule that ran still runs (a finding may not vanish because
the file it is about can no longer be read), and the re-check has no finding the original did
not have;
otherwise it is refused with the reason, and the next fixer starts from the last good state.
"""
from __future__ import annotations

import tempfile
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from ..intake.archive.base import TOO_LARGE, UNREADABLE, UNSAFE_PATH
from ..report.findings import Finding, FmuReport
from .archive import Package, PackageError
from .change import Change, NoFix
from .edits import EditConflict, apply_edits, by_file
from .fixers import FIXERS

#: Archive findings after which nothing is rewritten: the input is not trusted enough to copy.
UNSAFE = (UNSAFE_PATH, TOO_LARGE, UNREADABLE)

#: The "fixer" named by a refusal that stops every fix.
ALL = "all"

Key = tuple[str, str | None, str | None]


def key(finding: Finding) -> Key:
    """What identifies a finding across a fix (lines move when text is inserted)."""
    return (finding.code, finding.location.file, finding.subject)


def keys(findings: Iterable[Finding]) -> Counter[Key]:
    return Counter(key(f) for f in findings)


@dataclass(frozen=True)
class Outcome:
    package: Package
    applied: tuple[Change, ...]
    refused: tuple[tuple[str, str], ...]    # (fixer or "all", why it was not applied)
    report: FmuReport                       # the static re-check of the result
    original: FmuReport                     # the static check of the input


def fix(path: Path, package: Package, original: FmuReport,
        recheck: Callable[[Path], FmuReport], fixers: Mapping[str, tuple] = FIXERS) -> Outcome:
    """Run every fixer on ``package`` whose rules have findings in ``original``."""
    unsafe = [f for f in original.findings if f.name in UNSAFE]
    if unsafe:
        why = f"{unsafe[0].name}: the archive is not rewritten while check finds it unsafe"
        return Outcome(package, (), ((ALL, why),),
                       original, original)
    baseline = keys(original.findings)
    current, applied, refused = original, [], []
    for name, (codes, fixer) in fixers.items():
        findings = [f for f in current.findings if f.code in codes]
        if not findings:
            continue
        try:
            change = fixer(package, findings)
            if change is None:
                continue
            candidate = _apply(package, change)
        except (NoFix, EditConflict, PackageError, ValueError) as exc:
            refused.append((name, str(exc)))
            continue
        with tempfile.TemporaryDirectory(prefix="lsdae-fix-") as tmp:
            out = Path(tmp) / (path.name or "fmu")
            candidate.write(out)
            report = recheck(out)
        new = keys(report.findings) - baseline
        still = set(keys(change.fixes)) & set(keys(report.findings))
        stopped = sorted(set(current.rules_run) - set(report.rules_run))
        if stopped:   # a finding can vanish because its rule no longer runs: not a fix
            refused.append((name, f"rules would no longer run ({', '.join(stopped[:3])})"))
        elif new:
            first = next(iter(new))
            refused.append((name, f"it would add a finding ({first[0]} on {first[2] or first[1]})"))
        elif still:
            first = next(iter(still))
            refused.append((name, f"{first[0]} would still fire after it"))
        else:
            package, current = candidate, report
            applied.append(change)
    return Outcome(package, tuple(applied), tuple(refused), current, original)


def _apply(package: Package, change: Change) -> Package:
    files = {}
    for file, edits in by_file(change.edits).items():
        data = package.read(file)
        if data is None:
            raise PackageError(f"{file} cannot be read")
        files[file] = apply_edits(data, edits)
    return package.with_files(files, change.drop)
