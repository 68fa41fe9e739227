"""Static checks: the manifest's Output, state derivative and InitialUnknown lists (DAE424-DAE426).

In DAE mode the manifest ``<ModelStructure>`` replaces the modelDescription's (DAE-30). These
rules check its Output, ContinuousStateDerivative and InitialUnknown lists against the variables
(MS-02, MS-03, MS-05, D-10, D-16, Q-02, Q-06, Q-09); its dependencies are
:mod:`.manifest_dependencies`'s. An element that names no variable is reported by the list rule
of its kind, and a Residual that names none by residual-unknown-vr.
"""
from __future__ import annotations

from collections.abc import Iterator, Sequence
from operator import attrgetter

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import ModelDescription
from ..model.manifest import Manifest
from ..model.unknowns import Unknown
from .dae_roles import describe, roles_of
from .model_analysis import analyse


def _unresolved(u: Unknown, *, part: str | None = None) -> Violation:
    """A list element whose own valueReference names no variable (``part``: the catalogue part
    this is for the calling rule, None for its own case)."""
    return Violation(
        f"<{u.kind}> {{subject}} names no variable in modelDescription.xml",
        _loc(u), evidence(element=u.kind, value_reference=u.vr),
        subject=f"valueReference {u.vr}" if u.vr is not None else u.path, part=part)


def _loc(u: Unknown) -> Location:
    return Location(file=u.file, line=u.line, path=u.path)


# --- initial-unknown-not-allowed -------------------------------------------------------------

def initial_unknown_not_allowed(ctx: CheckContext) -> Iterator[Violation]:
    """Manifest InitialUnknowns are core ones or algebraic variables (MS-05, D-10, Q-06)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    roles = roles_of(ctx)
    event_indicators: frozenset[int] | None = None  # of DAE mode; computed at the first finding
    for u in manifest.unknowns("InitialUnknown"):
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u, part="unresolved")
            continue
        if var.vr in roles.algebraic:
            continue
        if var.vr in roles.residuals:
            not_exact_output = (var.causality == "output" and var.clocks is None
                                and var.initial in ("approx", "calculated"))
            yield Violation(
                "residual {subject} is listed as <InitialUnknown>; list the algebraic variable "
                "it determines instead, not the residual",
                _loc(u), evidence(element=u.kind, is_residual=True), subject=var.name,
                part="output-residual" if not_exact_output else None)
            continue
        not_exact = var.initial in ("approx", "calculated")
        if (var.causality == "calculatedParameter" or var.clocks is not None
                or (not_exact and var.causality == "output")
                or (not_exact and (var.vr in roles.states or var.vr in roles.derivatives))):
            continue
        what = describe(var, roles)
        if var.initial is not None:
            what += f' with initial="{var.initial}"'
        if event_indicators is None:
            event_indicators = _event_indicators(model, manifest)
        yield Violation(
            f"{{subject}} is listed as <InitialUnknown> but is {what}; initial unknowns are "
            "outputs, continuous states and state derivatives with initial=\"approx\" or "
            "\"calculated\", calculated parameters, and algebraic variables",
            _loc(u), evidence(element=u.kind, variable_is=what, causality=var.causality,
                              initial=var.initial), subject=var.name,
            part="event-indicator" if var.vr in event_indicators else None)


def _event_indicators(model: ModelDescription, manifest: Manifest) -> frozenset[int]:
    """Value references of the event indicators of DAE mode: the manifest's EventIndicator
    list, or modelDescription's when the manifest lists none (as :class:`.dae_roles.DaeRoles`
    takes the state derivatives)."""
    listed = manifest.unknowns("EventIndicator") or analyse(model).unknowns("EventIndicator")
    vrs = set(map(attrgetter("vr"), listed))
    vrs.discard(None)
    return frozenset(vrs)


# --- state-derivative-mismatch ---------------------------------------------------------------

def state_derivative_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """The manifest lists the state derivatives of modelDescription.xml (DAE-15, MV-31, Q-09)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    listed = manifest.unknowns("ContinuousStateDerivative")
    if not listed:
        return  # an absent list is inherited from modelDescription.xml
    if _same_state_derivatives(model, listed):
        return
    ours: dict[int, Unknown] = {}
    for u in listed:
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u, part="unresolved")
            continue
        if var.derivative is None:
            yield Violation(
                "<ContinuousStateDerivative> {subject} has no derivative attribute, so it names "
                "no state; add derivative=\"<valueReference of the state>\" to the variable",
                _loc(u), evidence(element=u.kind, value_reference=var.vr), subject=var.name,
                part="no-derivative-attribute")
            continue
        ours.setdefault(var.vr, u)  # type: ignore[arg-type]
    theirs: dict[int, Unknown] = {}
    for u in analyse(model).unknowns("ContinuousStateDerivative"):
        if u.vr is not None and u.vr in model.by_vr:
            theirs.setdefault(u.vr, u)
    for vr, u in ours.items():
        if vr not in theirs:
            yield Violation(
                "{subject} is a <ContinuousStateDerivative> in the manifest but not in "
                "modelDescription.xml, so DAE and ODE mode have different state derivative "
                "vectors",
                _loc(u), evidence(value_reference=vr, in_manifest=True,
                                  in_model_description=False), subject=model.by_vr[vr].name)
    for vr, u in theirs.items():
        if vr not in ours:
            yield Violation(
                "{subject} is a <ContinuousStateDerivative> in modelDescription.xml but not in "
                "the manifest, so DAE and ODE mode have different state derivative vectors",
                _loc(u), evidence(value_reference=vr, in_manifest=False,
                                  in_model_description=True), subject=model.by_vr[vr].name)


def _same_state_derivatives(model: ModelDescription, listed: Sequence[Unknown]) -> bool:
    """Whether :func:`state_derivative_mismatch` has nothing to say, decided in C for the usual
    case: every listed one resolves and has a derivative attribute, and both documents list
    the same variables."""
    ours = list(map(attrgetter("vr"), listed))
    variables = list(map(model.by_vr.get, ours))  # by_vr.get(None) is None
    if not all(variables) or None in map(attrgetter("derivative"), variables):
        return False
    theirs = map(attrgetter("vr"), analyse(model).unknowns("ContinuousStateDerivative"))
    return set(ours) == set(filter(model.by_vr.__contains__, theirs))


# --- output-set-mismatch ---------------------------------------------------------------------

def output_set_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """A manifest Output list holds exactly the causality="output" variables (MS-02, D-16)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    listed = manifest.unknowns("Output")
    if not listed:
        return  # an absent Output list is inherited from modelDescription.xml
    outputs = {v.vr: v for v in analyse(model).by_causality["output"] if v.vr is not None}
    roles = roles_of(ctx)
    seen = set()
    for u in listed:
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u)
            continue
        seen.add(var.vr)
        if var.vr not in outputs:
            yield Violation(
                "<Output> {subject} is %s, not a causality=\"output\" variable; list only "
                "outputs" % describe(var, roles),
                _loc(u), evidence(element="Output", causality=var.causality), subject=var.name)
    anchor = listed[-1]
    for vr, var in outputs.items():
        if vr not in seen:
            yield Violation(
                "output {subject} is missing from the manifest's <Output> list; in DAE mode the "
                "manifest list replaces modelDescription.xml's, so add an <Output> for it",
                Location(file=anchor.file, line=anchor.line, path=anchor.path),
                evidence(value_reference=vr, variable_line=var.line), subject=var.name)


CHECKS: dict[str, Check] = {
    "DAE424": initial_unknown_not_allowed,
    "DAE425": state_derivative_mismatch,
    "DAE426": output_set_mismatch,
}
