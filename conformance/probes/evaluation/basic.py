"""The basic probes: setting algebraic variables, consistency at the start and repeatability
(non-finite values, failing evaluations and inputs that cannot be set are in failures.py; the
enable handshake is in handshake.py).

Each probe runs in the worker process on a
:class:`~conformance.probes.instruments.api.ProbeContext` whose ``facts`` hold the
:class:`~conformance.runtime.layout.Layout` (``"layout"``) and the loaded
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
from typing import Iterator

import numpy as np

from ...report import causes
from ...report.findings import Violation, evidence
from ..instruments.api import FmiError, Point, ProbeContext
from ..instruments.common import (close, dae_of, error_evidence, finite, fresh_instance, layout_of,
                                  manifest_location, renew, unknown_location, unknowns_of)
from ...runtime.instance import Instance, PointNotSet
from ...runtime.layout import Layout
from ..instruments.sampling import within

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
                layout.name(vr), cause=causes.through(layout.name(vr)))
    if rejected:
        return
    watch = list(dict.fromkeys([*layout.residuals, *layout.derivatives]))
    base = dae.get_float64(watch)
    chosen = list(layout.algebraic)
    if len(chosen) > max_variables:
        picked = ctx.rng.choice(len(chosen), size=max_variables, replace=False)
        chosen = [chosen[i] for i in sorted(picked)]
    scales = np.array([layout.scale(w) for w in watch])
    for vr in chosen:
        yield from _set_one(ctx, dae, layout, start, vr, watch, base, scales, step=step,
                            rtol=rtol, react_rtol=react_rtol)


def _set_knowns(dae: Instance, point: Point) -> None:
    """Time, states and inputs of ``point``; PointNotSet (the probe is skipped) naming what
    was refused when that fails: evaluation-failed or input-not-settable reports it."""
    try:
        dae.set_point(point, algebraic=False)
    except FmiError as exc:
        raise PointNotSet(point, exc) from None


def _set_one(ctx: ProbeContext, dae: Instance, layout: Layout, start: Point, vr: int,
             watch: list[int], base: np.ndarray, scales: np.ndarray, *, step: float,
             rtol: float, react_rtol: float) -> Iterator[Violation]:
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
                evidence(point=start.label, set=value, read_back=got, rtol=rtol), name,
                part="value-not-kept", cause=causes.through(name))
            return
        after = dae.get_float64(watch)
        tried.append(value)
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
            name, part="no-effect", cause=causes.through(name))


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
                f"zero (tolerance {tol:.3g}): alpha.1 lets the FMU leave consistent "
                "initialisation to the importer (DAE-14), which must then solve the residuals "
                "for the algebraic variables, with the states and inputs as the FMU left them, "
                "before its first step",
                manifest_location(ctx, vr, ("Residual",)),
                evidence(point="start", value=float(r), scale=scale, scale_source=source,
                         tolerance=tol, rtol=rtol, atol=atol, started=started,
                         importer_solves="g(t0, x0, w, u0) = 0 for the algebraic variables w"),
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


PROBES = {
    "DAE720": algebraic_not_settable,
    "DAE721": initial_residual_nonzero,
    "DAE722": evaluation_not_repeatable,
}
