"""Fresh Initialization-Mode instances within the survey's budget (for :mod:`.survey`).

Every function value of the Initialization-Mode survey is a fresh instance, so the survey's
options bound the instances over all points (a count: the budget) and the wall-clock time (a
safety net only): :class:`InstanceCounter` counts both and raises :class:`OverBudget` past the
first, :class:`OutOfTime` past the second; :class:`InitialPoint` evaluates one point with a new
instance per call.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..instruments.api import Point
from ..instruments.jacobian_layout import JacobianLayout


@dataclass(frozen=True)
class SurveySettings:
    """The survey's options (those of ``initial-dependency-undeclared``)."""

    points: int           # sampling points, the start values included
    max_instances: int    # fresh instances over all points: the budget
    max_seconds: float    # wall-clock time over all points: a safety net only


class OverBudget(Exception):
    pass


class OutOfTime(OverBudget):
    """The wall-clock safety net ran out: what was measured may not be judged."""


class InstanceCounter:
    """Fresh instances and seconds left; :meth:`spend` raises OverBudget past the instances,
    OutOfTime past the seconds."""

    def __init__(self, settings: SurveySettings):
        self.settings = settings
        self.left, self.used = settings.max_instances, 0
        self.deadline = time.monotonic() + settings.max_seconds
        self.why = ""

    def restart_clock(self) -> None:
        """A new ``max_seconds`` from now (each mode's survey gets its own time; the instances
        are counted over all of them)."""
        self.deadline = time.monotonic() + self.settings.max_seconds

    def spend(self) -> None:
        if self.left <= 0:
            self.why = f"max_instances = {self.settings.max_instances} ran out"
            raise OverBudget
        if time.monotonic() > self.deadline:
            self.why = (f"time budget: lsdae's wall-clock safety net (max_seconds = "
                        f"{self.settings.max_seconds:g} s) ran out after {self.used} fresh "
                        "instances: a faster machine would have measured more, so no verdict")
            raise OutOfTime
        self.left -= 1
        self.used += 1


Factory = Callable[[str, Mapping[int, float], float], Any]


class InitialPoint:
    """One point of Initialization Mode: the knowns as a vector (time included), each function
    value a fresh instance."""

    def __init__(self, factory: Factory, mode: str, layout: JacobianLayout, point: Point,
                 counter: InstanceCounter):
        self.factory, self.mode, self.layout, self.counter = factory, mode, layout, counter
        self.rows = tuple(r.vr for r in layout.rows)   # tuples: converted once per call
        self.time = [j for j, c in enumerate(layout.cols) if c.role == "time"]
        self.t = point.t
        self.x = np.array([point.t if c.role == "time" else point.values[c.vr]
                           for c in layout.cols])
        self.dd_idx = np.flatnonzero(layout.dd_columns)
        self.dd_vrs = tuple(layout.cols[j].vr for j in self.dd_idx)
        self.base: Any = None

    def _knowns(self, delta: np.ndarray) -> tuple[dict[int, float], float]:
        x = self.x + delta
        t = float(x[self.time[0]]) if self.time else self.t
        return ({c.vr: float(v) for c, v in zip(self.layout.cols, x) if c.role != "time"}, t)

    def open(self, delta: np.ndarray) -> Any:
        self.counter.spend()
        values, t = self._knowns(delta)
        return self.factory(self.mode, values, t)

    def fun(self, delta: np.ndarray) -> np.ndarray:
        inst = self.open(delta)
        try:
            return np.asarray(inst.get_float64(self.rows), dtype=float)
        finally:
            inst.free()

    def directional(self, seed: np.ndarray) -> np.ndarray:
        return np.asarray(self.base.directional_as_set(
            self.rows, self.dd_vrs, np.asarray(seed, dtype=float)[self.dd_idx]), dtype=float)
