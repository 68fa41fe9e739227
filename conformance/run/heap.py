"""Give memory the C heap no longer uses back to the system, between the stages of a large check."""
from __future__ import annotations

import sys

#: Variables of a model from which it pays to give its freed tree's memory back.
RELEASE_FROM = 10_000


def release_freed_memory() -> None:
    """Give the pages of the C heap that are free back to the system (glibc's malloc_trim).

    The engine calls it once a large modelDescription tree (934 MiB at 500k variables) has been
    read and freed: glibc keeps its pages, and Python builds the manifest's objects in memory of
    its own, not in those pages, so the peak would otherwise be that tree plus every object. A
    no-op where there is no glibc.
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes  # lazy: only large documents pay for the import (2 ms)
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError):  # not glibc (musl has no malloc_trim)
        pass
