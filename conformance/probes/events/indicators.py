"""Event indicators in DAE mode, probed like outputs.

An importer that integrates the FMU in DAE mode reads the event indicators from inside its
solver: after setting t, the states, the algebraic variables and the inputs (fmusim's IDA root
function, through fmi-rs, does exactly that). So fmi3GetEventIndicators must work at any such
point, give as many values as the XML lists, and give the same values for the same point:

    event-indicators-failed        the count differs from the XML's <EventIndicator> list, the
                                   call fails, or a value is NaN or Inf (error)
    event-indicators-inconsistent  the same point gives other values after another point was
                                   evaluated, or the values differ from fmi3GetFloat64 of the
                                   indicator variables (error)

The XML's list is the manifest's <EventIndicator> elements in DAE mode, falling back to
modelDescription's when the manifest lists none (open question Q-03 of the digest), in document
order (MS-06).

fmi3GetNumberOfEventIndicators is asked where FMI 3.0.2 lists it, in Instantiated (§2.3.2; also
Event Mode, not Continuous-Time Mode): on a fresh instance whose switch was set true in
Configuration Mode, where an importer asks it after changing the structural parameter.
"""
from __future__ import annotations

import math
from typing import Any, Iterator, Sequence

import numpy as np

from ...report.findings import Location, Violation, evidence
from ...runtime.instance import Instance, PointNotSet
from ...runtime.layout import Layout
from ...model.unknowns import Unknown
from ..instruments.api import (EVENT_INDICATOR_FAULT, PLANNED, FmiError, Point, ProbeContext,
                               ProbeSkipped, noted)
from ..instruments.common import (close, dae_of, error_evidence, layout_of, new_instance, renew,
                                  root_location, var_location)
from ...runtime.modes import configure


def _declared(ctx: ProbeContext) -> tuple[list[Unknown], str]:
    """The <EventIndicator> elements that define the DAE-mode vector, and where they are."""
    listed = list(ctx.manifest.unknowns("EventIndicator")) if ctx.manifest else []
    if listed:
        return listed, "the manifest"
    return list(ctx.model.unknowns("EventIndicator")), "modelDescription.xml"


def _count(ctx: ProbeContext, listed: Sequence[Unknown]) -> int | None:
    """The length of the vector the XML defines, or None when an array makes it uncertain."""
    for u in listed:
        var = ctx.model.by_vr.get(u.vr) if u.vr is not None else None
        if var is not None and var.dimensions:
            return None
    return len(listed)


def _location(ctx: ProbeContext, listed: Sequence[Unknown]) -> Location:
    if listed:
        u = listed[0]
        return Location(file=u.file, line=u.line, path=u.path)
    return root_location(ctx)


def _names(layout: Layout, listed: Sequence[Unknown], n: int) -> list[str]:
    vrs = [u.vr for u in listed]
    return [layout.name(vrs[i]) if i < len(vrs) and vrs[i] is not None else f"z[{i}]"
            for i in range(n)]


def _instantiated(ctx: ProbeContext) -> Instance:
    """A fresh instance in Instantiated, switched to DAE mode in Configuration Mode (an FMU
    without an enable parameter is in DAE mode already)."""
    inst = new_instance(ctx.facts["library"], "count-dae")  # type: ignore[arg-type]
    try:
        if inst.layout.enable is not None:
            configure(inst, True)
    except BaseException:
        inst.free()
        raise
    return inst


def _number(ctx: ProbeContext) -> int:
    """fmi3GetNumberOfEventIndicators in DAE mode, asked in Instantiated; an FmiError of that
    call escapes, one of reaching the state skips the probe (enable-handshake's finding)."""
    try:
        inst = _instantiated(ctx)
    except FmiError as exc:
        raise ProbeSkipped(f"no instance in Instantiated, DAE mode, to ask the number of event "
                           f"indicators: {exc.call} returned {exc.status}") from None
    try:
        return inst.number_of_event_indicators()
    finally:
        inst.free()


# ------------------------------------------------------------------- event-indicators-failed


def event_indicators_failed(ctx: ProbeContext) -> Iterator[Violation]:
    """DAE-15, MS-06: in DAE mode fmi3GetNumberOfEventIndicators equals the XML's count, and
    fmi3GetEventIndicators succeeds with finite values at every sampled point (t, x, w, u)."""
    dae = dae_of(ctx)
    layout = layout_of(ctx)
    listed, source = _declared(ctx)
    expected = _count(ctx, listed)
    where = _location(ctx, listed)
    try:
        n = _number(ctx)
    except FmiError as exc:
        yield Violation(
            f"fmi3GetNumberOfEventIndicators returns {exc.status} in DAE mode", where,
            evidence(error_evidence(exc), declared=expected, declared_in=source),
            subject=exc.call)
        return
    if expected is not None and n != expected:
        yield Violation(
            f"fmi3GetNumberOfEventIndicators says {n} in DAE mode, but {source} lists {expected} "
            "<EventIndicator> element(s): an importer sizes its root function from one and "
            "reads the values by the other", where,
            evidence(reported=n, declared=expected, declared_in=source,
                     indicators=[layout.name(u.vr) for u in listed if u.vr is not None]),
            subject="fmi3GetNumberOfEventIndicators")
        return
    if n == 0:
        return
    names = _names(layout, listed, n)
    failed: list[str] = []
    first_error: FmiError | None = None
    nonfinite: dict[int, list[str]] = {}
    for point in ctx.points:
        try:
            dae.set_point(point)
        except FmiError:
            continue  # evaluation-failed, algebraic-not-settable
        try:
            z = dae.get_event_indicators(n)
        except FmiError as exc:
            failed.append(point.label)
            first_error = first_error or exc
            continue
        for i, v in enumerate(z):
            if not math.isfinite(v):
                nonfinite.setdefault(i, []).append(point.label)
    if first_error is not None:
        yield Violation(
            f"fmi3GetEventIndicators returns {first_error.status} in DAE mode at "
            f"{len(failed)} sampled point(s), first at {failed[0]}", where,
            evidence(error_evidence(first_error), points=failed, count=n),
            subject="fmi3GetEventIndicators")
    for i, points in nonfinite.items():
        vr = listed[i].vr if i < len(listed) else None
        yield Violation(
            f"the event indicator {{subject}} (element {i} of fmi3GetEventIndicators) is not "
            f"finite in DAE mode at {len(points)} sampled point(s), first at {points[0]}",
            var_location(ctx, vr) if vr is not None else where,
            evidence(points=points, index=i), names[i], part="not-finite")


# ------------------------------------------------------------- event-indicators-inconsistent


def event_indicators_inconsistent(ctx: ProbeContext, *, rtol: float, atol: float
                                  ) -> Iterator[Violation]:
    """MS-06: the same (t, x, w, u) gives the same indicators whatever was evaluated before
    (points A A B A B), and fmi3GetEventIndicators equals fmi3GetFloat64 of the indicator
    variables."""
    dae = dae_of(ctx)
    layout = layout_of(ctx)
    listed, _ = _declared(ctx)
    expected = _count(ctx, listed)
    n = _number(ctx)  # an FmiError skips the probe: event-indicators-failed reports it
    if expected is None:
        raise ProbeSkipped("an <EventIndicator> names an array variable: the probe compares "
                           "scalar indicators only")
    if n != expected:
        raise ProbeSkipped("the FMU's count of event indicators differs from the XML's "
                           "(event-indicators-failed reports it)")
    if n == 0:
        return
    names = _names(layout, listed, n)
    vrs = [u.vr for u in listed]
    readable = all(vr is not None and vr in layout.event_indicators for vr in vrs)
    points = list(ctx.points)
    a, b = points[0], points[1 % len(points)]
    first: dict[str, tuple[np.ndarray, str]] = {}
    reported: set[int] = set()
    previous = "the earlier probes"
    for point in (a, a, b, a, b):
        z = _evaluate(dae, point, n)
        if readable:
            try:
                by_vr = dae.get_float64([vr for vr in vrs if vr is not None])
            except FmiError as exc:
                # the vector reads, the variables do not: evaluation-failed's read-back names
                # the variable, state and mode; without it this rule says so itself
                readable = False
                if "DAE724" not in ctx.facts.get(PLANNED, ()):  # type: ignore[operator]
                    yield Violation(
                        f"fmi3GetEventIndicators gives values at point {point.label}, but "
                        f"fmi3GetFloat64 of the indicator variables returns {exc.status}: the "
                        "vector and the variables disagree", _location(ctx, listed),
                        evidence(error_evidence(exc), point=point.label, t=point.t),
                        subject="fmi3GetFloat64", part="variables-refused")
                dae = renew(ctx, "dae")
                if dae is None:
                    return
                previous = f"{point.label} (then a fresh instance)"
                continue
            yield from _against_variables(ctx, layout, names, vrs, point, z, by_vr, reported,
                                          rtol=rtol, atol=atol)
        if point.label in first:
            ref, ref_previous = first[point.label]
            yield from _against_first(ctx, layout, names, vrs, point, ref, z, ref_previous,
                                      previous, reported, rtol=rtol, atol=atol)
        else:
            first[point.label] = (z, previous)
        previous = point.label


def _evaluate(dae: Instance, point: Point, n: int) -> np.ndarray:
    try:
        dae.set_point(point)
    except FmiError as exc:
        raise PointNotSet(point, exc) from None
    return dae.get_event_indicators(n)


def _scale(layout: Layout, vr: int | None) -> float:
    return layout.scale(vr) if vr is not None else 1.0


def _where(ctx: ProbeContext, vr: int | None) -> Location:
    if vr is None:
        return root_location(ctx)
    return var_location(ctx, vr)


def _against_variables(ctx: ProbeContext, layout: Layout, names: list[str],
                       vrs: Sequence[int | None], point: Point, z: np.ndarray,
                       by_vr: np.ndarray, reported: set[int], *, rtol: float, atol: float
                       ) -> Iterator[Violation]:
    for i, x, y in _differing(layout, vrs, z, by_vr, reported, rtol=rtol, atol=atol):
        yield Violation(
            f"fmi3GetEventIndicators gives {{subject}} = {float(x):.17g} at point "
            f"{point.label}, fmi3GetFloat64 of the same variable {float(y):.17g}: the "
            "vector and the variable disagree", _where(ctx, vrs[i]),
            evidence(point=point.label, t=point.t, index=i, event_indicators=float(x),
                     get_float64=float(y), **_tolerance(layout, vrs[i], x, y, rtol, atol)),
            names[i], part="vector-vs-variables")


def _against_first(ctx: ProbeContext, layout: Layout, names: list[str],
                   vrs: Sequence[int | None], point: Point, ref: np.ndarray, z: np.ndarray,
                   ref_previous: str, previous: str, reported: set[int], *, rtol: float,
                   atol: float) -> Iterator[Violation]:
    for i, x, y in _differing(layout, vrs, ref, z, reported, rtol=rtol, atol=atol):
        yield Violation(
            f"the event indicator {{subject}} takes different values at the same point "
            f"{point.label}: {float(x):.17g} (after {ref_previous}) and {float(y):.17g} "
            f"(after {previous}); the FMU computes it from something it kept from an "
            "earlier evaluation", _where(ctx, vrs[i]),
            evidence(point=point.label, t=point.t, index=i, first=float(x),
                     second=float(y), **_tolerance(layout, vrs[i], x, y, rtol, atol)),
            names[i])


def _differing(layout: Layout, vrs: Sequence[int | None], first: np.ndarray, second: np.ndarray,
               reported: set[int], *, rtol: float, atol: float
               ) -> Iterator[tuple[int, float, float]]:
    """(index, first, second) of each indicator, not yet in ``reported``, whose two finite values
    differ beyond the tolerance (scaled by its nominal); each is added to ``reported``."""
    for i, (x, y) in enumerate(zip(first, second)):
        if i in reported or not (math.isfinite(x) and math.isfinite(y)):
            continue
        if not close(float(x), float(y), rtol=rtol, atol=atol, scale=_scale(layout, vrs[i])):
            reported.add(i)
            yield i, x, y


def _tolerance(layout: Layout, vr: int | None, x: float, y: float, rtol: float, atol: float
               ) -> dict[str, Any]:
    scale = _scale(layout, vr)
    return {"tolerance": atol + rtol * max(scale, abs(float(x)), abs(float(y))), "rtol": rtol,
            "atol": atol, "scale": "nominal or magnitude of the indicator"}


PROBES = {
    "DAE732": noted(EVENT_INDICATOR_FAULT, "DAE732", event_indicators_failed),
    "DAE733": noted(EVENT_INDICATOR_FAULT, "DAE733", event_indicators_inconsistent),
}
