"""The FMI call in progress, in a small buffer shared between the worker and its supervisor."""
from __future__ import annotations

from typing import Any


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
