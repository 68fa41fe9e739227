"""Static checks: the enable parameter that switches DAE mode on (digest B2, DAE-10).

The manifest points at it with ``<EnableDAEParameter valueReference=..>`` (alpha.1),
``<EnableDAE valueReference=..>`` or a root attribute ``enableDAEModeVariable`` (older drafts, by
value reference or by name); :mod:`conformance.model.manifest` reads all of them into
``Manifest.enables``.
The variable must be a scalar Boolean structural parameter, fixed or tunable, with start false
(MV-40, MV-42, SG-02). Each rule here checks one property, and only once the reference resolves,
so a single fault gives a single finding.
"""
from __future__ import annotations

from operator import attrgetter
from typing import Iterator

from .context import CheckContext
from ..model.drafts.detect import ALPHA1
from ..report.findings import Location, Violation, evidence
from ..model.manifest import VrRef
from ..model.description import Variable
from .model_analysis import analyse

SETTABLE_VARIABILITIES = ("fixed", "tunable")
FALSE_VALUES = ("false", "0")


def _at(ctx: CheckContext, ref: VrRef) -> Location:
    assert ctx.manifest is not None
    return Location(file=ctx.manifest.file, line=ref.line, path=ref.path)


def _at_var(ctx: CheckContext, var: Variable, line: int | None = None) -> Location:
    assert ctx.model is not None
    return Location(file=ctx.model.file, line=line or var.line, path=var.path)


def _lookup(ctx: CheckContext, ref: VrRef) -> Variable | None:
    """The variable an enable reference names, by name (old drafts) or value reference."""
    if ctx.model is None:
        return None
    if ref.name is not None:
        return next((v for v in ctx.model.variables if v.name == ref.name), None)
    return ctx.model.by_vr.get(ref.vr) if ref.vr is not None else None


def _resolved(ctx: CheckContext) -> Iterator[Variable]:
    """Each distinct variable the manifest's enable references resolve to."""
    if ctx.manifest is None or ctx.model is None:
        return
    seen: set[int] = set()
    for ref in ctx.manifest.enables:
        var = _lookup(ctx, ref)
        if var is not None and id(var) not in seen:
            seen.add(id(var))
            yield var


# ---------------------------------------------------------------------------------------------
def enable_parameter_missing(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/DAE-03: the manifest must name the switch; without it the mode is unknowable."""
    m = ctx.manifest
    if m is None or m.enables:
        return
    yield Violation(
        "the manifest names no enable parameter, so an importer cannot switch DAE mode on, nor "
        "tell a DAE-only FMU from one that starts in ODE mode; add <EnableDAEParameter "
        'valueReference=".."/> naming a Boolean structuralParameter with start="false"',
        Location(file=m.file, line=m.root_line, path=f"/{m.root_name}"),
        evidence(draft=m.draft, root=m.root_name))


def enable_parameter_duplicate(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-03: exactly one enable element; with several, which switch counts is undefined."""
    m = ctx.manifest
    if m is None or len(m.enables) < 2:
        return
    first = m.enables[0]
    # a pre-alpha.1 manifest: <EnableDAE> and the root attribute enableDAEModeVariable, or
    # <EnableDAE> repeated
    legacy = not (m.draft == ALPHA1 or ctx.draft == ALPHA1)
    for ref in m.enables[1:]:
        yield Violation(
            "the manifest names a second enable parameter ({subject}); keep exactly one "
            "<EnableDAEParameter>",
            _at(ctx, ref),
            evidence(element=ref.element, value_reference=ref.vr if ref.vr is not None else
                     (ref.name or ref.raw), first_element=first.element,
                     first_value_reference=first.vr if first.vr is not None else
                     (first.name or first.raw), count=len(m.enables)),
            subject=ref.element, part="legacy-element-plus-attribute" if legacy else None)


def enable_parameter_unknown_vr(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/MV-03: the reference must resolve to a variable of modelDescription.xml."""
    if ctx.manifest is None or ctx.model is None:
        return
    for ref in ctx.manifest.enables:
        if _lookup(ctx, ref) is not None:
            continue
        if ref.name is not None:
            yield Violation(
                "the enable parameter is given by the name {subject}, which names no variable "
                "of modelDescription.xml; use <EnableDAEParameter valueReference=\"..\"/>",
                _at(ctx, ref), evidence(element=ref.element, name=ref.name),
                subject=ref.name, part="legacy-name-reference")
        elif ref.raw is not None:
            yield Violation(
                "the enable parameter's valueReference {subject} is not a non-negative integer",
                _at(ctx, ref), evidence(element=ref.element, value_reference=ref.raw),
                subject=ref.raw, part="missing-or-not-integer")
        elif ref.vr is None:
            yield Violation(
                "<{subject}> has no valueReference; point it at the Boolean structural parameter "
                "that switches DAE mode on",
                _at(ctx, ref), evidence(element=ref.element), subject=ref.element,
                part="missing-or-not-integer")
        else:
            yield Violation(
                "the enable parameter's valueReference {subject} names no variable of "
                "modelDescription.xml",
                _at(ctx, ref), evidence(element=ref.element, value_reference=ref.vr),
                subject=str(ref.vr))


def enable_parameter_not_boolean(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/MV-42: the switch is a <Boolean>."""
    for var in _resolved(ctx):
        if var.type != "Boolean":
            yield Violation(
                "enable parameter {subject} is a <%s>, not a <Boolean>" % var.type,
                _at_var(ctx, var), evidence(value_reference=var.vr, type=var.type),
                subject=var.name)


def enable_parameter_not_structural(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/SG-02: only structural parameters may be set in Configuration Mode."""
    for var in _resolved(ctx):
        if var.causality != "structuralParameter":
            yield Violation(
                "enable parameter {subject} must have causality=\"structuralParameter\", so it "
                "can be set in Configuration Mode",
                _at_var(ctx, var), evidence(value_reference=var.vr, causality=var.causality),
                subject=var.name)


def enable_parameter_variability(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/MV-40/MV-10: a structural parameter is fixed or tunable."""
    for var in _resolved(ctx):
        # Judge the variability the switch has once its causality is right: an absent
        # attribute then defaults to fixed, so only a declared wrong value is this rule's fault
        # (a missing structuralParameter causality is enable-parameter-not-structural's).
        variability = var.declared_variability or "fixed"
        if variability not in SETTABLE_VARIABILITIES:
            yield Violation(
                "enable parameter {subject} has a variability that a structural parameter "
                "cannot have; set variability=\"fixed\" or \"tunable\"",
                _at_var(ctx, var),
                evidence(value_reference=var.vr, variability=variability),
                subject=var.name)


def enable_parameter_start_not_false(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/DAE-11: the FMU starts in ODE mode, so start is false."""
    for var in _resolved(ctx):
        if var.type != "Boolean":
            continue  # enable-parameter-not-boolean explains it
        start = var.start.strip() if var.start is not None else None
        if start in FALSE_VALUES:
            continue
        if start is None:
            text = "enable parameter {subject} has no start value; set start=\"false\""
        else:
            text = ("enable parameter {subject} does not start as false, so the FMU would not "
                    "start in ODE mode; set start=\"false\"")
        yield Violation(text, _at_var(ctx, var), evidence(value_reference=var.vr, start=var.start),
                        subject=var.name, part="start-missing" if start is None else None)


def enable_parameter_not_scalar(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-10/MV-40/MV-42: a scalar, and no <Dimension> refers to it."""
    model = ctx.model
    if model is None:
        return
    arrays = list(filter(attrgetter("dimensions"), model.variables)) \
        if analyse(model).has_arrays else []
    for var in _resolved(ctx):
        if var.dimensions:
            yield Violation(
                "enable parameter {subject} is an array; remove its <Dimension> elements",
                _at_var(ctx, var, var.dimensions[0].line),
                evidence(value_reference=var.vr, dimensions=len(var.dimensions)),
                subject=var.name)
            continue
        if var.vr is None:
            continue
        users = [(v, d) for v in arrays for d in v.dimensions if d.vr == var.vr]
        if users:
            user, dim = users[0]
            yield Violation(
                "enable parameter {subject} gives the size of an array <Dimension>; use a "
                "separate UInt64 structural parameter for array sizes",
                _at_var(ctx, user, dim.line),
                evidence(value_reference=var.vr, referenced_by=[v.name for v, _ in users]),
                subject=var.name, part="referenced-by-dimension")


CHECKS = {
    "DAE201": enable_parameter_missing,
    "DAE202": enable_parameter_unknown_vr,
    "DAE203": enable_parameter_not_boolean,
    "DAE204": enable_parameter_not_structural,
    "DAE205": enable_parameter_variability,
    "DAE206": enable_parameter_start_not_false,
    "DAE207": enable_parameter_not_scalar,
    "DAE208": enable_parameter_duplicate,
}
