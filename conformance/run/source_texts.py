"""The bytes of the XML files a check read, for the source lines its findings show.

A finding shows the line it points at (:class:`conformance.run.collector.LineCache`). Keeping every
file's bytes until the end of the check would hold a large modelDescription.xml (85 MB at 500k
variables) in memory beside its parsed tree and the model read from it, although a conformant
FMU needs no line at all. So a file up to :data:`KEEP_BYTES` is kept; a larger one is read again
from the FMU only when a finding asks for one of its lines (the archive limits apply again).
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Callable

from ..intake.fmu import ArchiveLimits, open_fmu

log = logging.getLogger(__name__)

KEEP_BYTES = 4 << 20


class SourceTexts:
    """File name -> its bytes, kept or read again on first use."""

    def __init__(self, path: Path, limits: ArchiveLimits):
        self._path = path
        self._limits = limits
        self._texts: dict[str, bytes | Callable[[], bytes | None] | None] = {}

    def keep(self, name: str, data: bytes) -> None:
        """Remember the bytes of ``name`` as read (or how to read them again, if large)."""
        if len(data) <= KEEP_BYTES:
            self._texts[name] = data
        else:
            self._texts[name] = lambda: self._read_again(name)

    def get(self, name: str) -> bytes | None:
        found = self._texts.get(name)
        if callable(found):
            found = self._texts[name] = found()
        return found

    def _read_again(self, name: str) -> bytes | None:
        try:
            source, _ = open_fmu(self._path, limits=self._limits)
            if source is None:
                return None
            with source:
                return source.read(name)
        except Exception:  # the FMU changed or vanished since: the finding has no source line
            log.debug("cannot read %s again for its source lines", name, exc_info=True)
            return None
