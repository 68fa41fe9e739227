"""Byte-range edits on the original bytes of a file; overlapping edits are refused."""
from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass


class EditConflict(ValueError):
    """Two edits touch the same bytes (or insert at the same offset): neither is applied."""


@dataclass(frozen=True, slots=True)
class Edit:
    """Replace ``data[start:end]`` of ``file`` by ``text`` (``start == end`` inserts)."""

    file: str
    start: int
    end: int
    text: bytes

    def __post_init__(self) -> None:
        if not 0 <= self.start <= self.end:
            raise ValueError(f"bad edit range {self.start}..{self.end}")


def _overlap(a: Edit, b: Edit) -> bool:
    if a.start == b.start:
        return True  # two insertions (or an insertion and a replacement) at one offset
    return a.start < b.end and b.start < a.end


def apply_edits(data: bytes, edits: Iterable[Edit]) -> bytes:
    """``data`` with every edit applied; raises :class:`EditConflict` if two overlap."""
    ordered = sorted(edits, key=lambda e: (e.start, e.end))
    for a, b in itertools.pairwise(ordered):
        if _overlap(a, b):
            raise EditConflict(f"edits overlap at bytes {b.start}..{b.end} of {b.file}")
    if ordered and ordered[-1].end > len(data):
        raise ValueError(f"edit beyond the end of {ordered[-1].file}")
    out: list[bytes] = []
    pos = 0
    for edit in ordered:
        out.append(data[pos:edit.start])
        out.append(edit.text)
        pos = edit.end
    out.append(data[pos:])
    return b"".join(out)


def by_file(edits: Iterable[Edit]) -> dict[str, list[Edit]]:
    out: dict[str, list[Edit]] = {}
    for edit in edits:
        out.setdefault(edit.file, []).append(edit)
    return out
