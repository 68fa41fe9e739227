"""Shared steps of the rules on the manifest's variable lists (AlgebraicVariables, Residuals).

Each list entry (a :class:`~conformance.manifest.VrRef` or a Residual
:class:`~conformance.unknowns.Unknown`) names a variable by value reference. The rules on a list
partition its faults: unresolved entries, repeated entries, then one class of problem per
variable. The steps they share live here, so both families resolve and classify alike.
"""
from __future__ import annotations

from typing import Callable, Iterable, Iterator, Sequence, TypeVar

from ..context import CheckContext
from ..manifest import VrRef
from ..model import ModelDescription, Variable
from ..unknowns import Unknown

Entry = TypeVar("Entry", VrRef, Unknown)
Classes = dict[str | None, list[tuple[Entry, Variable]]]


def first_listings(entries: Sequence[Entry], model: ModelDescription
                   ) -> Iterator[tuple[Entry, Variable]]:
    """The first entry of each variable that resolves, with the variable."""
    seen: set[int] = set()
    for entry in entries:
        if entry.vr is None or entry.vr not in model.by_vr or entry.vr in seen:
            continue
        seen.add(entry.vr)
        yield entry, model.by_vr[entry.vr]


def repeats(entries: Sequence[Entry], model: ModelDescription
            ) -> Iterator[tuple[Entry, Entry, Variable]]:
    """Each later entry of a variable already listed: (repeat, first entry, variable).
    Unresolved entries are left to the unknown-vr rules."""
    first: dict[int, Entry] = {}
    for entry in entries:
        if entry.vr is None or entry.vr not in model.by_vr:
            continue
        if entry.vr in first:
            yield entry, first[entry.vr], model.by_vr[entry.vr]
        else:
            first[entry.vr] = entry


def classified(ctx: CheckContext, key: str, wanted: str,
               listed: Callable[[], Iterable[tuple[Entry, Variable]]],
               classifier: Callable[[], Callable[[Variable], str | None]]
               ) -> list[tuple[Entry, Variable]]:
    """The entries whose variable has the ``wanted`` problem. The whole list is classified once
    per FMU (memoised under ``key``) and shared by the rules that partition it; ``classifier``
    builds the per-variable test once (it may gather model-wide facts first)."""

    def classify() -> Classes:
        problem = classifier()
        classes: Classes = {}
        for entry, var in listed():
            classes.setdefault(problem(var), []).append((entry, var))
        return classes

    return ctx.memo(key, classify).get(wanted, [])


def facts(var: Variable, entry: VrRef | Unknown) -> dict:
    """The evidence every problem finding of a list entry carries."""
    return {"value_reference": var.vr, "type": var.type, "causality": var.causality,
            "variability": var.variability, "listed_at_line": entry.line}
