"""The seeded sampling points of the probes.

The first sampling point is where the FMU stands after its initialisation in DAE mode (time,
states, algebraic variables, inputs read back with fmi3GetFloat64). The others perturb every
value by ``STEP`` times its scale (the larger of its nominal and its magnitude) with standard
normal weights from the run's seeded generator, stay within the declared ``min``/``max``, and
move time forward only (SM-06: fmi3SetTime never goes below the start time). Near points are
deliberately inconsistent (residuals are not zero there): in DAE mode the importer chooses the
algebraic variables, so every probe must work at any point.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ...runtime.instance import Instance
from ...runtime.layout import Layout
from .api import FmiError, Point

NEAR_POINTS = 3   # points besides the start point
STEP = 0.1        # relative size of a perturbation
TIME_STEP = 0.1   # seconds, scaled the same way


def start_point(inst: Instance | None, layout: Layout,
                nonfinite: dict[int, float] | None = None) -> Point:
    """The initial point of ``inst`` (in Continuous-Time Mode), or the XML start values.

    A value the FMU reports as NaN or Inf is replaced by its XML start value (0 without one),
    so that the other points stay usable, and noted in ``nonfinite`` for ``nan-or-inf`` -- unless
    the XML itself gives a non-finite start value (float-attribute-not-finite): the FMU's initial
    values then follow the XML, and the fault is the static finding's, not the binary's."""
    vrs = [*layout.states_for(inst.mode if inst else "dae"),
           *(layout.algebraic if inst is None or inst.mode == "dae" else ()), *layout.inputs]
    vrs = list(dict.fromkeys(vrs))
    fallback = [layout.start.get(vr, 0.0) for vr in vrs]
    values: Sequence[float] = fallback
    if inst is not None:
        try:
            values = inst.get_float64(vrs)
        except FmiError:
            pass
    out = {}
    for vr, v, default in zip(vrs, values, fallback):
        if not math.isfinite(v):
            if nonfinite is not None and not layout.flagged_start:
                nonfinite[vr] = float(v)
            v = default
        out[vr] = float(v)
    return Point(layout.start_time, out, "start")


def within(value: float, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    if value < lo:
        value = min(2 * lo - value, hi) if math.isfinite(hi) else 2 * lo - value
    if value > hi:
        value = max(2 * hi - value, lo) if math.isfinite(lo) else 2 * hi - value
    return min(max(value, lo), hi)


def near_points(start: Point, layout: Layout, rng: np.random.Generator, *,
                count: int = NEAR_POINTS, step: float = STEP) -> list[Point]:
    """``count`` seeded points around ``start``, within bounds, scaled by nominals."""
    out = []
    vrs = sorted(start.values)
    for k in range(count):
        weights = rng.standard_normal(len(vrs) + 1)
        values = {}
        for vr, w in zip(vrs, weights[1:]):
            v = start.values[vr]
            scale = max(layout.scale(vr), abs(v))
            values[vr] = within(v + step * scale * float(w),
                                 layout.bounds.get(vr, (-math.inf, math.inf)))
        t = start.t + TIME_STEP * abs(float(weights[0]))
        out.append(Point(t, values, f"near-{k + 1}"))
    return out


def points_info(points: Sequence[Point], layout: Layout, seed: int) -> dict[str, Any]:
    """The report's ``points`` and ``seed`` entries (see api.INFO_KEYS)."""
    return {
        "points": [{"label": p.label, "t": p.t,
                    "values": {layout.name(vr): v for vr, v in p.values.items()}}
                   for p in points],
        "seed": seed,
    }
