"""``lsdae fix FMU``: repair what the files alone determine, then re-check.

    lsdae fix MODEL.fmu -o FIXED.fmu | --in-place | --diff  [--select R] [--ignore R]

It runs the same check as ``lsdae check``, applies the safe fixers of :mod:`conformance.fixes`
(each kept only when the re-check shows it fixed its findings and added none), re-checks the
result and prints the remaining findings as ``check`` does, then "fixed N findings, M remain".
``--diff`` prints a unified diff of every changed file on stdout (the findings and the summary
go to stderr) and writes nothing. Exit codes: 0 when
nothing at the ``--fail-on`` level remains, 1 otherwise, 2 on usage errors. It sits above the
engine, beside ``check``.
"""
from __future__ import annotations

import argparse
import dataclasses
import difflib
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

from .. import __version__
from .arguments import add_fix_parser as add_parser  # noqa: F401  (the command's grammar)
from ..report.catalogue import default_catalogue
from .check import exit_code
from ..run.engine import check_fmu
from ..run.options import EngineOptions, RuleSelection
from .exit_codes import EXIT_FINDINGS, EXIT_OK, UsageError
from ..report.findings import FmuReport, Report
from ..fixes.apply import ALL, ROUNDS, Outcome, fix, key
from ..fixes.archive import Package
from ..fixes.fixers import UNSAFE_FIXERS
from ..intake.fmu import default_limits
from .precommit import fmu_roots
from ..reporters import console

#: The group threshold of the checks fix runs: no grouping.
UNGROUPED = sys.maxsize


def _split(values: list[str] | None) -> tuple[str, ...]:
    return tuple(v.strip() for value in values or () for v in value.split(",") if v.strip())


def _destination(args: argparse.Namespace, source: Path) -> Path | None:
    """Where to write (None for --diff); usage errors for every ambiguous choice."""
    if args.diff:
        if args.in_place:
            raise UsageError("--diff writes nothing: it does not go with --in-place")
        return None
    if args.output is None:
        if not args.in_place:
            raise UsageError("say where the fixed FMU goes: -o FIXED, --in-place or --diff")
        return source
    dest = Path(args.output)
    if dest.exists() and dest.resolve() == source.resolve():
        if not args.in_place:
            raise UsageError(f"-o {dest} is the input; add --in-place to overwrite it")
        return source
    if dest.is_dir():
        raise UsageError(f"-o {dest} is an existing folder; name a new path")
    if not dest.parent.is_dir():
        raise UsageError(f"-o {dest}: no such folder {dest.parent}")
    return dest


def fix_fmu(source: Path, *, options: EngineOptions | None = None,
            unsafe: bool = False) -> Outcome:
    """The fixes for one FMU (nothing written): the safe ones proven by static re-checks; with
    ``unsafe``, then the fixes from the probes' observations, proven by re-checks with them."""
    # Every violation its own finding, so that a fixer sees the evidence of each, not of the
    # first of a group or of a cause.
    options = dataclasses.replace(options or EngineOptions(), group_threshold=UNGROUPED,
                                  fold=False)
    static = dataclasses.replace(options, probes=False, probes_only=False)
    catalogue = default_catalogue()
    original = check_fmu(source, options=static, catalogue=catalogue)
    package = Package(source, default_limits())
    safe = fix(source, package, original,
               lambda p: check_fmu(p, options=static, catalogue=catalogue))
    if not unsafe or any(name == ALL for name, _ in safe.refused):
        return safe
    dynamic = dataclasses.replace(options, probes=True, probes_only=False)
    with tempfile.TemporaryDirectory(prefix="lsdae-fix-") as tmp:
        current = Path(tmp) / (source.name or "fmu")
        safe.package.write(current)
        observed = check_fmu(current, options=dynamic, catalogue=catalogue)
    more = fix(source, safe.package, observed,
               lambda p: check_fmu(p, options=dynamic, catalogue=catalogue), UNSAFE_FIXERS,
               rounds=ROUNDS)
    seen = Counter(key(f) for f in original.findings)
    probed = tuple(f for f in observed.findings if key(f) not in seen)   # what the probes saw
    return Outcome(more.package, safe.applied + more.applied, safe.refused + more.refused,
                   more.report, dataclasses.replace(original,
                                                    findings=original.findings + probed))


def diff_text(outcome: Outcome) -> str:
    out: list[str] = []
    for name, before, after in outcome.package.diffable():
        out.extend(difflib.unified_diff(
            before.decode("utf-8", "replace").splitlines(keepends=True),
            after.decode("utf-8", "replace").splitlines(keepends=True),
            fromfile=f"a/{name}", tofile=f"b/{name}"))
    for index in sorted(outcome.package.dropped):
        out.append(f"dropped duplicate entry #{index + 1} "
                   f"({outcome.package.entries()[index].filename})\n")
    return "".join(out)


def summary(original: FmuReport, final: FmuReport) -> str:
    gone = Counter(key(f) for f in original.findings) - Counter(key(f) for f in final.findings)
    n = sum(gone.values())
    m = len(final.findings)
    return f"fixed {n} finding{'s' if n != 1 else ''}, {m} remain{'s' if m == 1 else ''}"


def _fix_one(source: Path, dest: Path | None, args: argparse.Namespace, options: EngineOptions,
             catalogue: Any) -> tuple[FmuReport, Outcome, bool]:
    """Fix one FMU, write it (or print its diff), and check what was written; also whether it
    changed (known before writing: in place, the package reads its originals from ``source``)."""
    outcome = fix_fmu(source, options=options, unsafe=args.unsafe_fixes)
    modified = outcome.package.modified
    untouchable = any(fixer == ALL for fixer, _ in outcome.refused)
    with tempfile.TemporaryDirectory(prefix="lsdae-fix-") as tmp:
        target = dest
        if untouchable:
            target = source  # an unsafe archive is neither copied nor rewritten
        elif dest is None:
            target = Path(tmp) / (source.name or "fmu")
            if modified:
                outcome.package.write(target)
            else:
                target = source
            sys.stdout.write(diff_text(outcome))
        elif modified:
            outcome.package.write(dest)
        elif dest != source:
            outcome.package.write(dest)   # an unchanged copy: -o always produces its output
        final = check_fmu(target, options=options, catalogue=catalogue,
                          display_path=str(dest or source))
    return final, outcome, modified


def run(args: argparse.Namespace) -> int:
    if args.pre_commit:
        args.in_place = True
        args.fmu = fmu_roots(args.fmu)   # the FMUs the changed files belong to
        if not args.fmu:
            return EXIT_OK
    sources = [Path(p) for p in args.fmu]
    for source in sources:
        if not source.exists():
            raise UsageError(f"no such FMU: {source}")
    if len(sources) > 1 and args.output:
        raise UsageError("-o takes one FMU; fix several with --in-place or --diff")
    dests = [_destination(args, source) for source in sources]
    options = EngineOptions(select=_split(args.select), ignore=_split(args.ignore),
                            probes=not args.no_probes)
    catalogue = default_catalogue()
    try:
        RuleSelection(catalogue, options)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if args.unsafe_fixes and args.no_probes:
        raise UsageError("--unsafe-fixes needs the probes: it does not go with --no-probes")
    color = args.color == "always" or (args.color == "auto" and sys.stdout.isatty())
    finals: list[FmuReport] = []
    changed = False
    for source, dest in zip(sources, dests):
        final, outcome, modified = _fix_one(source, dest, args, options, catalogue)
        finals.append(final)
        changed = changed or (dest is not None and modified)
        out = sys.stderr if dest is None else sys.stdout   # --diff: stdout is the diff alone
        if final.findings:
            one = Report(tool_version=__version__, fmus=(final,))
            out.write(console.render(one, catalogue, color=color))
        for fixer, why in outcome.refused:
            print(f"not fixed ({fixer}): {why}", file=out)
        for code in sorted({f.code for f in final.findings}):
            rule = catalogue.get(code)
            if rule is not None and rule.fix and rule.fix.startswith("none:"):
                print(f"no fix for {code} {rule.name}: {rule.fix[5:].strip()}", file=out)
        print(summary(outcome.original, final) + (f" ({source})" if len(sources) > 1 else ""),
              file=out)
    code = exit_code(Report(tool_version=__version__, fmus=tuple(finals)), args.fail_on)
    if args.pre_commit and changed:
        return EXIT_FINDINGS   # pre-commit's convention: a hook that changed files fails
    return code
