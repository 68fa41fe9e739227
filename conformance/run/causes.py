"""One defect, one finding: violations that name the same cause are folded into one.

A probe or a check names the defect a violation shows (``Violation.cause``) where several rules
can see one defect: the same derivative entry and deviation in the directional and the adjoint
derivative, in both modes, in Continuous-Time and Initialization Mode; what a legacy draft's
shape implies for the manifest's header beside the migration that names the shape. The folded
finding is the weightiest of them (then the first in code order, then where it was seen, so
that one probe worker or two give the same finding): its message says how many more places
and which, its evidence lists each (``also``: rule, where, message). Violations without a cause
are left alone.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

from ..report.catalogue import RuleSpec
from ..report.findings import Severity, Violation, evidence

Item = tuple[RuleSpec, Violation]


def fold_causes(items: Sequence[Item], severity: Callable[[RuleSpec, str | None], Severity]
                ) -> list[Item]:
    """``items`` with each group of violations of one cause folded into its first."""
    groups: dict[str, list[int]] = {}
    for k, (_, v) in enumerate(items):
        if v.cause:
            groups.setdefault(v.cause, []).append(k)
    out = list(items)
    dropped: set[int] = set()
    for members in groups.values():
        if len(members) < 2:
            continue
        members.sort(key=lambda k: (-severity(items[k][0], items[k][1].part),
                                    items[k][0].code, seen(items[k][1]), items[k][1].text))
        first, rest = members[0], members[1:]
        rule, owner = items[first]
        also = [(items[k][0].code, seen(items[k][1]) or where(items[k][1]), items[k][1])
                for k in rest]
        places = "; ".join(w for _, w, _ in also)
        out[first] = (rule, replace(owner, message=owner.message + (
            f"; the same defect in {len(also)} more place{'s' if len(also) > 1 else ''}: "
            f"{places}"), evidence=owner.evidence + evidence(also=[
                {"rule": code, "where": w, "message": v.text} for code, w, v in also])))
        dropped.update(rest)
    return [item for k, item in enumerate(out) if k not in dropped]


def seen(v: Violation) -> str:
    """Where the violation was seen, as its probe says (``place`` in its evidence), or ''."""
    return str(dict(v.evidence).get("place", ""))


def where(v: Violation) -> str:
    """A place for a violation that names none: its subject, or its element path."""
    return f"'{v.subject}'" if v.subject else (v.location.path or v.location.file or "")
