"""A stand-in for the probe stage (``conformance.probes.machinery.stage:run_job``) that reaches a
limit on purpose, for the tests of lsdae's own limits (test_own_limits.py).

The driver starts it as it would the real stage (the test points ``driver.ENTRY`` here); it
never loads the binary. ``LSDAE_FAKE_WORKER`` (``BEHAVIOUR:CODE``) says what probe CODE does:

* ``sleep-outside``: computes (sleeps) with no FMI call in progress: the per-probe time limit
  is lsdae's own;
* ``sleep-inside``: the same inside an FMI call (the call record says fmi3DoStep is running):
  the binary's fault;
* ``memory-outside`` / ``memory-inside``: allocates until MemoryError (under the worker's
  address-space limit), outside or inside a recorded FMI call;
* ``short-calls``: makes one short "FMI call" (10 ms, recorded) after another, forever: the
  probe's time is spent in calls, but no call hangs.

The other probes (and CODE in a worker started after one that it stopped) finish at once,
without violations.
"""
from __future__ import annotations

import mmap
import os
import sys
import time
from typing import Any, Callable

from conformance.runtime.callrecord import CallRecord
from conformance.runtime.protocol import MEMORY_EXIT, Job

BEHAVIOUR = "LSDAE_FAKE_WORKER"


def _exhaust_memory() -> None:
    blocks = []
    while True:
        blocks.append(bytearray(64 << 20))


def _short_calls(record: CallRecord) -> None:
    count = 0
    while True:
        count += 1
        record.enter("fmi3GetFloat64", count)
        time.sleep(0.01)
        record.leave()


def run_job(job: Job, send: Callable[[dict[str, Any]], None]) -> int:
    with open(job.call_file, "r+b") as fh:
        record = CallRecord(mmap.mmap(fh.fileno(), CallRecord.SIZE))
    send({"event": "ready", "info": {}, "memory": {}})
    behaviour, _, target = os.environ.get(BEHAVIOUR, "").partition(":")
    for code, _name, _options in job.payload.probes:
        record.set_probe(code)
        send({"event": "start", "code": code})
        if code == target and code not in job.payload.died:
            if behaviour.endswith("-inside"):
                record.enter("fmi3DoStep", 1)
            try:
                if behaviour.startswith("sleep"):
                    time.sleep(600)
                elif behaviour == "short-calls":
                    _short_calls(record)
                else:
                    _exhaust_memory()
            except MemoryError:
                send({"event": "memory", "code": code})
                sys.stderr.flush()
                os._exit(MEMORY_EXIT)
        send({"event": "done", "code": code, "violations": [], "skipped": None, "info": {}})
    send({"event": "end"})
    return 0
