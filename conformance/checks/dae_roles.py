"""What each variable is in DAE mode, for the rules on the manifest's ModelStructure.

The dependency rules (:mod:`.manifest_dependencies`) and the list rules (:mod:`.manifest_lists`)
both classify variables by their DAE-mode role and name it in their messages.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from operator import attrgetter

from .context import CheckContext
from ..model.manifest import Manifest, VrRef
from ..model.description import ModelDescription, Variable
from ..model.unknowns import Unknown


@dataclass(frozen=True)
class DaeRoles:
    """What each variable is in DAE mode, by value reference.

    States and derivatives come from the manifest's ContinuousStateDerivative list, or from the
    modelDescription's when the manifest lists none (an absent list is inherited, Q-02).
    """

    algebraic: frozenset[int]
    states: frozenset[int]
    derivatives: frozenset[int]
    residuals: frozenset[int]

    @classmethod
    def of(cls, model: ModelDescription, manifest: Manifest) -> DaeRoles:
        csd = manifest.unknowns("ContinuousStateDerivative") or \
            tuple(model.unknowns("ContinuousStateDerivative"))
        derivatives = _vrs(csd)
        # the states the listed derivatives name, in C (by_vr.get(None) is None)
        states = set(map(attrgetter("derivative"), filter(None, map(model.by_vr.get, derivatives))))
        states.discard(None)
        return cls(algebraic=_vrs(manifest.algebraic), states=frozenset(states),
                   derivatives=derivatives, residuals=_vrs(manifest.residuals))


def _vrs(refs: Iterable[VrRef | Unknown]) -> frozenset[int]:
    """The value references of ``refs`` that are given."""
    vrs = set(map(attrgetter("vr"), refs))
    vrs.discard(None)
    return frozenset(vrs)


def roles_of(ctx: CheckContext) -> DaeRoles:
    """:meth:`DaeRoles.of` the context's model and manifest, computed once per FMU."""
    assert ctx.model is not None and ctx.manifest is not None
    return ctx.memo("dae-roles", lambda: DaeRoles.of(ctx.model, ctx.manifest))


def describe(var: Variable, roles: DaeRoles) -> str:
    """A short noun phrase for what ``var`` is ("a local variable", "a state derivative", ...)."""
    vr = var.vr
    if vr in roles.algebraic:
        return "an algebraic variable"
    if vr in roles.residuals:
        return "a residual"
    if vr in roles.states:
        return "a continuous state"
    if vr in roles.derivatives:
        return "a continuous state derivative"
    if var.variability == "constant":
        return "a constant"
    return {
        "structuralParameter": "a structural parameter",
        "calculatedParameter": "a calculated parameter",
        "parameter": "a parameter",
        "input": "an input",
        "output": "an output",
        "independent": "the independent variable",
    }.get(var.causality, "a local variable")
