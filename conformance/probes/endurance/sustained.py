"""The endurance probes (DAE760-DAE769): defects that only sustained use shows.

The point probes make few calls per instance; a real FMU may crash after a few thousand, leak on
every call, or keep its state in C globals shared by its instances. These probes run at the level
chosen with ``--endurance`` (``quick``, the default, or ``long``; ``off`` skips them in the
runner), each level with its own budget in the catalogue:

* ``evaluation-fails-late``: the path run of :mod:`.run` (thousands of set/get calls
  on one instance) must not start failing; a call that fails after N calls while a fresh
  instance evaluates the same point is the finding. A crash during the run is the supervisor's
  ``binary-crashed``, whose evidence then says after how many FMI calls (``call_count``);
* ``memory-grows`` (:mod:`.memory`): the worker's resident memory, sampled along the
  same run, must not grow with the calls (:func:`conformance.numerics.growth.growth` measures it);
* ``instances-not-independent``: a second instance beside the first, the two set to different
  points in turn, and repeated instantiate/free cycles give the same values at the same point.

Every probe runs in the worker process like the others and yields violations.
"""
from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from ...report.findings import Violation, evidence
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from ..instruments.api import Point, ProbeContext, ProbeSkipped
from ..instruments.common import dae_of, layout_of, root_location, unknowns_of
from .memory import RUN_CODES
from .run import level_of, path_run, remember_settings
from ..instruments.independence import shared_violation, survey

# the scenarios of instances-not-independent, in the order they are tried
KINDS = ("second-instance", "interleaved", "cycle", "first-after-cycles")
MAX_LISTED = 10                     # differing values listed in the evidence

# ------------------------------------------------------------------ evaluation-fails-late


def evaluation_fails_late(ctx: ProbeContext, *, calls_quick: int, calls_long: int,
                          values_quick: int, values_long: int, seconds_quick: float,
                          seconds_long: float, samples: int,
                          max_growth_mib: float) -> Iterator[Violation]:
    """Thousands of evaluations along a path on one instance in DAE mode (the budget of the
    level: ``calls_<level>`` FMI calls and ``values_<level>`` values passed; ``seconds_<level>``
    is a safety net whose end makes the run's rules not run) never start to fail. Carries the
    settings of the path run, which ``memory-grows`` judges too (``samples`` memory samples;
    the run stops when memory grew by ``max_growth_mib``)."""
    remember_settings(ctx, {"calls_quick": calls_quick, "calls_long": calls_long,
                            "values_quick": values_quick, "values_long": values_long,
                            "seconds_quick": seconds_quick, "seconds_long": seconds_long,
                            "samples": samples, "max_growth_mib": max_growth_mib})
    run = path_run(ctx, RUN_CODES)
    failure = run.failure
    if failure is None:
        if run.out_of_time():
            raise ProbeSkipped(run.out_of_time())
        return
    if failure["fresh_instance"] != "ok" and not failure["fresh_instance"].startswith("not"):
        raise ProbeSkipped(
            f"{failure['call']} returned {failure['status']} at the path point "
            f"{failure['path_point']} (t = {failure['t']:.9g}), and on a fresh instance too: a "
            "failure at that point, not one that comes with use")
    yield Violation(
        f"{failure['call']} returns {failure['status']} after {failure['calls_before']:,} "
        f"FMI calls on one instance (DAE mode, lap {failure['lap']} of the path, t = "
        f"{failure['t']:.9g}); a fresh instance evaluates the same point "
        + ("without error" if failure["fresh_instance"] == "ok" else
           f"({failure['fresh_instance']})"),
        root_location(ctx),
        evidence(failure, level=run.settings.level, budget_calls=run.settings.calls,
                 steps_before=run.steps),
        subject=failure["call"])


# --------------------------------------------------------------- instances-not-independent


class _Scenarios:
    """Reference values of the first instance, and the scenarios compared with them."""

    def __init__(self, ctx: ProbeContext, *, rtol: float, atol: float):
        self.ctx, self.rtol, self.atol = ctx, rtol, atol
        self.layout: Layout = layout_of(ctx)
        layout = self.layout
        self.unknowns = unknowns_of(layout)
        self.initial = list(dict.fromkeys([*layout.states, *layout.algebraic, *self.unknowns]))
        self.found: list[dict[str, Any]] = []
        self._scale_of: dict[int, tuple[Sequence[int], np.ndarray]] = {}  # by the list's id

    def differences(self, vrs: Sequence[int], expected: np.ndarray, actual: np.ndarray
                    ) -> list[dict[str, Any]]:
        """The values that differ beyond ``atol + rtol * max(nominal, |values|)`` (common.close,
        on whole arrays: a model of 10,000 variables is compared at once)."""
        a = np.asarray(expected, dtype=float)
        b = np.asarray(actual, dtype=float)
        scale = self._scales(vrs)
        with np.errstate(invalid="ignore"):
            off = np.isfinite(a) & np.isfinite(b) & ~(  # non-finite values: nan-or-inf's
                np.abs(a - b) <= self.atol + self.rtol * np.maximum(
                    scale, np.maximum(np.abs(a), np.abs(b))))
        out = []
        for k in np.flatnonzero(off).tolist():
            out.append({"variable": self.layout.name(vrs[k]), "expected": float(a[k]),
                        "actual": float(b[k]), "difference": abs(float(a[k]) - float(b[k]))})
        return out

    def _scales(self, vrs: Sequence[int]) -> np.ndarray:
        key = id(vrs)
        if key not in self._scale_of:
            self._scale_of[key] = (vrs, np.array([self.layout.scale(vr) for vr in vrs]))
        return self._scale_of[key][1]

    def compare(self, kind: str, scenario: str, what: str, vrs: Sequence[int],
                expected: np.ndarray, actual: np.ndarray, **more: Any) -> bool:
        """Record ``scenario`` (of ``kind``, one of ``KINDS``) when ``actual`` differs from
        ``expected``; True if it did."""
        diffs = self.differences(vrs, expected, actual)
        if diffs:
            self.found.append({"kind": kind, "scenario": scenario, **more, "compared": what,
                               "count": len(diffs), "differences": diffs[:MAX_LISTED]})
        return bool(diffs)


def instances_not_independent(ctx: ProbeContext, *, cycles_quick: int, cycles_long: int,
                              seconds_quick: float, seconds_long: float, rtol: float,
                              atol: float, alone_copies: int,
                              explains: Sequence[str]) -> Iterator[Violation]:
    """Instances of one FMU do not share state: a second instance beside the first, the two
    set to different points in turn, and ``cycles_<level>`` instantiate/free cycles give the
    values of the first instance at the same point (after initialisation, and at two sampled
    points), within ``atol + rtol * nominal``. ``seconds_<level>`` is a safety net: when it
    ends the cycles before a difference is found, the probe is not run (time budget). An
    instance that cannot repeat its own values (P, Q, P) is ``evaluation-not-repeatable``'s
    finding: the probe is skipped then.

    First of all, the survey of :mod:`..instruments.independence` (the process's first instance, a
    later one and the ODE-mode ones against instances alone, each in a copy of the binary of its
    own, ``alone_copies`` at most): a difference there is the finding. ``explains`` names the
    rules whose findings the probe stage re-runs with every instance alone; what vanishes is
    folded into this finding (``runner.fold_consequences``)."""
    level = level_of(ctx)
    me = ctx.model.model_exchange
    if me is not None and me.flag("canBeInstantiatedOnlyOncePerProcess"):
        raise ProbeSkipped("the FMU declares canBeInstantiatedOnlyOncePerProcess: its instances "
                           "may share state")
    shared = survey(ctx, copies=alone_copies, rtol=rtol, atol=atol)
    if shared.found:
        yield shared_violation(ctx, shared, root_location(ctx), level=level, rtol=rtol,
                               atol=atol, scale="nominal or magnitude of each value")
        return
    cycles = int(cycles_quick if level == "quick" else cycles_long)
    seconds = float(seconds_quick if level == "quick" else seconds_long)
    dae_of(ctx)
    s = _Scenarios(ctx, rtol=rtol, atol=atol)
    p, q = ctx.points[0], ctx.points[1 % len(ctx.points)]
    first: Instance = ctx.new_instance("dae")  # type: ignore[assignment]
    done = 0
    try:
        initial = first.get_float64(s.initial)
        at_p, at_q = first.evaluate(p, s.unknowns), first.evaluate(q, s.unknowns)
        if s.differences(s.unknowns, at_p, first.evaluate(p, s.unknowns)):
            raise ProbeSkipped(f"one instance alone gives different values at {p.label} after "
                               f"{q.label}: evaluation-not-repeatable's finding, not one about "
                               "instances")
        _side_by_side(ctx, s, first, p, q, initial, at_p, at_q)
        deadline = time.monotonic() + seconds
        while done < cycles and not s.found:
            if time.monotonic() >= deadline:  # the safety net: the verdict would be partial
                raise ProbeSkipped(
                    f"time budget: {done} of {cycles} instantiate/free cycles were made when "
                    f"lsdae's wall-clock safety net (seconds_{level} = {seconds:g} s) ran out: "
                    "a faster machine would have made them all, so no verdict")
            done += 1
            _cycle(ctx, s, p, initial, at_p, done)
        if not s.found:
            s.compare("first-after-cycles",
                      f"the first instance, after {done} free/instantiate cycles of others",
                      f"values at {p.label}", s.unknowns, at_p, first.evaluate(p, s.unknowns),
                      cycle=done)
    finally:
        first.free()
    ctx.facts.setdefault("info", {}).setdefault(  # type: ignore[union-attr]
        "endurance", {}).update(level=level, cycles=done)
    if not s.found:
        return
    found = s.found[0]
    shown = ", ".join(f"{d['variable']} {d['expected']:.9g} vs {d['actual']:.9g}"
                      for d in found["differences"][:3])
    yield Violation(
        f"instances are not independent: {found['scenario']}, {found['count']} value(s) "
        f"differ from the first instance's ({found['compared']}: {shown}); the FMU keeps "
        "state outside its instance (C globals or statics)",
        root_location(ctx),
        evidence(found, points={"p": _point(p), "q": _point(q)}, cycles_run=done,
                 cycles_budget=cycles, level=level, rtol=rtol, atol=atol,
                 scale="nominal or magnitude of each value"),
        subject=found["kind"])


def _point(point: Point) -> dict[str, Any]:
    return {"label": point.label, "t": point.t}


def _side_by_side(ctx: ProbeContext, s: _Scenarios, first: Instance, p: Point, q: Point,
                  initial: np.ndarray, at_p: np.ndarray, at_q: np.ndarray) -> None:
    """A second instance while the first lives; then each set to its own point in turn and
    read only after both were set."""
    second: Instance = ctx.new_instance("dae")  # type: ignore[assignment]
    try:
        beside = "a second instance beside the first"
        if s.compare("second-instance", beside, "values after initialisation", s.initial,
                     initial, second.get_float64(s.initial)):
            return
        if s.compare("second-instance", beside, f"values at {q.label}", s.unknowns, at_q,
                     second.evaluate(q, s.unknowns)):
            return
        first.set_point(p)
        second.set_point(q)
        if s.compare("interleaved", f"the first instance at {p.label}, read after the second "
                     f"was set to {q.label}", f"values at {p.label}", s.unknowns, at_p,
                     first.get_float64(s.unknowns)):
            return
        s.compare("interleaved", f"the second instance at {q.label}, read after the first was "
                  f"set to {p.label}", f"values at {q.label}", s.unknowns, at_q,
                  second.get_float64(s.unknowns))
    finally:
        second.free()


def _cycle(ctx: ProbeContext, s: _Scenarios, p: Point, initial: np.ndarray,
           at_p: np.ndarray, done: int) -> None:
    """One more instance: instantiated, initialised, evaluated at ``p``, freed."""
    scenario = f"a new instance after {done} free/instantiate cycle{'s' if done > 1 else ''}"
    inst: Instance = ctx.new_instance("dae")  # type: ignore[assignment]
    try:
        if s.compare("cycle", scenario, "values after initialisation", s.initial, initial,
                     inst.get_float64(s.initial), cycle=done):
            return
        s.compare("cycle", scenario, f"values at {p.label}", s.unknowns, at_p,
                  inst.evaluate(p, s.unknowns), cycle=done)
    finally:
        inst.free()


PROBES = {
    "DAE760": evaluation_fails_late,
    "DAE762": instances_not_independent,
}
