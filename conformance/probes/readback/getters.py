"""What an importer reads must read back right: the vector getters against the variables they
stand for, the nominals of the states, and values read on their own after the point changed.

    state-vectors-inconsistent    fmi3GetContinuousStateDerivatives differs from fmi3GetFloat64
                                  of the der() variables, or fmi3GetContinuousStates from the
                                  states, in the order of <ContinuousStateDerivative> (MS-03)
    state-nominals-invalid        fmi3GetNominalsOfContinuousStates is refused, gives a value
                                  that is not finite and > 0, or gives other values depending
                                  on what the caller's buffer held (MS-03, FMI 3.0.2 §3.2.3)
    state-nominal-not-xml         a nominal differs from the state's XML nominal although no
                                  fmi3UpdateDiscreteStates said nominalsOfContinuousStatesChanged
    stale-values-read             outputs, derivatives, residuals, algebraic variables or event
                                  indicators read on their own after a change of point give the
                                  previous point's values (FMI 3.0.2 §3.2.1)

Each runs in both modes, on the probe stage's instances in Continuous-Time Mode. A call that
fails is another rule's finding (evaluation-failed, event-indicators-failed, enable-handshake):
the instance is renewed and the comparison goes on without it. Tolerances are catalogue options.
"""
from __future__ import annotations

import math
from typing import Any, Iterator, Sequence

import numpy as np

from ...report import causes
from ...report.findings import Violation, evidence
from ...runtime.instance import Instance, PointNotSet
from ...runtime.layout import Layout
from ..instruments.api import FmiError, Point, ProbeContext
from ..instruments.common import close, dae_of, layout_of, renew, root_location, var_location

MODES = ("dae", "ode")


def _instances(ctx: ProbeContext) -> Iterator[tuple[str, Instance]]:
    """(mode, instance) for each mode that could be started; ProbeSkipped when none could."""
    if ctx.dae is None and ctx.ode is None:
        dae_of(ctx)
    for mode in MODES:
        inst = getattr(ctx, mode)
        if inst is not None and getattr(inst, "failure", None) is not None:
            inst = renew(ctx, mode)
        if inst is not None:
            yield mode, inst


def _mode(mode: str) -> str:
    return f"{mode.upper()} mode"


# ---------------------------------------------------------------- state-vectors-inconsistent


def state_vectors_inconsistent(ctx: ProbeContext, *, rtol: float, atol: float
                               ) -> Iterator[Violation]:
    """MS-03: at every sampled point, in each mode, fmi3GetContinuousStateDerivatives[i] equals
    fmi3GetFloat64 of the i-th <ContinuousStateDerivative> and fmi3GetContinuousStates[i] the
    state it names. One finding per variable and getter (the first point and mode)."""
    layout = layout_of(ctx)
    reported: set[tuple[str, int]] = set()
    # in DAE mode the manifest's <ContinuousStateDerivative> list, when it has one, orders
    # the vectors (alpha.1 re-defines the ModelStructure), else the modelDescription's
    manifest_order = bool(ctx.manifest and any(ctx.manifest.unknowns("ContinuousStateDerivative")))
    for mode, inst in _instances(ctx):
        states, ders = layout.states_for(mode), layout.derivatives_for(mode)
        by_manifest = mode == "dae" and manifest_order
        if not states:
            continue
        for point in ctx.points:
            try:
                inst.set_point(point)
                pairs = (("fmi3GetContinuousStateDerivatives", ders, inst.get_derivatives),
                         ("fmi3GetContinuousStates", states, inst.get_states))
                read = [(fname, vrs, getter(len(vrs)), inst.get_float64(list(vrs)))
                        for fname, vrs, getter in pairs]
            except FmiError:
                inst = renew(ctx, mode)  # another rule's finding; go on with a fresh instance
                if inst is None:
                    break
                continue
            for fname, vrs, vector, scalars in read:
                yield from _vector_against(
                    ctx, layout, mode, point, fname, vrs, vector, scalars, reported, rtol=rtol,
                    atol=atol, part="dae-mode-order" if by_manifest else None)


def _vector_against(ctx: ProbeContext, layout: Layout, mode: str, point: Point, fname: str,
                    vrs: Sequence[int], vector: np.ndarray, scalars: np.ndarray,
                    reported: set[tuple[str, int]], *, rtol: float, atol: float,
                    part: str | None = None) -> Iterator[Violation]:
    for i, (vr, x, y) in enumerate(zip(vrs, vector, scalars)):
        x, y = float(x), float(y)
        if (fname, vr) in reported or not (math.isfinite(x) and math.isfinite(y)):
            continue
        if close(x, y, rtol=rtol, atol=atol, scale=layout.scale(vr)):
            continue
        reported.add((fname, vr))
        yield Violation(
            f"{fname} gives {x:.17g} as element {i}, fmi3GetFloat64 of {{subject}}, the "
            f"variable that element stands for, {y:.17g} at point {point.label} "
            f"({_mode(mode)}): the vector and the variable disagree", var_location(ctx, vr),
            evidence(getter=fname, index=i, vector=x, get_float64=y, point=point.label,
                     t=point.t, mode=_mode(mode), rtol=rtol, atol=atol,
                     tolerance=atol + rtol * max(layout.scale(vr), abs(x), abs(y)),
                     scale="nominal or magnitude of the variable"),
            layout.name(vr), part=part, cause=causes.through(layout.name(vr)))


# ------------------------------------------------------------------- state-nominals-invalid


FILLS = (math.nan, 1e300)   # what the caller's buffer holds before the two calls


def _nominals(ctx: ProbeContext) -> Iterator[tuple[str, Instance, Sequence[int], Any]]:
    """(mode, instance, states, [values read into each fill] or the FmiError) per mode."""
    layout = layout_of(ctx)
    for mode, inst in _instances(ctx):
        states = layout.states_for(mode)
        if not states:
            continue
        try:
            yield mode, inst, states, [inst.get_nominals(len(states), fill) for fill in FILLS]
        except FmiError as exc:
            yield mode, inst, states, exc
            renew(ctx, mode)


def state_nominals_invalid(ctx: ProbeContext) -> Iterator[Violation]:
    """FMI 3.0.2 §3.2.3: fmi3GetNominalsOfContinuousStates, allowed in Continuous-Time Mode,
    returns for each state a nominal that is finite and > 0 ("it is required that
    nominals[i] > 0.0"), whatever the caller's buffer held: it is called into a buffer of NaN
    and into one of 1e300, in each mode."""
    layout = layout_of(ctx)
    for mode, _, states, got in _nominals(ctx):
        if isinstance(got, FmiError):
            yield Violation(
                f"fmi3GetNominalsOfContinuousStates returns {got.status} in Continuous-Time "
                f"Mode ({_mode(mode)}), where FMI 3.0 allows it", root_location(ctx),
                evidence(call=got.call, status=got.status, log=list(got.log[:10]),
                         mode=_mode(mode), state="Continuous-Time Mode", place=_mode(mode)),
                subject="fmi3GetNominalsOfContinuousStates", part="refused",
                cause=causes.FAULT.format("refuses fmi3GetNominalsOfContinuousStates"))
            continue
        first, second = got
        for i, vr in enumerate(states):
            a, b = float(first[i]), float(second[i])
            if a == b and math.isfinite(a) and a > 0:
                continue
            unwritten = a != b and not (math.isnan(a) and math.isnan(b))
            why = ("depends on what the caller's buffer held (the FMU does not write it)"
                   if unwritten else "is not finite" if not math.isfinite(a) else "is not > 0")
            if unwritten:
                yield _nominal_invalid(ctx, layout, mode, i, vr, a, b, why, part="unwritten")
            elif a == math.inf:  # > 0.0, all FMI requires (NaN and -Inf are not)
                yield _nominal_invalid(ctx, layout, mode, i, vr, a, b, why, part="infinite")
            else:
                yield _nominal_invalid(ctx, layout, mode, i, vr, a, b, why, part=None)


def _nominal_invalid(ctx: ProbeContext, layout: Layout, mode: str, i: int, vr: int, a: float,
                     b: float, why: str, *, part: str | None) -> Violation:
    return Violation(
        f"fmi3GetNominalsOfContinuousStates gives {a!r} for {{subject}} (element {i}) "
        f"in {_mode(mode)}: the nominal {why}; FMI 3.0 requires nominals[i] > 0.0",
        var_location(ctx, vr),
        evidence(index=i, into_nan=a, into_1e300=b, fills=["nan", 1e300],
                 mode=_mode(mode), state="Continuous-Time Mode", place=_mode(mode)),
        layout.name(vr), part=part,
        cause=causes.FAULT.format(f"gives no valid nominal of '{layout.name(vr)}'"))


def state_nominal_not_xml(ctx: ProbeContext, *, rtol: float) -> Iterator[Violation]:
    """Derived from FMI 3.0.2 §2.4.7.5 (nominal) and §3.2.3: until an fmi3UpdateDiscreteStates
    says nominalsOfContinuousStatesChanged, each state's nominal from
    fmi3GetNominalsOfContinuousStates equals the nominal its XML declares."""
    layout = layout_of(ctx)
    for mode, inst, states, got in _nominals(ctx):
        if isinstance(got, FmiError) or (inst.discrete and inst.discrete.nominals_changed):
            continue
        for i, vr in enumerate(states):
            declared = _declared_nominal(ctx, vr)
            value = float(got[0][i])
            if declared is None or not (math.isfinite(value) and value > 0):
                continue  # no XML nominal to hold, or state-nominals-invalid's finding
            if abs(value - declared) <= rtol * max(abs(value), declared):
                continue
            yield Violation(
                f"fmi3GetNominalsOfContinuousStates gives {value!r} for {{subject}} (element "
                f"{i}) in {_mode(mode)}, its XML nominal is {declared!r}, and no "
                "fmi3UpdateDiscreteStates said nominalsOfContinuousStatesChanged: an importer "
                "scales its error control with one or the other", var_location(ctx, vr),
                evidence(index=i, nominal=value, xml_nominal=declared, mode=_mode(mode),
                         rtol=rtol, state="Continuous-Time Mode", place=_mode(mode)),
                layout.name(vr), cause=causes.FAULT.format(
                    f"gives a nominal of '{layout.name(vr)}' its XML does not"))


def _declared_nominal(ctx: ProbeContext, vr: int) -> float | None:
    var = ctx.model.by_vr.get(vr)
    try:
        value = float(var.nominal) if var is not None and var.nominal is not None else None
    except ValueError:
        return None
    return value if value is not None and math.isfinite(value) and value > 0 else None


# ------------------------------------------------------------------------ stale-values-read


def _groups(layout: Layout, mode: str) -> list[tuple[str, tuple[int, ...]]]:
    groups = [("outputs", layout.outputs_for(mode)), ("derivatives", layout.derivatives_for(mode)),
              ("residuals", layout.residuals if mode == "dae" else ()),
              ("algebraic variables", layout.algebraic),
              ("event indicators", layout.event_indicators_for(mode))]
    return [(name, tuple(vrs)) for name, vrs in groups if vrs]


def _setters(layout: Layout, mode: str, a: Point, b: Point) -> list[tuple[str, Point, Any]]:
    """(the call, the point it leads to from ``a``, the call itself) for each part of the point
    that differs between ``a`` and ``b``, each on its own: time, the states, the values
    fmi3SetFloat64 sets (algebraic variables in DAE mode, inputs); last, the whole of ``b``."""
    states = layout.states_for(mode)
    knowns = [vr for vr in (*(layout.algebraic if mode == "dae" else ()), *layout.inputs)
              if vr in b.values and b.values[vr] != a.values.get(vr)]
    out: list[tuple[str, Point, Any]] = []
    if b.t != a.t:
        out.append(("fmi3SetTime", Point(b.t, a.values, f"{a.label} at the time of {b.label}"),
                    lambda inst: inst.set_time(b.t)))
    if states and all(vr in b.values for vr in states) and \
            any(b.values[vr] != a.values.get(vr) for vr in states):
        moved = {**a.values, **{vr: b.values[vr] for vr in states}}
        out.append(("fmi3SetContinuousStates", Point(a.t, moved, f"{a.label} with the states of "
                    f"{b.label}"), lambda inst: inst.set_states([b.values[vr] for vr in states])))
    if knowns:
        moved = {**a.values, **{vr: b.values[vr] for vr in knowns}}
        out.append(("fmi3SetFloat64", Point(a.t, moved, f"{a.label} with the values of "
                    f"{b.label}"), lambda inst: inst.set_float64(
                        knowns, [b.values[vr] for vr in knowns])))
    return [*out, ("setting the whole point", b, lambda inst: inst.set_point(b))]


def _stale(alone: float, new: float, previous: float, *, rtol: float, atol: float,
           scale: float) -> bool:
    """Whether a value read alone is the previous point's: it differs from the value at the new
    point and equals the one at the previous point. A value in between is no stale read but the
    noise of an internal solve started from another guess (an ODE-mode algebraic variable of an
    ill-conditioned loop differs in its ninth digit with the Newton iteration's start)."""
    return (not close(alone, new, rtol=rtol, atol=atol, scale=scale)
            and close(alone, previous, rtol=rtol, atol=atol, scale=scale))


def stale_values_read(ctx: ProbeContext, *, rtol: float, atol: float) -> Iterator[Violation]:
    """FMI 3.0.2 §3.2.1: after fmi3SetTime, fmi3SetContinuousStates or fmi3SetFloat64 moved the
    point, a variable read with fmi3GetFloat64 has its value at the new point, whatever else is
    read with it. In each mode, for each group (outputs, derivatives, residuals, algebraic
    variables, event indicators) and each setter on its own (then the whole point): point A
    read whole, one setter moves it to M, the group is read alone; then M is set whole (every
    setter) and everything read: the group alone must equal that reading, and is stale when it
    equals A's reading instead (a value between the two is an internal solve's noise). One
    finding per group and mode, naming every setter after which it showed."""
    layout = layout_of(ctx)
    if len(ctx.points) < 2:
        return
    a, b = ctx.points[0], ctx.points[1]
    for mode, inst in _instances(ctx):
        groups = _groups(layout, mode)
        everything = list(dict.fromkeys(vr for _, vrs in groups for vr in vrs))
        for name, vrs in groups:
            first: tuple[int, float, float, float, str, Point] | None = None
            after_calls: list[str] = []
            for call, moved, change in _setters(layout, mode, a, b):
                try:
                    before = dict(zip(everything, inst.evaluate(a, everything)))
                    change(inst)
                    alone = inst.get_float64(list(vrs))
                    after = dict(zip(everything, inst.evaluate(moved, everything)))
                except (FmiError, PointNotSet):  # other rules' findings
                    if (inst := renew(ctx, mode)) is None:
                        return
                    continue
                for vr, x in zip(vrs, alone):
                    x, y, old = float(x), float(after[vr]), float(before[vr])
                    if all(map(math.isfinite, (x, y, old))) and _stale(
                            x, y, old, rtol=rtol, atol=atol, scale=layout.scale(vr)):
                        first = first or (vr, x, y, old, call, moved)
                        after_calls.append(call)
                        break
            if first is None:
                continue
            vr, x, y, old, call, moved = first
            yield Violation(
                f"read on its own after {call} moved the point from {a.label} to "
                f"{moved.label} ({_mode(mode)}), {{subject}} gives {x:.17g}, its value there is "
                f"{y:.17g} (at {a.label} it was {old:.17g}): the evaluation is not brought to "
                f"the new point when the {name} are read", var_location(ctx, vr),
                evidence(group=name, alone=x, at_new_point=y, previous_point=old,
                         points=[a.label, moved.label], changed_by=after_calls,
                         mode=_mode(mode), rtol=rtol, atol=atol),
                layout.name(vr), cause=(causes.STALE, causes.through(layout.name(vr))))


PROBES = {
    "DAE714": state_vectors_inconsistent,
    "DAE715": state_nominals_invalid,
    "DAE716": state_nominal_not_xml,
    "DAE717": stale_values_read,
}
