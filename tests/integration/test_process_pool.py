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
