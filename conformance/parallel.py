"""Check many FMUs, one after another or in parallel processes, with a progress display.

``-j N`` runs :func:`conformance.engine.check_fmu` in a :class:`ProcessPoolExecutor` of N
spawned processes (spawn, not fork: a forked child would inherit the parent's loaded libraries
and threads; spawn behaves the same on Linux, macOS and Windows). Reports come back in input
order, so ``-j 2`` writes the same bytes as ``-j 1``.

A worker that dies (killed, out of memory, a crash in a native library) breaks the whole pool;
the FMUs that had not finished are then re-checked one at a time, each in a fresh process, and
an FMU whose worker dies again gets an ``internal-error`` finding. No FMU's report is ever lost.
"""
from __future__ import annotations

import logging
import multiprocessing
import time
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

from .catalogue import Catalogue, default_catalogue
from .engine import EngineOptions, check_fmu, check_paths
from .engine_options import RuleSelection
from .findings import Finding, FmuReport, Location, Report, evidence
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
            _pooled(paths, options, catalogue, jobs, progress, results, worker)
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


def _pooled(paths: Sequence[str], options: EngineOptions, catalogue: Catalogue, jobs: int,
            progress: Progress, results: dict[int, tuple[FmuReport, float]],
            worker: Worker) -> None:
    shipped = _shipped(catalogue)
    broken: list[int] = []
    workers = min(jobs, len(paths))
    progress.start(f"{len(paths)} FMUs in {workers} processes")
    with _pool(workers) as pool:
        futures: dict[Future, int] = {pool.submit(worker, p, options, shipped): i
                                      for i, p in enumerate(paths)}
        try:
            for future in as_completed(futures):
                i = futures[future]
                outcome = _outcome(future, paths[i], options, catalogue)
                if outcome is None:
                    broken.append(i)
                    continue
                results[i] = outcome
                progress.finish(paths[i])
        except BaseException:  # Ctrl-C: start nothing more, stop the running checks now
            _kill_workers(pool)  # first: shutdown forgets the processes
            pool.shutdown(wait=False, cancel_futures=True)
            raise
    for i in sorted(broken):  # the pool died: find out which FMU killed it
        log.info("re-checking %s in a fresh process after a worker died", paths[i])
        progress.start(paths[i])
        with _pool(1) as alone:
            outcome = _outcome(alone.submit(worker, paths[i], options, shipped), paths[i],
                               options, catalogue)
        results[i] = outcome or (crashed(
            paths[i], "the process checking this FMU died (killed, out of memory, or a crash "
                      "in a native library); run without -j to see more", options,
            catalogue), 0.0)
        progress.finish(paths[i])


def _kill_workers(pool: ProcessPoolExecutor) -> None:
    """Kill the pool's processes (a check may run probes for a minute); their own probe workers
    die with them (they are killed when their parent dies)."""
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            process.kill()
        except (OSError, AttributeError):
            pass


def _pool(workers: int) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=workers,
                               mp_context=multiprocessing.get_context("spawn"))


def _outcome(future: Future, path: str, options: EngineOptions, catalogue: Catalogue
             ) -> tuple[FmuReport, float] | None:
    """The worker's result, a crash report for an exception, or None when the pool broke."""
    try:
        return future.result()
    except BrokenProcessPool:
        return None
    except Exception as exc:
        return crashed(path, f"lsdae failed while checking this FMU: {type(exc).__name__}: "
                             f"{exc}", options, catalogue), 0.0


def crashed(path: str, message: str, options: EngineOptions, catalogue: Catalogue
            ) -> FmuReport:
    """The report of an FMU whose check never completed: one ``internal-error`` finding.

    Shown even when the rule is deselected: hiding it would pass an FMU nobody checked.
    """
    rule = catalogue["internal-error"]
    severity = RuleSelection(catalogue, options).severity[rule.code]
    finding = Finding(rule.code, rule.name, severity, message, Location(),
                      evidence(stage="worker"))
    return FmuReport(path=path, draft=None, findings=(finding,))
