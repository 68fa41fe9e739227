"""The worker process: the only process that loads the FMU's binary.

    python -m conformance.runtime.child JOB_FILE ADDRESS_SPACE_BYTES

The supervisor starts it with a private temporary directory as its working directory. The child
limits its own address space first (before numpy or fmpy are imported), keeps the original stdout
as its private channel and points file descriptor 1 at stderr, so whatever the FMU prints cannot
corrupt the channel. It then reads the pickled :class:`~conformance.runtime.protocol.Job` and
calls the job's entry point, which sends JSON events (see ``conformance.probes.machinery.stage``).
An exception of ours outside the entry is sent as ``{"event": "worker-error"}``; a MemoryError as
``{"event": "memory"}`` with exit status ``MEMORY_EXIT``.
"""
from __future__ import annotations

import ctypes
import importlib
import json
import os
import pickle
import signal
import sys
import traceback
from typing import Any

from .protocol import MEMORY_EXIT, json_default

try:
    import resource
except ImportError:  # pragma: no cover - not POSIX: no address-space limit
    resource = None  # type: ignore[assignment]


def _limit_memory(limit: int) -> None:
    if resource is not None and limit > 0:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _die_with_parent() -> None:
    """Linux: be killed when the parent dies, so a hung FMU never outlives lsdae."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    parent = os.environ.get("LSDAE_PROBE_PARENT", "")
    if parent.isdigit() and os.getppid() != int(parent):  # it died before prctl took effect
        os._exit(1)


def _channel() -> Any:
    """Keep the original stdout for the protocol; make fd 1 an alias of stderr."""
    fd = os.dup(1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return os.fdopen(fd, "w", buffering=1, encoding="utf-8")


def memory_info(keys: tuple[str, ...] = ("VmSize", "VmRSS")) -> dict[str, int]:
    """``keys`` of /proc/self/status in bytes (Linux; VmSize and VmRSS by default, so the
    supervisor can judge a later death; VmHWM is the peak resident size)."""
    out: dict[str, int] = {}
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                key, _, rest = line.partition(":")
                if key in keys:
                    out[key] = int(rest.split()[0]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return out


def near_limit(share: float = 0.9) -> bool:
    """Whether the address space (VmSize) is at ``share`` of its limit (RLIMIT_AS) or more:
    an allocation or an import that fails then failed for want of memory."""
    if resource is None:
        return False
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    size = memory_info(("VmSize",)).get("VmSize")
    return limit not in (resource.RLIM_INFINITY, -1) and size is not None and size >= share * limit


def reset_peak_memory() -> bool:
    """Start a new peak of the resident size (VmHWM) from now (Linux 4.0 and later: write 5 to
    /proc/self/clear_refs); False where that is not possible, and VmHWM stays the process's."""
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as fh:
            fh.write("5")
    except OSError:
        return False
    return True


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print("usage: python -m conformance.runtime.child JOB_FILE ADDRESS_SPACE_BYTES",
              file=sys.stderr)
        return 2
    _die_with_parent()
    _limit_memory(int(argv[2]))
    channel = _channel()

    def send(message: dict[str, Any]) -> None:
        channel.write(json.dumps(message, default=json_default) + "\n")
        channel.flush()

    try:
        with open(argv[1], "rb") as fh:
            job = pickle.load(fh)
        module, _, function = job.entry.partition(":")
        # the entry (and numpy, fmpy with it) is imported only now, under the memory limit
        status = getattr(importlib.import_module(module), function)(job, send)
    except MemoryError:
        send({"event": "memory", "code": ""})
        status = MEMORY_EXIT
    except Exception as exc:  # a defect of ours outside any probe: say so, not "crashed"
        send({"event": "worker-error", "error": f"{type(exc).__name__}: {exc}",
              "traceback": traceback.format_exc(limit=8)})
        status = 0
    channel.flush()
    sys.stderr.flush()
    os._exit(status)  # no library unloading, no atexit: everything was reported


if __name__ == "__main__":
    main(sys.argv)


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
        "fordblks", "keepcost")]


_MALLINFO: list[Any] = []   # [the function or None], looked up once


def heap_in_use() -> int | None:
    """The bytes the C heap has handed out and not taken back (glibc's mallinfo2: uordblks,
    plus hblkhd for the blocks it maps on its own), or None where there is no mallinfo2.
    Unlike the resident size it grows by exactly what a leak keeps, even while the heap still
    has free chunks to reuse (a process that freed much earlier absorbs a small leak's first
    hundreds of kilobytes without growing)."""
    if not _MALLINFO:
        try:
            function = ctypes.CDLL(None).mallinfo2
            function.restype = _MallInfo2
            function.argtypes = []
            _MALLINFO.append(function)
        except (AttributeError, OSError):
            _MALLINFO.append(None)
    function = _MALLINFO[0]
    if function is None:
        return None
    info = function()
    return int(info.uordblks) + int(info.hblkhd)
