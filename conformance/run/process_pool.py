"""Run one job per path in a pool of spawned processes; survive a worker that dies.

The pool is :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn`` start method (a
forked child would inherit the parent's loaded libraries and threads; spawn behaves the same on
Linux, macOS and Windows). A worker that dies (killed, out of memory, a crash in a native
library) breaks the whole pool; the jobs that had not finished are then run again one at a time,
each in a fresh process, and a job whose worker dies again is handed to ``crashed``. Ctrl-C
kills the running workers at once and re-raises.

Only ``lsdae check -j N`` imports this module, so that a sequential run never loads
multiprocessing.
"""
from __future__ import annotations

import logging
import multiprocessing
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Protocol, Sequence

log = logging.getLogger(__name__)

#: path -> (a picklable function, its arguments): the job a worker process runs for that path.
Job = Callable[[str], "tuple[Callable[..., Any], tuple[Any, ...]]"]
#: (path, message) -> the result that stands for a job that failed or whose worker died.
Crashed = Callable[[str, str], Any]


class Progress(Protocol):
    def start(self, item: str) -> None: ...
    def finish(self, item: str) -> None: ...


def run_pooled(paths: Sequence[str], job: Job, jobs: int, progress: Progress,
               results: dict[int, Any], crashed: Crashed) -> None:
    """Run ``job(path)`` for every path in ``min(jobs, len(paths))`` processes.

    ``results[i]`` is set as each path finishes (so an interrupted run keeps what finished).
    """
    broken: list[int] = []
    workers = min(jobs, len(paths))
    progress.start(f"{len(paths)} FMUs in {workers} processes")
    with _pool(workers) as pool:
        futures: dict[Future, int] = {}
        for i, path in enumerate(paths):
            function, arguments = job(path)
            futures[pool.submit(function, *arguments)] = i
        try:
            for future in as_completed(futures):
                i = futures[future]
                outcome = _outcome(future, paths[i], crashed)
                if outcome is None:
                    broken.append(i)
                    continue
                results[i] = outcome
                progress.finish(paths[i])
        except BaseException:  # Ctrl-C: start nothing more, stop the running checks now
            _kill_workers(pool)  # first: shutdown forgets the processes
            # Wait for the pool's manager thread, which sees its workers dead at once: left
            # running, it may close its wake-up pipe while the interpreter's exit hook writes
            # to it ("Exception ignored ... Bad file descriptor" on stderr, CPython 3.11).
            pool.shutdown(wait=True, cancel_futures=True)
            raise
    for i in sorted(broken):  # the pool died: find out which job killed it
        log.info("re-checking %s in a fresh process after a worker died", paths[i])
        progress.start(paths[i])
        function, arguments = job(paths[i])
        with _pool(1) as alone:
            outcome = _outcome(alone.submit(function, *arguments), paths[i], crashed)
        results[i] = outcome if outcome is not None else crashed(
            paths[i], "the process checking this FMU died (killed, out of memory, or a crash "
                      "in a native library); run without -j to see more")
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


def _outcome(future: Future, path: str, crashed: Crashed) -> Any:
    """The worker's result, ``crashed(...)`` for an exception, or None when the pool broke."""
    try:
        return future.result()
    except BrokenProcessPool:
        return None
    except Exception as exc:
        return crashed(path, f"lsdae failed while checking this FMU: {type(exc).__name__}: "
                             f"{exc}")
