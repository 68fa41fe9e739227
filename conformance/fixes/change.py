"""What a fixer returns: a change, or NoFix with the reason no exact fix exists."""
from __future__ import annotations

from dataclasses import dataclass

from ..report.findings import Finding
from .edits import Edit


class NoFix(Exception):
    """No exact fix exists; the message says why (``lsdae fix`` prints it)."""


@dataclass(frozen=True)
class Change:
    fixer: str
    fixes: tuple[Finding, ...]               # the findings this change claims to fix
    edits: tuple[Edit, ...] = ()
    drop: frozenset[int] = frozenset()       # zip entries to leave out (indices)
