"""A one-line progress display on stderr while FMUs are checked.

Shown only where a person is watching: stderr is a terminal and the ``CI`` environment variable
is not set (GitHub Actions, GitLab and most CI services set it). Elsewhere :func:`make_progress`
returns a display that prints nothing, so logs and captured output stay clean.
"""
from __future__ import annotations

import os
import sys
import time
from typing import TextIO


class Progress:
    """Counts finished FMUs and names the one in progress, rewriting one line in place."""

    def __init__(self, total: int, *, stream: TextIO, label: str = "checking"):
        self.total = total
        self.stream = stream
        self.label = label
        self.done = 0
        self.started = time.monotonic()
        self._width = 0

    def start(self, path: str) -> None:
        self._show(f"{self.label} {path}")

    def finish(self, path: str) -> None:
        self.done += 1
        self._show(f"checked {path}" if self.done < self.total else "done")

    def close(self) -> None:
        """Erase the line so the report that follows starts on a clean line."""
        if self._width:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
            self._width = 0

    def _show(self, text: str) -> None:
        elapsed = time.monotonic() - self.started
        line = f"[{self.done}/{self.total}] {elapsed:5.1f}s {text}"
        columns = _columns()
        if len(line) > columns - 1:
            line = line[: columns - 2] + "…"
        pad = max(0, self._width - len(line))
        self.stream.write("\r" + line + " " * pad)
        self.stream.flush()
        self._width = len(line)


class NoProgress(Progress):
    """The display used in CI, in pipes and for a single quick FMU: prints nothing."""

    def __init__(self, total: int = 0):
        super().__init__(total, stream=sys.stderr)

    def _show(self, text: str) -> None:
        pass

    def close(self) -> None:
        pass


def _columns() -> int:
    try:
        return os.get_terminal_size(sys.stderr.fileno()).columns
    except (OSError, ValueError):
        return 80


def wanted(mode: str, *, total: int, probes: bool, stream: TextIO | None = None) -> bool:
    """Whether to show progress: ``mode`` is auto, always or never.

    In auto mode: several FMUs or probes (which load binaries and take seconds), on a terminal,
    outside CI.
    """
    if mode == "never":
        return False
    if mode == "always":
        return True
    stream = stream or sys.stderr
    if os.environ.get("CI"):
        return False
    try:
        tty = stream.isatty()
    except (AttributeError, ValueError):
        tty = False
    return tty and (total > 1 or probes)


def make_progress(mode: str, *, total: int, probes: bool, stream: TextIO | None = None
                  ) -> Progress:
    if not wanted(mode, total=total, probes=probes, stream=stream):
        return NoProgress(total)
    return Progress(total, stream=stream or sys.stderr)
