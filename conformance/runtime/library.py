"""The FMU's binary, loaded once per worker process (fmpy's ``FMU3Model``).

Every FMI call made through a :class:`Library` goes through one choke point, ``_call``, which

* writes the name of the call and its number among the library's calls into the shared
  :class:`~conformance.runtime.callrecord.CallRecord` *before* calling, so that the supervisor
  can name the call in progress, and say after how many calls, when the process crashes, hangs
  or runs out of memory;
* counts the call, and the time spent inside the binary (what the FMU costs, apart from
  lsdae's own work, for the benchmarks and ``lsdae check -v``);
* turns fmi3Discard, fmi3Error and fmi3Fatal into :class:`~conformance.runtime.errors.FmiError`
  carrying the messages the FMU logged during that call;
* watches what the calls do to the worker's address space (read from /proc/self/statm on
  Linux before and after one call in ``WATCH_EVERY``, and after every call once those
  sampled calls grew it by an estimated ``WATCH_FROM``): each watched call's growth is added
  up in the CallRecord, with the call that grew it last, so that a worker that runs out of
  memory between two FMI calls after the FMU took the memory is the binary's
  ``binary-memory-limit``, not lsdae's own limit (``conformance.probes.machinery.deaths``). Growth
  between calls (lsdae's own imports and arrays) is never counted and never makes every call
  watched.

fmpy is imported lazily (it is heavy, and the worker sets its memory limit first).
"""
from __future__ import annotations

import ctypes
import itertools
import os
import random
import shutil
import time
from typing import Any, Callable, Sequence

from .callrecord import VALUE_CALLS, CallRecord
from .child import heap_in_use
from .errors import FmiError, Unavailable
from .host import host_platform_tuple, library_extension
from .layout import Layout

STATUS_NAMES = {0: "fmi3OK", 1: "fmi3Warning", 2: "fmi3Discard", 3: "fmi3Error", 4: "fmi3Fatal"}
MAX_LOG_MESSAGES = 200          # per call; an FMU that floods its logger is cut off here
MAX_MESSAGE_CHARS = 1000
WATCH_FROM = 128 << 20          # estimated growth inside calls after which every call is watched
WATCH_EVERY = 32                # one call in WATCH_EVERY is measured until then
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


_STATM: list[int] = []          # [pid, fd]: /proc/self/statm, kept open by the process that opened it


def address_space() -> int | None:
    """The worker's address-space size in bytes (VmSize, from /proc/self/statm; None
    elsewhere). Read with one ``pread`` of a descriptor kept open: it is read around many FMI
    calls, and opening the file each time cost more than a small model's call."""
    try:
        if not _STATM or _STATM[0] != os.getpid():
            _STATM[:] = [os.getpid(), os.open("/proc/self/statm", os.O_RDONLY | os.O_CLOEXEC)]
        return int(os.pread(_STATM[1], 64, 0).split()[0]) * _PAGE
    except (OSError, ValueError, IndexError, AttributeError):
        return None


#: Which calls are measured, one in WATCH_EVERY at random (seeded: the same calls in every
#: run), not every WATCH_EVERY-th: a loop of calls whose period shares a factor with
#: WATCH_EVERY would alias (a path step of twelve calls would never measure the calls at odd
#: places in it), and so would any fixed stride near a rational multiple of the period.
_SAMPLER = random.Random(20)


def sampled() -> bool:
    """Whether the next call's growth is measured (one in WATCH_EVERY, at random)."""
    return _SAMPLER.random() * WATCH_EVERY < 1.0


_RECORDING_CLASS: Any = None
_COPIES = itertools.count(1)    # the folders of the copies made by Library.alone


def _recording_class() -> Any:
    """fmpy's FMU3Model with every FMI call recorded, counted and checked (built lazily)."""
    global _RECORDING_CLASS
    if _RECORDING_CLASS is None:
        from fmpy.fmi3 import FMU3Model  # fmpy: loaded under the worker's memory limit

        class RecordingFMU3Model(FMU3Model):  # type: ignore[misc, valid-type]
            lsdae_record: CallRecord
            lsdae_calls = 0
            lsdae_seconds = 0.0
            lsdae_log: list[str]
            # per FMI function, in this process (every copy of the binary Library.alone
            # loads counts here too: a probe re-run with every instance alone walks its path
            # on copies): calls made, address-space and C-heap growth measured inside them
            lsdae_by_call: dict[str, int] = {}
            lsdae_grown_by: dict[str, int] = {}
            lsdae_heap_by: dict[str, int] = {}
            lsdae_blocked: frozenset[str] = frozenset()
            lsdae_fatal = False
            lsdae_fatal_call = ""           # the first call that returned fmi3Fatal
            lsdae_watch = False             # every call's growth is added up
            lsdae_grown = 0

            def _call(self, fname: str, *args: Any) -> Any:
                function = self._functions[fname]
                if fname in self.lsdae_blocked:  # not an FmiError: nobody must report it as one
                    raise Unavailable(f"{fname} is not called again: in an earlier worker it "
                                      "did not return (binary-timed-out) or returned fmi3Fatal")
                del self.lsdae_log[:]  # the log holds the messages of the last call only
                before = self._lsdae_before()
                heap = heap_in_use() if before is not None else None
                if fname in VALUE_CALLS and len(args) > 2:
                    n = args[2]
                    self.lsdae_record.enter(fname, self.lsdae_calls + 1, args[1],
                                            int(getattr(n, "value", n)))
                else:
                    self.lsdae_record.enter(fname, self.lsdae_calls + 1)
                started = time.perf_counter()
                result = function(*args)
                self.lsdae_seconds += time.perf_counter() - started
                self.lsdae_record.leave()
                self.lsdae_calls += 1
                by_call = self.lsdae_by_call
                by_call[fname] = by_call.get(fname, 0) + 1
                if heap is not None:
                    kept = heap_in_use()
                    if kept is not None and kept > heap:
                        heap_by = self.lsdae_heap_by
                        heap_by[fname] = heap_by.get(fname, 0) + kept - heap
                if before is not None:
                    after = address_space()
                    if after is not None and after > before:
                        self.lsdae_grown += after - before
                        grown_by = self.lsdae_grown_by
                        grown_by[fname] = grown_by.get(fname, 0) + after - before
                        self.lsdae_record.grew(fname, self.lsdae_grown)
                        # a sampled call stands for WATCH_EVERY: watch every call once the
                        # calls' estimated growth passed WATCH_FROM
                        self.lsdae_watch = (self.lsdae_watch or
                                            self.lsdae_grown * WATCH_EVERY > WATCH_FROM)
                if function.restype is ctypes.c_int and result not in (0, 1):
                    self.lsdae_fatal = self.lsdae_fatal or result == 4
                    if result == 4 and not self.lsdae_fatal_call:
                        self.lsdae_fatal_call = fname
                    status = STATUS_NAMES.get(result, f"the illegal status {result}")
                    raise FmiError(fname, status, self.lsdae_log)
                return result

            def _lsdae_before(self) -> int | None:
                """The address space before this call when every call is watched, or when
                this one is sampled (one in WATCH_EVERY); else None. Only what grows inside
                the calls counts: lsdae's own growth between them (its imports, its arrays)
                never makes every call watched, which would slow every call down."""
                if self.lsdae_watch or sampled():
                    return address_space()
                return None

        _RECORDING_CLASS = RecordingFMU3Model
    return _RECORDING_CLASS


class Library:
    """The FMU's binary, loaded once per worker process; the instances made from it.

    :meth:`alone` gives a twin whose every instance has a copy of the binary of its own (its own
    C globals): what an instance computes when no other instance shares its process, the
    reference of ``instances-not-independent`` and of the first-cause re-runs.
    """

    def __init__(self, directory: str, layout: Layout, record: CallRecord, *,
                 blocked: Sequence[str] = (), copies: int = 0):
        self.layout = layout
        self.record = record
        self.directory = directory
        self.blocked = tuple(blocked)
        self.log: list[str] = []
        self.instances: list[Any] = []  # the live Instances; each registers itself
        self.path = os.path.join(directory, "binaries", host_platform_tuple(),
                                 layout.model_identifier + library_extension())
        self.copies = copies     # alone: the copies of the binary one twin may load (0: not)
        self._loaded = 0
        self.fmu = self._load(directory if not copies else self._copy())
        resources = os.path.join(directory, "resources")
        self.resource_path = resources + os.sep if os.path.isdir(resources) else None
        self._count = 0
        self._init_count = 0
        self._first_taken = False

    def _load(self, root: str) -> Any:
        """The binary of the FMU unpacked at ``root`` (fmpy builds the path from it)."""
        # fmpy resolves every fmi3* symbol here (AR-07): a missing one raises. Loading runs
        # the library's constructors, so it is recorded like a call.
        self.record.enter("dlopen (loading the library)")
        fmu = _recording_class()(guid=self.layout.token,
                                 modelIdentifier=self.layout.model_identifier,
                                 unzipDirectory=root, instanceName="lsdae")
        self.record.leave()
        fmu.lsdae_record = self.record
        fmu.lsdae_log = self.log
        fmu.lsdae_blocked = frozenset(self.blocked)
        return fmu

    def _copy(self) -> str:
        """A folder beside the FMU's whose binaries/<platform>/ holds a copy of the binary and
        links to the files beside it (its dependencies are the same ones): the dynamic loader
        maps a file it has not seen as a new library, with C globals of its own. Returns the
        folder (fmpy builds the library's path from it)."""
        if self._loaded >= self.copies:
            raise Unavailable(f"more than {self.copies} copies of the binary would be needed "
                              "to give every instance its own")
        self._loaded += 1
        root = os.path.join(os.path.dirname(os.path.abspath(self.directory)),
                            f"lsdae-alone-{os.getpid()}-{next(_COPIES)}")
        source = os.path.dirname(self.path)
        target = os.path.join(root, "binaries", os.path.basename(source))
        os.makedirs(target)
        for name in os.listdir(source):
            if os.path.join(source, name) != self.path:
                os.symlink(os.path.join(source, name), os.path.join(target, name))
        shutil.copyfile(self.path, os.path.join(target, os.path.basename(self.path)))
        return root

    def alone(self, copies: int) -> Library:
        """A twin of this library whose every instance loads a copy of the binary of its own
        (at most ``copies`` in all): no instance shares a C global with any other."""
        return Library(self.directory, self.layout, self.record, blocked=self.blocked,
                       copies=copies)

    def fmu_for_instance(self) -> Any:
        """The loaded binary a new instance calls: this library's, or, for a twin made by
        :meth:`alone`, a copy of its own (the first instance takes the copy loaded first)."""
        if not self.copies or not self._first_taken:
            self._first_taken = True
            return self.fmu
        return self._load(self._copy())

    @property
    def calls(self) -> int:
        return self.fmu.lsdae_calls

    def calls_by_function(self) -> dict[str, int]:
        """How many calls of each FMI function the process has made so far, through this
        library and its copies (a copy of the counts)."""
        return dict(self.fmu.lsdae_by_call)

    def growth_by_function(self) -> dict[str, int]:
        """The growth measured inside each FMI function (bytes; the calls measured: one in
        WATCH_EVERY, every call once the growth passed WATCH_FROM): of the C heap in use where
        glibc tells it (a leak served from free heap pages grows no address space), else of
        the address space."""
        return dict(self.fmu.lsdae_heap_by or self.fmu.lsdae_grown_by)

    @property
    def seconds(self) -> float:
        """Seconds spent inside the binary's functions so far (not in lsdae's code)."""
        return float(self.fmu.lsdae_seconds)

    @property
    def fatal_call(self) -> str:
        """The first FMI call that returned fmi3Fatal ("" when none did)."""
        return str(self.fmu.lsdae_fatal_call)

    @property
    def fatal(self) -> bool:
        """An FMI call returned fmi3Fatal: no instance of this library may be used again."""
        return bool(self.fmu.lsdae_fatal)

    def logger(self, name: str) -> Callable[..., None]:
        def log_message(env: Any, status: int, category: bytes | None,
                        message: bytes | None) -> None:
            if len(self.log) >= MAX_LOG_MESSAGES:
                return
            text = (message or b"").decode("utf-8", "replace")[:MAX_MESSAGE_CHARS]
            label = STATUS_NAMES.get(status, str(status)).removeprefix("fmi3")
            self.log.append(f"[{label}] {name}: {text}")
        return log_message

    def next_name(self, mode: str) -> str:
        self._count += 1
        return f"lsdae-{mode}-{self._count}"

    def next_initialization_name(self, mode: str) -> str:
        """The name of an instance left in Initialization Mode (modes.start_initialization),
        numbered apart: the many of them never rename the other instances in the reports."""
        self._init_count += 1
        return f"lsdae-init-{mode}-{self._init_count}"

    def free_all(self) -> None:
        for inst in list(self.instances):
            inst.free()
