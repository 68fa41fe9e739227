"""Check many FMUs, one after another or in parallel processes, with a progress display.

``-j N`` runs :func:`conformance.run.engine.check_fmu` in N spawned processes
(:mod:`conformance.run.process_pool`, imported only then). Reports come back in input order, so
``-j 2`` writes the same bytes as ``-j 1``. A worker that dies (killed, out of memory, a crash in
a native library) breaks the whole pool; the FMUs that had not finished are then re-checked one at
a time, each in a fresh process, and an FMU whose worker dies again gets an ``internal-error``
finding. No FMU's report is ever lost.
"""
from __future__ import annotations

import logging
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

from ..report.catalogue import Catalogue, default_catalogue
from .collector import limit_said
from .engine import EngineOptions, check_fmu, check_paths
from .options import RuleSelection
from ..report.findings import Finding, FmuReport, Location, Report, evidence
from .progress import NoProgress, Progress

log = logging.getLogger(__name__)

# (path, options, catalogue or None for the default) -> (report, seconds)
Worker = Callable[[str, EngineOptions, "Catalogue | None"], "tuple[FmuReport, float]"]


def check_one(path: str, options: EngineOptions, catalogue: Catalogue | None
              ) -> tuple[FmuReport, float]:
    """Check one FMU and time it; the function each worker process runs."""
    start = time.perf_counter()
    report = check_fmu(Path(path), options=options, catalogue=catalogue or default_catalogue(),
                       display_path=path)
    return report, time.perf_counter() - start


def check_all(paths: Sequence[str], *, options: EngineOptions, catalogue: Catalogue,
              jobs: int = 1, progress: Progress | None = None,
              durations: dict[str, float] | None = None,
              worker: Worker = check_one) -> Report:
    """Check every path and return one report, FMUs in input order.

    Raises ValueError for a bad rule selection before any FMU is read.
    """
    skeleton = check_paths([], options=options, catalogue=catalogue)  # validates the selection
    progress = progress or NoProgress(len(paths))
    results: dict[int, tuple[FmuReport, float]] = {}
    try:
        if jobs > 1 and len(paths) > 1:
            from .process_pool import run_pooled  # multiprocessing: only for -j N
            shipped = _shipped(catalogue)
            run_pooled(paths, lambda path: (worker, (path, options, shipped)), jobs, progress,
                       results, lambda path, message: (crashed(path, message, options,
                                                                catalogue), 0.0))
        else:
            for i, path in enumerate(paths):
                progress.start(path)
                results[i] = _guarded(worker, path, options, catalogue)
                progress.finish(path)
    except KeyboardInterrupt:  # Ctrl-C: keep what finished, mark the rest as not checked
        log.info("interrupted after %d of %d FMUs", len(results), len(paths))
    finally:
        progress.close()
    done = sorted(results)
    if durations is not None:
        durations.update((paths[i], results[i][1]) for i in done)
    return replace(skeleton, fmus=tuple(results[i][0] for i in done),
                   not_checked=tuple(p for i, p in enumerate(paths) if i not in results))


def _shipped(catalogue: Catalogue) -> Catalogue | None:
    """What to send to a worker: nothing for the default catalogue (it loads its own)."""
    return None if catalogue is default_catalogue() else catalogue


def _guarded(worker: Worker, path: str, options: EngineOptions, catalogue: Catalogue
             ) -> tuple[FmuReport, float]:
    try:
        return worker(path, options, _shipped(catalogue))
    except Exception as exc:  # check_fmu reports its own failures; this is a last resort
        log.debug("checking %s failed", path, exc_info=True)
        return crashed(path, f"lsdae failed while checking this FMU: {type(exc).__name__}: "
                             f"{exc}", options, catalogue), 0.0


def crashed(path: str, message: str, options: EngineOptions, catalogue: Catalogue
            ) -> FmuReport:
    """The report of an FMU whose check never completed: one ``internal-error`` finding.

    Shown even when the rule is deselected: hiding it would pass an FMU nobody checked.
    """
    rule = catalogue["internal-error"]
    severity = RuleSelection(catalogue, options).severity[rule.code]
    finding = Finding(rule.code, rule.name, severity, limit_said(rule, None, message),
                      Location(), evidence(stage="worker"))
    return FmuReport(path=path, draft=None, findings=(finding,))
