"""Static checks: the basic rules of the manifest's ``<Residual>`` elements (DAE-31 to DAE-33).

A residual is a value the FMU computes and the importer drives to zero by choosing the algebraic
variables. These rules check that each Residual names a distinct continuous floating-point
variable that the FMU computes, and that there are as many residual elements as algebraic ones,
so that the Jacobian of the residuals with respect to the algebraic variables can be square.
The dependency structure (matching, knowns) is checked by the structure family (DAE420 and up).

Every faulty Residual is reported by exactly one rule: unresolved entries only as unresolved,
repeats only as repeats, a variable that is also an algebraic variable only by the algebraic
rules (algebraic-is-residual and the rest), and otherwise type and variability before role.
Legacy ``<Residual><Formulation/>...</Residual>`` elements arrive here as one Residual each
(see conformance/model/manifest.py), so a higher-index constraint counts once.
"""
from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from itertools import repeat
from operator import attrgetter, is_not

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import FLOAT_TYPES, Variable
from ..model.unknowns import Unknown
from .algebraic import element_count, states_of
from .dae_form import fully_implicit
from .dae_roles import roles_of
from .listing import (
    Listing,
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

# A residual with one of these causalities is a value the importer sets, not one the FMU
# computes. Parameters are left out on purpose: their variability is fixed or tunable (MV-10),
# so residual-not-float-continuous reports them.
SET_BY_IMPORTER = frozenset({"input", "independent"})

NOT_FLOAT_CONTINUOUS = "not-float-continuous"
STATE_OR_INPUT = "state-derivative-or-input"


def _class_problem(type_: str, variability: str, causality: str) -> str | None:
    """The first reason a variable of this type, variability and causality cannot be a
    residual, before its role is known, or None."""
    if type_ not in FLOAT_TYPES or variability != "continuous":
        return NOT_FLOAT_CONTINUOUS
    return STATE_OR_INPUT if causality in SET_BY_IMPORTER else None


def residual_problem(var: Variable, *, states: frozenset[int]) -> str | None:
    """The first reason ``var`` cannot be a residual, or None if it can."""
    problem = _class_problem(var.type, var.variability, var.causality)
    if problem is None and (var.vr in states or var.derivative is not None):
        return STATE_OR_INPUT
    return problem


def _problems(variables: Sequence[Variable], states: frozenset[int]
              ) -> list[str | None] | None:
    """:func:`residual_problem` of each variable, or None when none has one: decided per
    distinct (type, variability, causality) and by set tests, in C, for the usual clean list."""
    classes = set(map(attrgetter("type", "variability", "causality"), variables))
    if (not any(_class_problem(*c) for c in classes)
            and states.isdisjoint(map(attrgetter("vr"), variables))
            and not any(map(is_not, map(attrgetter("derivative"), variables), repeat(None)))):
        return None
    return [residual_problem(v, states=states) for v in variables]


def _classified(ctx: CheckContext, wanted: str) -> Iterator[tuple[Unknown, Variable]]:
    model, manifest = ctx.model, ctx.manifest
    if model is None or manifest is None:
        return

    def listed() -> Listing:
        algebraic = resolved_vrs(resolution(ctx, "algebraic"))  # the algebraic rules' to explain
        entries, variables = first_listings(resolution(ctx, "residuals"))
        if algebraic.isdisjoint(map(attrgetter("vr"), entries)):
            return entries, variables  # the usual case, decided in C
        kept = [(res, var) for res, var in zip(entries, variables) if res.vr not in algebraic]
        return [res for res, _ in kept], [var for _, var in kept]

    def classifier() -> Problems:
        states = states_of(ctx)
        return lambda variables: _problems(variables, states)

    yield from classified(ctx, "residual-classes", wanted, listed, classifier)


def _at(res: Unknown) -> Location:
    return Location(file=res.file, line=res.line, path=res.path)


def residual_unknown_vr(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-31: every Residual names an existing variable by an integer value reference."""
    if ctx.model is None or ctx.manifest is None:
        return
    for res in ctx.manifest.residuals:
        if res.vr is None:
            yield Violation(
                "a Residual has no valueReference, or one that is not an unsigned integer; give "
                "the valueReference of the variable that holds the residual",
                _at(res), evidence(value_reference=None, reason="missing or not an integer"),
                part="missing-or-not-integer")
        elif res.vr not in ctx.model.by_vr:
            yield Violation(
                "Residual valueReference {subject} names no variable of modelDescription.xml; "
                "use the valueReference of the Float64 variable that holds the residual",
                _at(res), evidence(value_reference=res.vr, reason="no such variable"),
                subject=str(res.vr))


def residual_duplicate(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-31: no two Residual elements name the same variable."""
    if ctx.model is None or ctx.manifest is None:
        return
    for res, first, var in repeats(resolution(ctx, "residuals")):
        yield Violation(
            "residual {subject} is listed in more than one Residual element; list each "
            "residual once",
            _at(res), evidence(value_reference=res.vr, first_listed_at_line=first.line),
            subject=var.name)


def residual_not_float_continuous(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-32: a residual is a Float32/Float64 variable with variability continuous."""
    for res, var in _classified(ctx, NOT_FLOAT_CONTINUOUS):
        yield Violation(
            "residual {subject} is not a continuous Float32 or Float64 variable; the importer "
            "reads residuals with fmi3GetFloat64/32 at every solver iteration, so declare it "
            "as a continuous floating-point variable",
            Location(file=ctx.model.file if ctx.model else None, line=var.line, path=var.path),
            evidence(facts(var, res)), subject=var.name)


def residual_is_state_derivative_or_input(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-32: a residual is not a state, a state derivative, an input or the independent one.

    The rule's own case is an input, the independent variable or a state of DAE mode
    (:class:`.dae_roles.DaeRoles`: the manifest's ContinuousStateDerivative list, or
    modelDescription's when it lists none). Otherwise a variable with a derivative attribute is
    the part state-derivative, and a state of ODE mode only the part ode-only-state."""
    for res, var in _classified(ctx, STATE_OR_INPUT):
        if var.causality in SET_BY_IMPORTER:
            role = var.causality
        else:
            role = "state derivative" if var.derivative is not None else "continuous state"
        if var.causality in SET_BY_IMPORTER or var.vr in roles_of(ctx).states:
            yield _state_derivative_or_input(res, var, role, part=None)
        elif var.derivative is not None:
            yield _state_derivative_or_input(res, var, role, part="state-derivative")
        else:  # a state only by modelDescription's list, which the manifest's replaces
            yield _state_derivative_or_input(res, var, role, part="ode-only-state")


def _state_derivative_or_input(res: Unknown, var: Variable, role: str, *,
                               part: str | None) -> Violation:
    """The finding of :func:`residual_is_state_derivative_or_input` for ``res``."""
    return Violation(
        "residual {subject} is a continuous state, a state derivative, an input or the "
        "independent variable; a residual must be a local or output variable that the FMU "
        "computes from the algebraic variables",
        _at(res), evidence(facts(var, res), role=role), subject=var.name, part=part)


def residual_count_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-33: the residuals and the algebraic variables have the same number of elements."""
    if ctx.model is None or ctx.manifest is None:
        return
    model, manifest = ctx.model, ctx.manifest
    sides = []
    for name in ("algebraic", "residuals"):
        listed = resolution(ctx, name)
        variables = listed.variables
        if not (listed.complete and listed.distinct):
            # An unresolved entry has no size, and with a repeat it is unclear whether an
            # entry is extra or stands for a missing one: the unknown-vr and duplicate
            # rules explain those, and the count is judged once they are fixed.
            return
        if not analyse(model).has_arrays:
            sides.append((len(variables), variables))  # all scalars, the usual case
            continue
        sizes = [element_count(model, v) for v in variables]
        known = [s for s in sizes if s is not None]
        if len(known) != len(sizes):
            log.debug("residual-count-mismatch skipped: an array size is not known statically")
            return
        sides.append((sum(known), variables))
    (n_alg, alg_vars), (n_res, res_vars) = sides
    if n_alg == n_res or fully_implicit(model, manifest) is not None:
        return  # the fully implicit form is fully-implicit-form's finding
    alg_names, res_names = [v.name for v in alg_vars], [v.name for v in res_vars]
    if manifest.algebraic_line is not None:
        where = Location(file=manifest.file, line=manifest.algebraic_line,
                         path=f"/{manifest.root_name}/AlgebraicVariables")
    else:
        first = manifest.residuals[0]
        where = Location(file=manifest.file, line=first.line, path=first.path)
    yield Violation(
        f"the manifest has {n_res} residual element(s) for {n_alg} algebraic variable "
        "element(s); the Jacobian of the residuals with respect to the algebraic variables "
        "cannot be square, so list one residual per algebraic variable",
        where, evidence(residual_count=n_res, algebraic_count=n_alg, residuals=res_names,
                        algebraic_variables=alg_names))


CHECKS: dict[str, Check] = {
    "DAE401": residual_unknown_vr,
    "DAE402": residual_duplicate,
    "DAE403": residual_not_float_continuous,
    "DAE404": residual_is_state_derivative_or_input,
    "DAE405": residual_count_mismatch,
}
