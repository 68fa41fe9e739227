"""Background work hands back its value or its exception, as if it had run in the caller."""
from __future__ import annotations

import threading

import pytest

from conformance.run.background import Background


def test_the_value_comes_back_from_another_thread():
    seen = []
    work = Background(lambda: seen.append(threading.current_thread().name) or 42)
    assert work.result() == 42
    assert seen == ["lsdae-background"]


def test_the_exception_is_raised_in_the_caller():
    def fail():
        raise ValueError("boom")

    with pytest.raises(ValueError, match="boom"):
        Background(fail).result()


def test_the_work_runs_beside_the_caller():
    started, release = threading.Event(), threading.Event()

    def wait():
        started.set()
        return release.wait(timeout=10)

    work = Background(wait)
    assert started.wait(timeout=10)  # running while the caller goes on
    release.set()
    assert work.result() is True
