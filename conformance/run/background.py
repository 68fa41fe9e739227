"""Run one piece of work in a thread while the caller does another.

libxml2 releases the GIL while it validates a document against an XSD, so the schema stage of a
large modelDescription.xml runs on a second core while Python reads the same (unchanged) tree
into the model. The result, or the exception, is handed back by :meth:`Background.result`, so the
caller sees the same values in the same order as if it had run the work first.
"""
from __future__ import annotations

import threading
from typing import Callable, Generic, TypeVar

T = TypeVar("T")


class Background(Generic[T]):
    """``work()`` running in a daemon thread (an interrupted run does not wait for it)."""

    def __init__(self, work: Callable[[], T]):
        self._work = work
        self._value: T | None = None
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="lsdae-background", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self._value = self._work()
        except BaseException as exc:  # handed to the caller by result()
            self._error = exc

    def result(self) -> T:
        """Wait for the work; its value, or its exception raised here."""
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]
