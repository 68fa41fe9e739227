"""The worker process: the only process that loads the FMU's binary; runs the probes.

    python -m conformance.probes.worker JOB_FILE ADDRESS_SPACE_BYTES

The runner (``conformance.probes.runner``) starts it with a private temporary directory as its
working directory. The worker limits its own address space first (before numpy or fmpy are
imported), keeps the original stdout as its private channel to the runner and points file
descriptor 1 at stderr, so whatever the FMU prints cannot corrupt the channel. It then reads the
pickled :class:`Job`, loads the binary, brings one instance into Continuous-Time Mode in DAE
mode and one in ODE mode, samples the points, and runs each probe in turn, writing one JSON line
per event:

    {"event": "ready", "info": {...}}             setup done (points, seed)
    {"event": "load-failed", "violation": {...}}  the binary cannot be loaded
    {"event": "start", "code": "DAE7xx"}
    {"event": "done", "code": ..., "violations": [...], "skipped": reason|null, "info": {...}}
    {"event": "memory", "code": ...}              Python itself ran out of memory
    {"event": "fatal", "code": ...}               a call returned fmi3Fatal: this process stops,
                                                  a fresh one runs the remaining probes
    {"event": "worker-error", "error": ...}       an exception of ours outside the probes
    {"event": "end"}

The parent reads JSON, never pickle, from this process: it runs foreign code. The probe
running and the FMI call in progress are in a small shared file (:class:`CallRecord`), written
before every FMI call, which the parent reads after a death or a hang. :class:`WorkerProcess`
is the parent's end: the channel, the memory the worker reached, and how it ended. Both ends of
the protocol live here; what a death means is decided by ``conformance.probes.runner``.
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
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

log = logging.getLogger(__name__)

MEMORY_EXIT = 86           # exit status after a MemoryError in Python
POLL_SECONDS = 0.05        # how often the parent looks at the worker's memory
MAX_CHANNEL_BYTES = 64 << 20


@dataclass
class Job:
    """What the runner hands the worker (pickled: parent to child only)."""

    directory: str                 # where binaries/ and resources/ were extracted
    call_file: str                 # the shared CallRecord
    model: Any                     # ModelDescription
    manifest: Any                  # Manifest | None
    draft: str | None
    seed: int
    probes: list[tuple[str, str, dict[str, Any]]] = field(default_factory=list)  # code, name, opts
    blocked: list[str] = field(default_factory=list)  # FMI functions that hung earlier


class CallRecord:
    """The probe running and the FMI call in progress, in a small shared buffer.

    The worker writes it before and after every FMI call (two slice assignments); the runner
    reads the same bytes from the file after the worker died or was killed. Layout: probe code
    (32 bytes), call name (64 bytes), one byte that is 1 while the call is in progress.
    """

    SIZE = 128
    _PROBE, _CALL, _FLAG = slice(0, 32), slice(32, 96), 96

    def __init__(self, buffer: Any | None = None):
        self.buffer = buffer if buffer is not None else bytearray(self.SIZE)

    def set_probe(self, probe: str) -> None:
        self.buffer[self._PROBE] = probe.encode()[:32].ljust(32, b"\0")
        self.buffer[self._CALL] = bytes(64)
        self.buffer[self._FLAG] = 0

    def enter(self, call: str) -> None:
        self.buffer[self._CALL] = call.encode()[:64].ljust(64, b"\0")
        self.buffer[self._FLAG] = 1

    def leave(self) -> None:
        self.buffer[self._FLAG] = 0

    @classmethod
    def parse(cls, data: bytes) -> tuple[str, str, bool]:
        """(probe, last call, whether that call was still in progress)."""
        data = bytes(data).ljust(cls.SIZE, b"\0")

        def text(part: bytes) -> str:
            return part.split(b"\0", 1)[0].decode("ascii", "replace")

        return text(data[cls._PROBE]), text(data[cls._CALL]), data[cls._FLAG] == 1


def _limit_memory(limit: int) -> None:
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return
    if limit > 0:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _die_with_parent() -> None:
    """Linux: be killed when the parent dies, so a hung FMU never outlives lsdae."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

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


def _plain(value: Any) -> Any:
    """JSON default for numpy scalars and arrays in evidence."""
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    return str(value)


def violation_json(v: Any) -> dict[str, Any]:
    loc = v.location
    return {"message": v.message, "location": [loc.file, loc.line, loc.column, loc.path],
            "evidence": [[k, val] for k, val in v.evidence], "subject": v.subject,
            "rule": v.rule}


def _tuples(value: Any) -> Any:
    if isinstance(value, list):
        return tuple(_tuples(v) for v in value)
    return value


def violation_from_json(data: dict[str, Any]) -> Any:
    """The inverse of :func:`violation_json` (lists become tuples, as in evidence)."""
    from ..findings import Location, Violation

    file, line, column, path = (list(data.get("location") or []) + [None] * 4)[:4]
    return Violation(str(data.get("message", "")), Location(file, line, column, path),
                     _tuples(data.get("evidence") or []), data.get("subject"), data.get("rule"))


def _memory_info() -> dict[str, int]:
    """VmSize and VmRSS in bytes (Linux), so the runner can judge a later death."""
    out: dict[str, int] = {}
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                key, _, rest = line.partition(":")
                if key in ("VmSize", "VmRSS"):
                    out[key] = int(rest.split()[0]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return out


class Worker:
    def __init__(self, job: Job, send: Callable[[dict[str, Any]], None]):
        self.job = job
        self.send = send

    def run(self) -> int:
        import mmap

        from ..findings import Location, Violation, evidence
        from .sampling import Layout
        from .session import Library

        with open(self.job.call_file, "r+b") as fh:
            record = CallRecord(mmap.mmap(fh.fileno(), CallRecord.SIZE))
        record.set_probe("setup")
        model = self.job.model
        layout = Layout.build(model, self.job.manifest)
        try:
            library = Library(self.job.directory, layout, record, blocked=self.job.blocked)
        except Exception as exc:  # fmpy raises plain Exception or AttributeError here
            error = str(exc).replace(self.job.directory + os.sep, "")  # the path in the FMU
            self.send({"event": "load-failed", "violation": violation_json(Violation(
                f"the binary cannot be loaded: {error}", Location(),
                evidence(error=error, exception=type(exc).__name__)))})
            return 0
        ctx = self._context(library, layout)
        self.send({"event": "ready", "info": ctx.facts["info"], "memory": _memory_info()})
        for code, name, options in self.job.probes:
            self._probe(ctx, record, code, name, options)
            if library.fatal:  # every instance is invalid now (SM-04): start afresh
                self.send({"event": "fatal", "code": code})
                return 0
        record.set_probe("teardown")
        library.free_all()
        self.send({"event": "end"})
        return 0

    def _context(self, library: Any, layout: Any) -> Any:
        import numpy as np

        from .api import FmiError, ProbeContext, ProbeSkipped
        from .sampling import near_points, points_info, start_point
        from .session import start_instance

        facts: dict[str, Any] = {"layout": layout, "library": library, "info": {}}
        evaluators: dict[str, Any] = {}
        for mode in ("dae", "ode"):
            try:
                evaluators[mode] = start_instance(library, mode)
            except (FmiError, ProbeSkipped) as exc:
                evaluators[mode] = None
                facts[f"{mode}_error"] = exc
        start = start_point(evaluators["dae"] or evaluators["ode"], layout,
                            facts.setdefault("start_nonfinite", {}))
        rng = np.random.default_rng(self.job.seed)
        points = [start, *near_points(start, layout, rng)]
        facts["info"].update(points_info(points, layout, self.job.seed))
        return ProbeContext(
            model=self.job.model, manifest=self.job.manifest, draft=self.job.draft,
            seed=self.job.seed, rng=rng, points=points, dae=evaluators["dae"],
            ode=evaluators["ode"], new_instance=lambda mode: start_instance(library, mode),
            facts=facts)

    def _probe(self, ctx: Any, record: Any, code: str, name: str,
               options: dict[str, Any]) -> None:
        from ..findings import Violation, evidence
        from .api import FmiError, ProbeSkipped
        from .registry import PROBES

        record.set_probe(code)
        self.send({"event": "start", "code": code})
        violations: list[Any] = []
        skipped = None
        try:
            for v in PROBES[code](ctx, **options):
                violations.append(v)
        except ProbeSkipped as exc:
            skipped = str(exc) or "skipped by the probe"
        except FmiError as exc:
            first = f": {exc.log[0]}" if exc.log else ""
            skipped = f"{exc.call} returned {exc.status}{first}"
        except MemoryError:
            violations.clear()
            self.send({"event": "memory", "code": code})
            sys.stderr.flush()
            os._exit(MEMORY_EXIT)
        except Exception as exc:  # a defect of ours: report it, run the next probe
            violations.append(Violation(
                f"probe {code} {name} failed: {type(exc).__name__}: {exc}",
                evidence=evidence(rule=code, traceback=traceback.format_exc(limit=8)),
                rule="internal-error"))
        self.send({"event": "done", "code": code,
                   "violations": [violation_json(v) for v in violations],
                   "skipped": skipped, "info": ctx.facts.get("info", {})})


# ---------------------------------------------------------------- parent side

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
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        if self.returncode is None:
            self._reap(0)
        if self.proc.stdout is not None:
            self.proc.stdout.close()

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


# ----------------------------------------------------------------- child side

def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print("usage: python -m conformance.probes.worker JOB_FILE ADDRESS_SPACE_BYTES",
              file=sys.stderr)
        return 2
    _die_with_parent()
    _limit_memory(int(argv[2]))
    channel = _channel()

    def send(message: dict[str, Any]) -> None:
        channel.write(json.dumps(message, default=_plain) + "\n")
        channel.flush()

    import pickle

    with open(argv[1], "rb") as fh:
        job = pickle.load(fh)
    try:
        status = Worker(job, send).run()
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
