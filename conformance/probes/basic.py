"""The basic probes: setting algebraic variables and inputs, consistency at the start,
repeatability, non-finite values and failing evaluations (the enable handshake is in
handshake.py).

Each probe runs in the worker process on a :class:`~conformance.probes.api.ProbeContext` whose
``facts`` hold the :class:`~conformance.runtime.layout.Layout` (``"layout"``) and the loaded
:class:`~conformance.runtime.library.Library` (``"library"``), and yields violations. Tolerances
are catalogue options. One fault, one finding: a probe that cannot set a point or start DAE mode
raises :class:`ProbeSkipped` (or lets the :class:`FmiError` escape), and the rule that owns the
fault reports it: ``evaluation-failed`` time and states, ``algebraic-not-settable`` the algebraic
variables, ``input-not-settable`` the inputs (the :class:`KnownNotSet` of a refused set says
which). A call that returned fmi3Error puts the instance in Terminated (SM-04): what fails on it
afterwards is a consequence, reported by nobody, and a probe that goes on takes a fresh
instance. Non-finite values are left to ``nan-or-inf``.
"""
from __future__ import annotations

import math
from typing import Any, Iterator

import numpy as np

from ..findings import Location, Violation, evidence
from .api import FmiError, Point, ProbeContext, ProbeSkipped
from .common import (
    close,
    dae_of,
    error_evidence,
    finite,
    fresh_instance,
    layout_of,
    manifest_location,
    renew,
    root_location,
    unknown_location,
    unknowns_of,
    var_location,
)
from ..runtime.instance import Instance, KnownNotSet, PointNotSet
from ..runtime.layout import Layout
from .sampling import within

# ------------------------------------------------------------------- algebraic-not-settable


def algebraic_not_settable(ctx: ProbeContext, *, step: float, rtol: float,
                           react_rtol: float, max_variables: int) -> Iterator[Violation]:
    """DAE-40: in Continuous-Time Mode every algebraic variable accepts fmi3SetFloat64, reads
    back the value set, and the residuals or derivatives change with it. Each variable costs
    two evaluations of every residual and derivative, so a large FMU is checked on a seeded
    sample of ``max_variables`` of them (all of them are set once at the start point)."""
    dae = dae_of(ctx)
    layout = layout_of(ctx)
    start = ctx.points[0]
    _set_knowns(dae, start)
    rejected = False
    for vr in layout.algebraic:  # each on its own, at its value of the start point
        if getattr(dae, "failure", None) is not None:  # refused: Terminated (SM-04)
            dae = renew(ctx, "dae")
            if dae is None:
                return
            _set_knowns(dae, start)
        value = start.values.get(vr, layout.start.get(vr, 0.0))
        try:
            dae.set_float64([vr], [value])
        except FmiError as exc:
            rejected = True
            yield Violation(
                f"fmi3SetFloat64 on the algebraic variable {{subject}} returns {exc.status} in "
                "Continuous-Time Mode, DAE mode", manifest_location(ctx, vr,
                                                                    ("AlgebraicVariable",)),
                evidence(error_evidence(exc), point=start.label, value=value),
                layout.name(vr))
    if rejected:
        return
    watch = list(dict.fromkeys([*layout.residuals, *layout.derivatives]))
    base = dae.get_float64(watch)
    chosen = list(layout.algebraic)
    if len(chosen) > max_variables:
        picked = ctx.rng.choice(len(chosen), size=max_variables, replace=False)
        chosen = [chosen[i] for i in sorted(picked)]
    for vr in chosen:
        yield from _set_one(ctx, dae, layout, start, vr, watch, base, step=step, rtol=rtol,
                            react_rtol=react_rtol)


def _set_knowns(dae: Instance, point: Point) -> None:
    """Time, states and inputs of ``point``; PointNotSet (the probe is skipped) naming what
    was refused when that fails: evaluation-failed or input-not-settable reports it."""
    try:
        dae.set_point(point, algebraic=False)
    except FmiError as exc:
        raise PointNotSet(point, exc) from None


def _set_one(ctx: ProbeContext, dae: Instance, layout: Layout, start: Point, vr: int,
             watch: list[int], base: np.ndarray, *, step: float, rtol: float,
             react_rtol: float) -> Iterator[Violation]:
    where = manifest_location(ctx, vr, ("AlgebraicVariable",))
    name = layout.name(vr)
    v0 = start.values.get(vr, layout.start.get(vr, 0.0))
    delta = step * max(layout.scale(vr), abs(v0))
    bounds = layout.bounds.get(vr, (-math.inf, math.inf))
    tried = []
    for sign in (1.0, -1.0):
        value = within(v0 + sign * delta, bounds)
        dae.set_point(start)
        dae.set_float64([vr], [value])
        got = float(dae.get_float64([vr])[0])
        if not close(got, value, rtol=rtol, atol=0.0, scale=layout.scale(vr)):
            yield Violation(
                "the algebraic variable {subject} does not keep the value set in DAE mode: "
                "the FMU overwrites it", where,
                evidence(point=start.label, set=value, read_back=got, rtol=rtol), name)
            return
        after = dae.get_float64(watch)
        tried.append(value)
        scales = np.array([layout.scale(w) for w in watch])
        change = np.abs(after - base)
        if np.any(change > react_rtol * np.maximum(scales, np.abs(base))):
            return
        if not finite(after) or not finite(base):
            return  # nan-or-inf owns non-finite values
    if _declared_anywhere(ctx, vr):
        yield Violation(
            "neither the residuals nor the derivatives change when the algebraic variable "
            "{subject} is set: the FMU does not use the value the importer gives it", where,
            evidence(point=start.label, values_set=tried, unknowns=[layout.name(w) for w in watch],
                     relative_tolerance=react_rtol, scale="nominal or magnitude of each unknown"),
            name)


def _declared_anywhere(ctx: ProbeContext, vr: int) -> bool:
    """Whether a manifest Residual or ContinuousStateDerivative may depend on ``vr``."""
    if ctx.manifest is None:
        return False
    for u in ctx.manifest.structure:
        if u.kind in ("Residual", "ContinuousStateDerivative"):
            if u.dependencies is None or vr in u.dependencies:
                return True
    return False


# ----------------------------------------------------------------- initial-residual-nonzero


def initial_residual_nonzero(ctx: ProbeContext, *, rtol: float, atol: float) -> Iterator[Violation]:
    """After initialisation in DAE mode, on a fresh instance, every residual is zero within
    ``atol + rtol * nominal`` (the residual's own nominal, 1 when it declares none)."""
    layout = layout_of(ctx)
    if not layout.residuals:
        return
    dae_of(ctx)
    with fresh_instance(ctx, "dae") as inst:
        values = inst.get_float64(list(layout.residuals))
        started = inst.started
    for vr, r in zip(layout.residuals, values):
        if not math.isfinite(r):
            continue  # nan-or-inf
        var = ctx.model.by_vr.get(vr)
        scale = layout.scale(vr)
        tol = atol + rtol * scale
        if abs(r) > tol:
            source = (f"nominal of '{layout.name(vr)}'" if var is not None and var.nominal
                      else "default nominal 1")
            yield Violation(
                f"the residual {{subject}} is {r:.6g} after initialisation in DAE mode, not "
                f"zero (tolerance {tol:.3g}): the FMU's initial point is not consistent",
                manifest_location(ctx, vr, ("Residual",)),
                evidence(point="start", value=float(r), scale=scale, scale_source=source,
                         tolerance=tol, rtol=rtol, atol=atol, started=started),
                layout.name(vr))


# ---------------------------------------------------------------- evaluation-not-repeatable


def evaluation_not_repeatable(ctx: ProbeContext, *, rtol: float, atol: float
                              ) -> Iterator[Violation]:
    """The same (t, x, w, u) gives the same residuals, derivatives and outputs whatever was
    evaluated before: points A, B, C evaluated as A B A A C B A, and A, B on a fresh instance."""
    dae = dae_of(ctx)
    layout = layout_of(ctx)
    unknowns = unknowns_of(layout)
    points = list(ctx.points)
    if not unknowns or len(points) < 2:
        return
    a, b, c = points[0], points[1], points[2 % len(points)]
    first: dict[str, tuple[np.ndarray, str]] = {}
    reported: set[int] = set()
    previous = "initialisation"
    sequence = []
    for point in (a, b, a, a, c, b, a):
        values = dae.evaluate(point, unknowns)
        sequence.append(point.label)
        yield from _compare(ctx, layout, unknowns, first, point, values, previous, reported,
                            rtol=rtol, atol=atol, sequence=sequence)
        first.setdefault(point.label, (values, previous))
        previous = point.label
    with fresh_instance(ctx, "dae") as fresh:
        for point in (b, a):
            values = fresh.evaluate(point, unknowns)
            yield from _compare(ctx, layout, unknowns, first, point, values,
                                "initialisation of a fresh instance" if point is b else b.label,
                                reported, rtol=rtol, atol=atol, sequence=[*sequence, "fresh"])


def _compare(ctx: ProbeContext, layout: Layout, unknowns: list[int],
             first: dict[str, tuple[np.ndarray, str]], point: Point, values: np.ndarray,
             previous: str, reported: set[int], *, rtol: float, atol: float,
             sequence: list[str]) -> Iterator[Violation]:
    if point.label not in first:
        return
    ref, ref_previous = first[point.label]
    for i, vr in enumerate(unknowns):
        x, y = float(ref[i]), float(values[i])
        if vr in reported or not (math.isfinite(x) and math.isfinite(y)):
            continue
        if not close(x, y, rtol=rtol, atol=atol, scale=layout.scale(vr)):
            reported.add(vr)
            yield Violation(
                f"{{subject}} takes different values at the same point {point.label}: "
                f"{x:.17g} (after {ref_previous}) and {y:.17g} (after {previous}); the FMU "
                "keeps hidden state between evaluations", unknown_location(ctx, vr),
                evidence(point=point.label, first=x, second=y, difference=abs(x - y),
                         tolerance=atol + rtol * max(layout.scale(vr), abs(x), abs(y)),
                         rtol=rtol, atol=atol, sequence=list(sequence)),
                layout.name(vr))


# ------------------------------------------------------------------------------- nan-or-inf


def nan_or_inf(ctx: ProbeContext, *, directional: bool) -> Iterator[Violation]:
    """No NaN or Inf at any sampled point: residuals, derivatives, outputs and algebraic
    variables in DAE mode; derivatives, outputs and algebraic variables in ODE mode; and, when
    the FMU provides directional derivatives, J @ 1 in DAE mode (every known at once, so a
    single non-finite partial shows)."""
    layout = layout_of(ctx)
    if ctx.dae is None and ctx.ode is None:
        dae_of(ctx)
    found: dict[str, dict[str, Any]] = {}
    initial = Point(0.0, {}, "start (as initialised)")
    for vr, v in dict(ctx.facts.get("start_nonfinite") or {}).items():  # see start_point
        _note(found, layout.name(vr), var_location(ctx, vr),
              "dae" if ctx.dae is not None else "ode", initial, v)
    for mode, inst in (("dae", ctx.dae), ("ode", ctx.ode)):
        if inst is None:
            continue
        unknowns = list(dict.fromkeys([*unknowns_of(layout, mode), *layout.algebraic]))
        for point in ctx.points:
            try:
                values = inst.evaluate(point, unknowns)
            except (FmiError, PointNotSet):
                continue  # evaluation-failed, algebraic-not-settable, enable-handshake (ODE)
            for vr, v in zip(unknowns, values):
                if not math.isfinite(v):
                    _note(found, layout.name(vr), var_location(ctx, vr), mode, point, v)
    dae = ctx.dae
    if directional and layout.provides_directional and dae is not None:
        _directional(ctx, layout, dae, found)
    for subject, item in found.items():
        yield Violation(
            f"{item['what']} {{subject}} is {item['value']} at {len(item['points'])} sampled "
            f"point(s), first at {item['points'][0]} ({item['mode']} mode)", item["location"],
            evidence(points=item["points"], value=item["value"], mode=item["mode"],
                     first_point={"label": item["first"].label, "t": item["first"].t}),
            subject)


def _note(found: dict[str, dict[str, Any]], subject: str, location: Location, mode: str,
          point: Point, value: float, what: str = "") -> None:
    item = found.setdefault(subject, {
        "what": what or "the value of", "location": location, "mode": mode, "points": [],
        "value": repr(float(value)), "first": point})
    if point.label not in item["points"]:
        item["points"].append(point.label)


def _directional(ctx: ProbeContext, layout: Layout, dae: Instance,
                 found: dict[str, dict[str, Any]]) -> None:
    unknowns = unknowns_of(layout)
    knowns = list(dict.fromkeys([*layout.states, *layout.algebraic, *layout.inputs]))
    if not unknowns or not knowns:
        return
    seed = np.ones(len(knowns))
    for point in ctx.points:
        try:
            column = dae.directional(point, unknowns, knowns, seed)
        except (FmiError, PointNotSet):
            return  # the derivative probes report a failing fmi3GetDirectionalDerivative
        for vr, v in zip(unknowns, column):
            if not math.isfinite(v):
                _note(found, f"d({layout.name(vr)})", unknown_location(ctx, vr), "dae", point,
                      v, what="the directional derivative (all knowns seeded with 1)")


# -------------------------------------------------------------------------- evaluation-failed


def evaluation_failed(ctx: ProbeContext) -> Iterator[Violation]:
    """DAE-41: in DAE mode, at every sampled point, time and states can be set and the
    residuals, derivatives and outputs read (fmi3GetFloat64, fmi3GetContinuousStateDerivatives).
    A rejected input is input-not-settable's finding, a rejected algebraic variable
    algebraic-not-settable's: the probe is skipped. The first failing call at a point is the
    finding; it put the instance in Terminated (SM-04), so the next point is evaluated on a
    fresh instance, and a call that fails after an earlier failure on the same instance is
    not reported."""
    dae = dae_of(ctx)
    layout = layout_of(ctx)
    unknowns = unknowns_of(layout)
    for point in ctx.points:
        if getattr(dae, "failure", None) is not None:
            dae = renew(ctx, "dae")
            if dae is None:
                return
        try:
            dae.set_point(point, algebraic=False)
        except FmiError as exc:
            kind = exc.kind if isinstance(exc, KnownNotSet) else ""
            if exc.after is not None or kind not in ("time", "states"):
                raise PointNotSet(point, exc) from None  # not a fault of time or states
            yield Violation(
                f"setting the {kind} in DAE mode fails at point {point.label}: "
                f"{exc.call} returned {exc.status}", root_location(ctx),
                evidence(error_evidence(exc), point=point.label, t=point.t, setting=kind,
                         mode="DAE mode, Continuous-Time Mode"), subject=exc.call)
            continue
        try:
            dae.set_algebraic(point)
        except FmiError as exc:  # algebraic-not-settable reports it
            raise PointNotSet(point, exc) from None
        for read, arg in ((dae.get_float64, unknowns), (dae.get_derivatives, len(layout.states))):
            try:
                read(arg)
            except FmiError as exc:
                if exc.after is not None:
                    raise ProbeSkipped(exc.cause()) from None
                yield Violation(
                    f"reading the residuals, derivatives and outputs in DAE mode fails at "
                    f"point {point.label}: {exc.call} returned {exc.status}",
                    root_location(ctx),
                    evidence(error_evidence(exc), point=point.label, t=point.t,
                             unknowns=[layout.name(vr) for vr in unknowns]),
                    subject=exc.call)
                break


# ------------------------------------------------------------------------ input-not-settable


def input_not_settable(ctx: ProbeContext) -> Iterator[Violation]:
    """SG-05: in Continuous-Time Mode every continuous input accepts fmi3SetFloat64, in DAE
    mode and in ODE mode. Each input is set on its own, to its value at the start point; a
    refusal names the call, the input, its value reference, the mode and the FMU's log. A
    refused call puts the instance in Terminated (SM-04): the next input is tried on a fresh
    instance."""
    layout = layout_of(ctx)
    if not layout.inputs:
        return
    if ctx.dae is None and ctx.ode is None:
        dae_of(ctx)  # ProbeSkipped: no mode could be started
    start = ctx.points[0]
    for mode in ("dae", "ode"):
        inst = getattr(ctx, mode)
        for vr in layout.inputs:
            if inst is None:
                break
            value = start.values.get(vr, layout.start.get(vr, 0.0))
            try:
                inst.set_float64([vr], [value])
            except FmiError as exc:
                if exc.after is not None:
                    raise ProbeSkipped(exc.cause()) from None
                yield Violation(
                    f"fmi3SetFloat64 on the continuous input {{subject}} (valueReference {vr}) "
                    f"returns {exc.status} in {mode.upper()} mode, Continuous-Time Mode, where "
                    "FMI 3.0 allows setting it (SG-05)", var_location(ctx, vr),
                    evidence(error_evidence(exc), value_reference=vr, value=value,
                             mode=f"{mode.upper()} mode", state="Continuous-Time Mode",
                             point=start.label), layout.name(vr))
                if getattr(inst, "failure", None) is not None:
                    inst = renew(ctx, mode)


PROBES = {
    "DAE720": algebraic_not_settable,
    "DAE721": initial_residual_nonzero,
    "DAE722": evaluation_not_repeatable,
    "DAE723": nan_or_inf,
    "DAE724": evaluation_failed,
    "DAE725": input_not_settable,
}
