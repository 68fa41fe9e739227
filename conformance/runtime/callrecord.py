"""The FMI call in progress, in a small buffer shared between the worker and its supervisor."""
from __future__ import annotations

import ctypes
import struct
from typing import Any, NamedTuple

_COUNT = struct.Struct("<Q")
_REFS = struct.Struct("<I")

#: Value references of the call in progress kept in the record (the first of them).
REFS_KEPT = 8

#: The calls whose second and third arguments are value references and their count: a crash
#: in one of them names the variables (:meth:`CallRecord.refs`).
VALUE_TYPES = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32",
               "Int64", "UInt64", "Boolean", "String", "Binary", "Clock")
GETTER_CALLS = frozenset(f"fmi3Get{type_}" for type_ in VALUE_TYPES)
VALUE_CALLS = GETTER_CALLS | frozenset(f"fmi3Set{type_}" for type_ in VALUE_TYPES)


class CallCounts(NamedTuple):
    """How many FMI calls the worker's library had started (the one in progress included),
    and how many it had started when the current probe began."""

    started: int
    probe_start: int

    def completed(self, in_progress: bool) -> int:
        """FMI calls that had returned: the call in progress is not one of them."""
        return max(0, self.started - (1 if in_progress else 0))

    def completed_in_probe(self, in_progress: bool) -> int:
        return max(0, self.completed(in_progress) - self.probe_start)


class CallRecord:
    """The probe running and the FMI call in progress, in a small shared buffer.

    The worker writes it before and after every FMI call (a few slice assignments); the runner
    reads the same bytes from the file after the worker died or was killed. Layout: probe code
    (32 bytes), call name (64 bytes), one byte that is 1 while the call is in progress; at 104
    the number of FMI calls the library has started (the call in progress included, written
    before the call), at 112 that number when the probe began (both unsigned 64-bit, little
    endian); at 120 the bytes by which FMI calls grew the worker's address space (counted once
    the library watches its calls' memory, see ``conformance.runtime.library``), at 128 the
    name of the call that grew it last (64 bytes); at 192 how many value references the call in
    progress passed (0 for a call that passes none, unsigned 32-bit), at 196 how many of them
    are kept (one byte), at 200 the first :data:`REFS_KEPT` of them (unsigned 32-bit), so
    that a crash names the variables it read or set.
    """

    SIZE = 232
    _PROBE, _CALL, _FLAG = slice(0, 32), slice(32, 96), 96
    _STARTED, _PROBE_START = slice(104, 112), slice(112, 120)
    _GROWN, _GREW = slice(120, 128), slice(128, 192)
    _NREFS, _KEPT, _REFS = slice(192, 196), 196, slice(200, 200 + 4 * REFS_KEPT)

    def __init__(self, buffer: Any | None = None):
        self.buffer = buffer if buffer is not None else bytearray(self.SIZE)

    def set_probe(self, probe: str) -> None:
        self.buffer[self._PROBE] = probe.encode()[:32].ljust(32, b"\0")
        self.buffer[self._CALL] = bytes(64)
        self.buffer[self._FLAG] = 0
        self.buffer[self._PROBE_START] = bytes(self.buffer[self._STARTED])

    def enter(self, call: str, count: int | None = None, refs: Any = None, n: int = 0) -> None:
        """``call`` is about to be made; ``count`` is its number among the library's calls;
        ``refs``: the C array of the ``n`` value references it passes (None: it passes none)."""
        self.buffer[self._CALL] = call.encode()[:64].ljust(64, b"\0")
        if count is not None:
            self.buffer[self._STARTED] = _COUNT.pack(count)
        head = b""
        # an array of 32-bit value references; a pointer (a probe's raw arguments) is not read
        if n > 0 and isinstance(refs, ctypes.Array) and ctypes.sizeof(refs._type_) == 4:
            head = bytes(memoryview(refs).cast("B")[:4 * min(n, REFS_KEPT)])
        self.buffer[self._NREFS] = _REFS.pack(min(max(n, 0), 0xFFFFFFFF) if head else 0)
        self.buffer[self._KEPT] = len(head) // 4
        self.buffer[self._REFS.start:self._REFS.start + len(head)] = head
        self.buffer[self._FLAG] = 1

    def leave(self) -> None:
        self.buffer[self._FLAG] = 0

    def grew(self, call: str, total: int) -> None:
        """FMI calls grew the address space by ``total`` bytes so far, ``call`` last."""
        self.buffer[self._GROWN] = _COUNT.pack(max(0, total))
        self.buffer[self._GREW] = call.encode()[:64].ljust(64, b"\0")

    @classmethod
    def growth(cls, data: bytes) -> tuple[int, str]:
        """(bytes by which FMI calls grew the address space, the call that grew it last)."""
        data = bytes(data).ljust(cls.SIZE, b"\0")
        return (_COUNT.unpack(data[cls._GROWN])[0],
                data[cls._GREW].split(b"\0", 1)[0].decode("ascii", "replace"))

    @classmethod
    def parse(cls, data: bytes) -> tuple[str, str, bool]:
        """(probe, last call, whether that call was still in progress)."""
        data = bytes(data).ljust(cls.SIZE, b"\0")

        def text(part: bytes) -> str:
            return part.split(b"\0", 1)[0].decode("ascii", "replace")

        return text(data[cls._PROBE]), text(data[cls._CALL]), data[cls._FLAG] == 1

    @classmethod
    def refs(cls, data: bytes) -> tuple[int, tuple[int, ...]]:
        """(how many value references the last call passed, the first of them)."""
        data = bytes(data).ljust(cls.SIZE, b"\0")
        n = _REFS.unpack(data[cls._NREFS])[0]
        kept = min(data[cls._KEPT], REFS_KEPT)
        return n, struct.unpack(f"<{kept}I", data[cls._REFS.start:cls._REFS.start + 4 * kept])

    @classmethod
    def counts(cls, data: bytes) -> CallCounts:
        """The call counters of ``data`` (zeros for a short or empty buffer)."""
        data = bytes(data).ljust(cls.SIZE, b"\0")
        return CallCounts(_COUNT.unpack(data[cls._STARTED])[0],
                          _COUNT.unpack(data[cls._PROBE_START])[0])
