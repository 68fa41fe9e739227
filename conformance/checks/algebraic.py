"""Static checks: the manifest's ``<AlgebraicVariables>`` (DAE-20, DAE-21, DAE-22).

An algebraic variable is an unknown the importer solves for: it calls ``fmi3SetFloat64`` on it
in Continuous-Time Mode and iterates until every residual is zero. Each listed entry is therefore
checked for what would stop that from working.

Every faulty entry is reported by exactly one rule. An entry that does not resolve is reported
only as unresolved; a repeated entry only as repeated (at the repeat); each distinct variable is
then classified by the first problem found in a fixed order, type, causality, variability, role
(:func:`algebraic_problem`), so a Boolean parameter is "not a float" and not also "a parameter".
The helpers :func:`continuous_states` and :func:`element_count` are shared with the residual rules.
"""
from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from itertools import repeat
from operator import attrgetter, is_not

from .context import Check, CheckContext
from .dae_roles import roles_of
from ..report.findings import Location, Violation, evidence
from ..model.manifest import Manifest, VrRef
from ..model.description import FLOAT_TYPES, ModelDescription, Variable
from ..model.unknowns import parse_uint
from .listing import (
    Problems,
    classified,
    facts,
    first_listings,
    repeats,
    resolution,
    resolved_vrs,
)
from .model_analysis import analyse

log = logging.getLogger(__name__)

# Causalities of knowns: values the environment provides (inputs, parameters, time), never
# unknowns an importer may solve for. Parameter causalities all have variability fixed or tunable
# (MV-10), so they are reported here and not as "not continuous".
KNOWN_CAUSALITIES = frozenset({"input", "parameter", "structuralParameter",
                               "calculatedParameter", "independent"})
# Of these, the ones that are not p of alpha.1 §2.2 (part structural-or-calculated-parameter).
NOT_P_PARAMETERS = frozenset({"structuralParameter", "calculatedParameter"})

# The classification order; each rule fires only for its own class.
NOT_FLOAT = "not-float"
KNOWN = "input-or-parameter"
NOT_CONTINUOUS = "not-continuous"
STATE = "state-or-derivative"
RESIDUAL = "residual"


def continuous_states(model: ModelDescription, manifest: Manifest | None) -> frozenset[int]:
    """Value references of the continuous states.

    A state is the variable named by the ``derivative`` attribute of a variable listed as
    ``ContinuousStateDerivative``, in modelDescription.xml (ODE mode) or in the manifest (DAE
    mode): a variable that is a state in either mode cannot be an algebraic variable or residual.
    """
    unknowns = list(analyse(model).unknowns("ContinuousStateDerivative"))
    if manifest is not None:
        unknowns.extend(manifest.unknowns("ContinuousStateDerivative"))
    # one pass in C: the listed derivatives (by_vr.get(None) is None), then what they name
    derivatives = filter(None, map(model.by_vr.get, map(attrgetter("vr"), unknowns)))
    states = set(map(attrgetter("derivative"), derivatives))
    states.discard(None)
    return frozenset(states)


def states_of(ctx: CheckContext) -> frozenset[int]:
    """:func:`continuous_states` of the context's model and manifest, computed once per FMU."""
    assert ctx.model is not None
    return ctx.memo("continuous-states", lambda: continuous_states(ctx.model, ctx.manifest))


def element_count(model: ModelDescription, var: Variable) -> int | None:
    """Number of scalar elements of ``var`` (1 for a scalar), or None when a size is unknown.

    A ``<Dimension>`` gives its size by ``start`` or by the ``start`` of the UInt64 variable its
    ``valueReference`` names (the initial size, MV-41).
    """
    count = 1
    for dim in var.dimensions:
        size = parse_uint(dim.start)
        if size is None and dim.vr is not None:
            target = model.by_vr.get(dim.vr)
            size = parse_uint(target.start) if target is not None else None
        if size is None:
            return None
        count *= size
    return count


def _class_problem(type_: str, causality: str, variability: str) -> str | None:
    """The first reason a variable of this type, causality and variability cannot be an
    algebraic variable, or None."""
    if type_ not in FLOAT_TYPES:
        return NOT_FLOAT
    if causality in KNOWN_CAUSALITIES:
        return KNOWN
    if variability != "continuous":
        return NOT_CONTINUOUS
    return None


def algebraic_problem(var: Variable, *, states: frozenset[int],
                      residuals: frozenset[int]) -> str | None:
    """The first reason ``var`` cannot be an algebraic variable, or None if it can."""
    problem = _class_problem(var.type, var.causality, var.variability)
    if problem is not None:
        return problem
    if var.vr in states or var.derivative is not None:
        return STATE
    if var.vr in residuals:
        return RESIDUAL
    return None


def _problems(variables: Sequence[Variable], states: frozenset[int],
              residuals: frozenset[int]) -> list[str | None] | None:
    """:func:`algebraic_problem` of each variable, or None when none has one: decided per
    distinct (type, causality, variability) and by set tests, in C, for the usual clean list."""
    classes = set(map(attrgetter("type", "causality", "variability"), variables))
    vrs = set(map(attrgetter("vr"), variables))
    if (not any(_class_problem(*c) for c in classes) and vrs.isdisjoint(states)
            and vrs.isdisjoint(residuals)
            and not any(map(is_not, map(attrgetter("derivative"), variables), repeat(None)))):
        return None
    return [algebraic_problem(v, states=states, residuals=residuals) for v in variables]


def _classified(ctx: CheckContext, wanted: str) -> Iterator[tuple[VrRef, Variable]]:
    model, manifest = ctx.model, ctx.manifest
    if model is None or manifest is None:
        return

    def classifier() -> Problems:
        states = states_of(ctx)
        residuals = resolved_vrs(resolution(ctx, "residuals"))
        return lambda variables: _problems(variables, states, residuals)

    yield from classified(ctx, "algebraic-classes", wanted,
                          lambda: first_listings(resolution(ctx, "algebraic")), classifier)


def _at_ref(ctx: CheckContext, ref: VrRef) -> Location:
    return Location(file=ctx.manifest.file if ctx.manifest else None, line=ref.line,
                    path=ref.path)


def _at_var(ctx: CheckContext, var: Variable) -> Location:
    return Location(file=ctx.model.file if ctx.model else None, line=var.line, path=var.path)


def algebraic_unknown_vr(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-20: every AlgebraicVariable names an existing variable by an integer value reference."""
    if ctx.model is None or ctx.manifest is None:
        return
    for ref in ctx.manifest.algebraic:
        if ref.vr is not None and ref.vr in ctx.model.by_vr:
            continue
        if ref.vr is None and ref.raw is None:
            yield Violation(
                "an AlgebraicVariable has no valueReference attribute; give the valueReference "
                "of the variable the importer solves for",
                _at_ref(ctx, ref), evidence(value_reference=None, reason="missing"),
                part="missing-or-not-integer")
            continue
        text = ref.raw if ref.vr is None else str(ref.vr)
        reason = "not an unsigned integer" if ref.vr is None else "no such variable"
        yield Violation(
            "AlgebraicVariable valueReference {subject} names no variable of "
            "modelDescription.xml; use the valueReference of an existing Float64 variable",
            _at_ref(ctx, ref), evidence(value_reference=text, reason=reason), subject=text,
            part="missing-or-not-integer" if ref.vr is None else None)


def algebraic_duplicate(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-20 (derived): no algebraic variable is listed twice."""
    if ctx.model is None or ctx.manifest is None:
        return
    for ref, first, var in repeats(resolution(ctx, "algebraic")):
        yield Violation(
            "algebraic variable {subject} is listed more than once in <AlgebraicVariables>; "
            "list each algebraic variable once",
            _at_ref(ctx, ref), evidence(value_reference=ref.vr, first_listed_at_line=first.line),
            subject=var.name)


def algebraic_not_float(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-21: an algebraic variable is a Float32 or Float64."""
    for ref, var in _classified(ctx, NOT_FLOAT):
        yield Violation(
            "algebraic variable {subject} is not a Float32 or Float64; the importer sets "
            "algebraic variables with fmi3SetFloat64/32 and iterates on them, so list only "
            "floating-point variables",
            _at_var(ctx, var), evidence(facts(var, ref)), subject=var.name)


def algebraic_not_continuous(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-21: an algebraic variable has variability continuous."""
    for ref, var in _classified(ctx, NOT_CONTINUOUS):
        yield Violation(
            "algebraic variable {subject} is not continuous; the importer changes it at every "
            "solver iteration in Continuous-Time Mode, so declare variability=\"continuous\" "
            "or remove it from <AlgebraicVariables>",
            _at_var(ctx, var), evidence(facts(var, ref)), subject=var.name)


def algebraic_is_state_or_derivative(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-21: an algebraic variable is neither a continuous state nor a derivative.

    The rule's own case is a state or derivative of DAE mode (:class:`.dae_roles.DaeRoles`:
    the manifest's ContinuousStateDerivative list, or modelDescription's when it lists none);
    a state of ODE mode only, or a derivative only by its derivative attribute, is the part
    not-a-dae-mode-state-or-derivative."""
    for ref, var in _classified(ctx, STATE):
        role = "state derivative" if var.derivative is not None else "continuous state"
        roles = roles_of(ctx)
        dae_mode = var.vr in roles.states or (var.derivative is not None
                                              and var.vr in roles.derivatives)
        yield Violation(
            "algebraic variable {subject} is a continuous state or a state derivative, which "
            "the integrator owns; list only variables that the residuals determine",
            _at_ref(ctx, ref), evidence(facts(var, ref), role=role,
                                        derivative_of=var.derivative), subject=var.name,
            part="not-a-dae-mode-state-or-derivative" if not dae_mode else None)


def algebraic_is_input_or_parameter(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-21: an algebraic variable is not an input, a parameter or the independent variable."""
    for ref, var in _classified(ctx, KNOWN):
        yield Violation(
            "algebraic variable {subject} is an input, a parameter or the independent "
            "variable, a known that the environment provides; list only local or output "
            "variables that the residuals determine",
            _at_ref(ctx, ref), evidence(facts(var, ref)), subject=var.name,
            part="structural-or-calculated-parameter" if var.causality in NOT_P_PARAMETERS
            else None)


def algebraic_is_residual(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-21: an algebraic variable is not also a residual."""
    for ref, var in _classified(ctx, RESIDUAL):
        yield Violation(
            "algebraic variable {subject} is also listed as a Residual; an algebraic variable "
            "is an unknown the importer sets and a residual a value the FMU computes, so use "
            "two different variables",
            _at_ref(ctx, ref), evidence(facts(var, ref)), subject=var.name)


CHECKS: dict[str, Check] = {
    "DAE301": algebraic_unknown_vr,
    "DAE302": algebraic_duplicate,
    "DAE303": algebraic_not_float,
    "DAE304": algebraic_not_continuous,
    "DAE305": algebraic_is_state_or_derivative,
    "DAE306": algebraic_is_input_or_parameter,
    "DAE307": algebraic_is_residual,
}
