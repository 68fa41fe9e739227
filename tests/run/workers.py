"""Worker functions for the -j tests; module-level so spawned processes can import them."""
from __future__ import annotations

import os

from conformance.run.parallel import check_one


def crash_on_marked(path, options, catalogue):
    """Die like a segfaulting native library when the FMU's name says so."""
    if "crash" in os.path.basename(path):
        os._exit(70)
    return check_one(path, options, catalogue)


def raise_on_marked(path, options, catalogue):
    if "raise" in os.path.basename(path):
        raise RuntimeError("worker failed")
    return check_one(path, options, catalogue)


def spawn_child(path, options, catalogue):
    """A worker that starts a process of its own, as the probe runner does."""
    import multiprocessing

    child = multiprocessing.get_context("spawn").Process(target=os.getpid)
    child.start()
    child.join()
    assert child.exitcode == 0
    return check_one(path, options, catalogue)


def describe(path, options, catalogue):
    """No check at all: a report that says which catalogue the worker was given (None: the
    default), and an exception for an FMU whose name says so."""
    from conformance.report.findings import FmuReport, evidence

    if "raise" in os.path.basename(path):
        raise RuntimeError("worker failed")
    given = "default" if catalogue is None else f"{len(catalogue)} rules"
    return FmuReport(path, None, (), info=evidence(catalogue=given, seed=options.seed)), 0.5
