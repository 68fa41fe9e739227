"""One defect, one finding: findings that name a shared cause are folded into one.

A probe or a check names the defect a violation shows (``Violation.cause``: one key, or several)
where several rules can see one defect: the same derivative entry in the directional and the
adjoint derivative, in both modes, in Continuous-Time and Initialization Mode; the entries of one unknown or one known that a wrong formula or a wrong partial derivative
spoils; what a legacy draft's shape implies for the manifest's header beside the migration that
names the shape. Violations that share a key are one cause, and so are violations linked through
others (the components of the graph of shared keys): a wrong formula for an intermediate value
spoils the entries of several unknowns, each sharing a known with the next.

The folded finding is the weightiest of them; among equals the first cause (:data:`FIRST`,
then code order -- the catalogue numbers rules in the order a check meets them, so a cause
mostly comes before its consequences --, then where it was seen, so that one probe worker or two
give the same finding; a crash in a call of one variable before the same crash in a call of
several, which it narrows to that variable). Its message says how many more places and the
first few, its evidence
lists each (``also``: rule, where, message). Violations without a cause are left alone.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

from ..report.catalogue import RuleSpec
from ..report.findings import Severity, Violation, evidence

Item = tuple[RuleSpec, Violation]

#: The rules that name a first cause, in order, before the others of one weight: a run that
#: stops, a value the FMU will not take or give, start values it does not hold, and a formula
#: that differs between its two modes (what it does to that mode's derivatives, its dg/dw and
#: its trajectory follows from it).
FIRST = ("enable-handshake", "dae-initialization-refused", "evaluation-failed",
         "algebraic-not-settable", "input-not-settable", "state-set-ignored",
         "start-value-not-applied", "ode-dae-inconsistent")

#: Places named in a folded finding's message; its evidence lists them all (up to ALSO_KEPT).
PLACES_SHOWN = 5
ALSO_KEPT = 200


def cause_keys(v: Violation) -> tuple[str, ...]:
    """The keys of a violation's cause (none, one or several)."""
    if not v.cause:
        return ()
    return (v.cause,) if isinstance(v.cause, str) else tuple(v.cause)


def components(items: Sequence[Item]) -> list[list[int]]:
    """The indices of ``items`` linked by a shared cause key, component by component (each
    component in index order; items without a cause are in none)."""
    parent: dict[int, int] = {}

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    owner: dict[str, int] = {}
    for k, (_, v) in enumerate(items):
        keys = cause_keys(v)
        if not keys:
            continue
        parent[k] = k
        for key in keys:
            if key in owner:
                a, b = root(owner[key]), root(k)
                if a != b:
                    parent[max(a, b)] = min(a, b)
            else:
                owner[key] = k
    out: dict[int, list[int]] = {}
    for k in parent:
        out.setdefault(root(k), []).append(k)
    return list(out.values())


def fold_causes(items: Sequence[Item], severity: Callable[[RuleSpec, str | None], Severity]
                ) -> list[Item]:
    """``items`` with each group of violations of one cause folded into its first."""
    return [item for _, item in fold_indexed(items, severity)]


def fold_indexed(items: Sequence[Item], severity: Callable[[RuleSpec, str | None], Severity],
                 labels: Sequence[str | None] = ()) -> list[tuple[int, Item]]:
    """:func:`fold_causes`, each kept item with its index in ``items``. ``labels``: how to
    name an item among the places of another (default: where it was seen and its subject)."""
    out = list(items)
    dropped: set[int] = set()
    for members in components(items):
        if len(members) < 2:
            continue
        members.sort(key=lambda k: (-severity(items[k][0], items[k][1].part),
                                    _rank(items[k][0]), items[k][0].code, _breadth(items[k][1]),
                                    seen(items[k][1]), items[k][1].text))
        first, rest = members[0], members[1:]
        rule, owner = items[first]
        also = [(items[k][0].code, (labels[k] if k < len(labels) else None)
                 or label(items[k][1], owner), items[k][1]) for k in rest]
        shown = "; ".join(w for _, w, _ in also[:PLACES_SHOWN])
        if len(also) > PLACES_SHOWN:
            shown += f"; and {len(also) - PLACES_SHOWN} more"
        extra = evidence(also=[{"rule": code, "where": w, "message": v.text}
                               for code, w, v in also[:ALSO_KEPT]])
        if len(also) > ALSO_KEPT:
            extra += evidence(also_left_out=len(also) - ALSO_KEPT)
        out[first] = (rule, replace(owner, message=owner.message + (
            f"; the same defect in {len(also)} more place{'s' if len(also) > 1 else ''}: "
            f"{shown}"), evidence=owner.evidence + extra))
        dropped.update(rest)
    return [(k, item) for k, item in enumerate(out) if k not in dropped]


def _rank(rule: RuleSpec) -> int:
    return FIRST.index(rule.name) if rule.name in FIRST else len(FIRST)


def _breadth(v: Violation) -> int:
    """How many variables the violation's call named (``value_reference_count``: a crash
    during a call that read or set them); the narrowest names the defect best (0: none)."""
    n = dict(v.evidence).get("value_reference_count")
    return n if isinstance(n, int) else 0


def seen(v: Violation) -> str:
    """Where the violation was seen, as its probe says (``place`` in its evidence), or ''."""
    return str(dict(v.evidence).get("place", ""))


def label(v: Violation, owner: Violation) -> str:
    """Where a folded violation was seen, and what it is about where that is not the owner's
    subject (another entry, another variable)."""
    place = seen(v)
    if not place:
        return where(v)
    if v.subject and v.subject != owner.subject:
        return f"'{v.subject}', {place}"
    return place


def where(v: Violation) -> str:
    """A place for a violation that names none: its subject, or its element path."""
    return f"'{v.subject}'" if v.subject else (v.location.path or v.location.file or "")
