"""The parent's end of a worker process: its channel, the memory it reached, how it ended.

The worker runs in a session of its own (killed as a whole process group). :meth:`read` returns
the JSON events that arrived; the memory is sampled from ``/proc/<pid>/status`` while it runs and,
after death, from ``wait4``'s peak resident size. What a death means is the caller's to decide.
"""
from __future__ import annotations

import json
import logging
import os
import select
import signal
import subprocess
import sys
import time
from typing import Any

from .protocol import MEMORY_EXIT

log = logging.getLogger(__name__)

POLL_SECONDS = 0.05        # how often the parent looks at the worker's memory
MAX_CHANNEL_BYTES = 64 << 20


class WorkerProcess:
    """The parent's handle on one worker process: its channel, its memory, its exit status."""

    def __init__(self, proc: subprocess.Popen[bytes]):
        self.proc = proc
        assert proc.stdout is not None
        self.fd = proc.stdout.fileno()
        os.set_blocking(self.fd, False)
        self.buffer = b""
        self.peak_vm = 0
        self.maxrss = 0
        self.baseline: dict[str, int] = {}
        self.memory_error = False
        self.returncode: int | None = None
        self._last_poll = 0.0

    def read(self, timeout: float) -> tuple[list[dict[str, Any]], bool]:
        """Events that arrived within ``timeout`` seconds, and whether the channel closed."""
        timeout = max(0.0, min(timeout, POLL_SECONDS))
        ready, _, _ = select.select([self.fd], [], [], timeout)
        self._poll_memory()
        eof = False
        if ready:
            try:
                chunk: bytes | None = os.read(self.fd, 1 << 16)
            except BlockingIOError:
                chunk = None
            if chunk == b"":
                eof = True
            elif chunk:
                self.buffer += chunk
            if len(self.buffer) > MAX_CHANNEL_BYTES:  # a flood: treat as a broken worker
                self.buffer, eof = b"", True
        events = []
        while b"\n" in self.buffer:
            line, self.buffer = self.buffer.split(b"\n", 1)
            try:
                event = json.loads(line)
            except ValueError:
                log.warning("probe worker sent an unreadable line: %r", line[:200])
                continue
            if isinstance(event, dict):
                events.append(event)
        return events, eof

    def _poll_memory(self) -> None:
        now = time.monotonic()
        if now - self._last_poll < POLL_SECONDS:
            return
        self._last_poll = now
        try:
            with open(f"/proc/{self.proc.pid}/status", encoding="ascii") as fh:
                for line in fh:
                    if line.startswith("VmPeak:"):
                        self.peak_vm = max(self.peak_vm, int(line.split()[1]) * 1024)
                        break
        except (OSError, ValueError, IndexError):
            pass

    def peak(self) -> int:
        """The largest address space the worker is known to have reached, in bytes."""
        nonresident = max(0, self.baseline.get("VmSize", 0) - self.baseline.get("VmRSS", 0))
        return max(self.peak_vm, self.maxrss + nonresident)

    def finish(self, wait: float = 2.0) -> None:
        """Reap the worker (killing it if it does not exit within ``wait`` seconds)."""
        deadline = time.monotonic() + wait
        while self.returncode is None:
            self._poll_memory()
            if self._reap() or time.monotonic() > deadline:
                break
            time.sleep(0.005)
        if self.returncode is None:
            self.kill()

    def _reap(self, flags: int = os.WNOHANG) -> bool:
        try:
            pid, status, usage = os.wait4(self.proc.pid, flags)
        except ChildProcessError:
            self.returncode = self.proc.returncode if self.proc.returncode is not None else -1
            return True
        if pid == 0:
            return False
        self.returncode = os.waitstatus_to_exitcode(status)
        self.proc.returncode = self.returncode
        self.maxrss = usage.ru_maxrss * (1 if sys.platform == "darwin" else 1024)
        return True

    def kill(self) -> None:
        """Kill the worker's whole process group (it runs in a session of its own)."""
        self.signal_kill()
        if self.returncode is None:
            self._reap(0)
        if self.proc.stdout is not None:
            self.proc.stdout.close()

    def signal_kill(self) -> None:
        """SIGKILL to the worker's process group, and nothing else: safe from another thread
        while this one reads (it then reads the end of the channel and cleans up)."""
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass

    def how(self) -> str:
        code = self.returncode
        if code is None:
            return "ended"
        if code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            return f"killed by {name}"
        if code == MEMORY_EXIT and self.memory_error:
            return "MemoryError"
        return f"the process exited with status {code}"
