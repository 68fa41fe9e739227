"""conformance.run.process_pool on Ctrl-C: the running workers are killed and the pool is wound down
before the interrupt goes on, so that nothing of it is left to race the interpreter's exit."""
from __future__ import annotations

import os
import select
import threading
import time
from concurrent.futures.process import _ExecutorManagerThread

import pytest

from conformance.run.process_pool import run_pooled


class _InterruptAfterFirst:
    """A progress display on which the user presses Ctrl-C once the first result is in."""

    def start(self, item: str) -> None:
        pass

    def finish(self, item: str) -> None:
        raise KeyboardInterrupt


def test_ctrl_c_leaves_no_pool_thread_running():
    results: dict[int, object] = {}
    # picklable jobs with a result (None stands for a broken pool): one quick, two that block
    jobs = {"quick": (os.getpid, ()), "slow": (select.select, ([], [], [], 60.0)),
            "later": (select.select, ([], [], [], 60.0))}
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run_pooled(list(jobs), jobs.__getitem__, 2, _InterruptAfterFirst(), results,
                   lambda path, message: None)
    assert time.monotonic() - started < 30, "the slow workers were waited for, not killed"
    assert list(results) == [0]
    left = [t for t in threading.enumerate() if isinstance(t, _ExecutorManagerThread)]
    assert not left, "the pool's manager thread outlives the interrupt"


class _Recorded:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def start(self, item: str) -> None:
        self.events.append(("start", item))

    def finish(self, item: str) -> None:
        self.events.append(("finish", item))


def test_a_job_whose_worker_dies_twice_is_handed_to_crashed_and_the_others_finish():
    """The pool breaks; the jobs that had not finished run again, each alone; one whose
    worker dies again gets ``crashed``'s result, with the message a user reads."""
    results: dict[int, object] = {}
    progress = _Recorded()
    jobs = {"ok": (os.getpid, ()), "dies": (os._exit, (70,))}
    run_pooled(list(jobs), jobs.__getitem__, 2, progress, results,
               lambda path, message: (path, message))
    assert sorted(results) == [0, 1] and isinstance(results[0], int)
    assert results[1] == ("dies", "the process checking this FMU died (killed, out of memory, "
                                  "or a crash in a native library); run without -j to see more")
    assert progress.events[0] == ("start", "2 FMUs in 2 processes")
    assert progress.events[-2:] == [("start", "dies"), ("finish", "dies")]
