"""Shared steps of the rules on the manifest's variable lists (AlgebraicVariables, Residuals).

Each list entry (a :class:`~conformance.model.manifest.VrRef` or a Residual
:class:`~conformance.model.unknowns.Unknown`) names a variable by value reference. The rules on a list
partition its faults: unresolved entries, repeated entries, then one class of problem per
variable. The steps they share live here, so both families resolve and classify alike.
"""
from __future__ import annotations

from itertools import compress
from operator import attrgetter
from typing import Callable, Iterator, NamedTuple, Sequence, TypeVar

from .context import CheckContext
from ..model.manifest import VrRef
from ..model.description import Variable
from ..model.unknowns import Unknown

Entry = TypeVar("Entry", VrRef, Unknown)
Classes = dict[str | None, list[tuple[Entry, Variable]]]
# A list as two columns: the entries, and the variable each names.
Listing = tuple[Sequence[Entry], Sequence[Variable]]
# The problem of each listed variable, or None when none has one.
Problems = Callable[[Sequence[Variable]], Sequence[str | None] | None]


class Resolution(NamedTuple):
    """A manifest list resolved against the model: each entry's value reference and variable
    (None when it names none), in list order."""

    entries: Sequence[VrRef] | Sequence[Unknown]
    vrs: list[int | None]
    variables: list[Variable | None]
    complete: bool      # every entry names a variable
    distinct: bool      # no value reference is listed twice


def resolution(ctx: CheckContext, name: str) -> Resolution:
    """The manifest's ``algebraic`` or ``residuals`` list resolved, once per FMU: the list
    rules, the count rule and the index-1 rule all start from it."""
    def compute() -> Resolution:
        assert ctx.model is not None and ctx.manifest is not None
        entries = getattr(ctx.manifest, name)
        vrs = list(map(attrgetter("vr"), entries))
        variables = list(map(ctx.model.by_vr.get, vrs))  # by_vr.get(None) is None
        return Resolution(entries, vrs, variables, all(variables), len(set(vrs)) == len(vrs))
    return ctx.memo(f"resolution-{name}", compute)


def resolved_vrs(listed: Resolution) -> frozenset[int]:
    """The value references of the list that name a variable."""
    return frozenset(compress(listed.vrs, listed.variables))


def first_listings(listed: Resolution) -> Listing:
    """The first entry of each variable that resolves, and the variables, in list order."""
    if listed.complete and listed.distinct:
        return listed.entries, listed.variables  # type: ignore[return-value]  # the usual case
    seen: set[int] = set()
    entries, variables = [], []
    for entry, var in zip(listed.entries, listed.variables):
        if var is None or entry.vr in seen:
            continue
        seen.add(entry.vr)
        entries.append(entry)
        variables.append(var)
    return entries, variables


def repeats(listed: Resolution) -> Iterator[tuple[Entry, Entry, Variable]]:
    """Each later entry of a variable already listed: (repeat, first entry, variable).
    Unresolved entries are left to the unknown-vr rules."""
    if listed.distinct:
        return  # the usual case
    first: dict[int, Entry] = {}
    for entry, var in zip(listed.entries, listed.variables):
        if var is None:
            continue
        if entry.vr in first:
            yield entry, first[entry.vr], var
        else:
            first[entry.vr] = entry


def classified(ctx: CheckContext, key: str, wanted: str,
               listed: Callable[[], Listing], classifier: Callable[[], Problems]
               ) -> list[tuple[Entry, Variable]]:
    """The entries whose variable has the ``wanted`` problem. The whole list is classified once
    per FMU (memoised under ``key``) and shared by the rules that partition it; ``classifier``
    builds the test once (it may gather model-wide facts first): given the listed variables, it
    returns the problem of each, or None when none has one (the usual case, which it may decide
    per class of variables rather than per variable)."""

    def classify() -> Classes:
        entries, variables = listed()
        problems = classifier()(variables)
        if problems is None:
            return {}  # no entry has a problem (the rules ask only for problem classes)
        classes: Classes = {}
        for problem, entry, var in zip(problems, entries, variables):
            classes.setdefault(problem, []).append((entry, var))
        return classes

    return ctx.memo(key, classify).get(wanted, [])


def facts(var: Variable, entry: VrRef | Unknown) -> dict:
    """The evidence every problem finding of a list entry carries."""
    return {"value_reference": var.vr, "type": var.type, "causality": var.causality,
            "variability": var.variability, "listed_at_line": entry.line}
