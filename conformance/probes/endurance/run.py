"""The path run the endurance probes judge: thousands of evaluations on one instance.

:func:`path_run` takes a fresh instance in DAE mode and walks it around a closed path through
the sampled points (the start point, then each near point, back to the start;
``SEGMENT_STEPS`` evaluations on each segment, every known interpolated linearly), lap after
lap, until the budget of its level is spent: at every step it sets t, x, w and u
(fmi3SetTime, fmi3SetContinuousStates, fmi3SetFloat64) and reads the residuals and outputs
(fmi3GetFloat64) and the derivatives (fmi3GetContinuousStateDerivatives), and then makes every
other call an importer makes (:mod:`.calls`: event indicators, the state vector and
its nominals, directional and adjoint derivatives; and one instance instantiated and freed per
lap). Along the way it samples the worker's resident memory (VmRSS, Linux): every
``budget / samples`` calls, and besides whenever the peak resident size grew by a share of
``max_growth_mib`` since the last sample, so that a fast leak is sampled densely up to the stop.
The first call that fails ends the run; the same path point is then tried on a fresh instance,
which tells a failure that comes with use from one that belongs to the point. A run stopped
because memory grew by ``max_growth_mib`` ends as "memory": that growth is itself
``memory-grows``'s finding.

So that the growth can be told function by function, the mix of calls changes from one memory
sample to the next: between two samples one function of the step (in turn: each base call,
each optional call, the instance cycle) is *emphasised*, made ``EMPHASIS`` more times at every
step (the instance cycle once more every ``CYCLE_EVERY`` steps), and every sample records how
many calls of each function the library had made. ``memory-grows`` fits the growth on those
counts (:func:`conformance.numerics.growth.attribute`): a leak in one function follows that
function's count, whatever the others do.

The budget is counted, never timed, so that the run, and every verdict on it, is the same on
every machine: ``calls_<level>`` FMI calls, and ``values_<level>`` values set and read (the
lengths of the arrays a step passes), which keeps a model of 10,000 variables from taking a
thousand times longer than a small one. The wall clock (``seconds_<level>``) is a safety net
only: a run it stops ends as "time", and the rules that judge the run are then not run.

The run is made once per worker and kept in ``ctx.facts`` so that ``evaluation-fails-late``
and ``memory-grows`` judge the same run; its settings are the options of
``evaluation-fails-late`` (the catalogue's when that rule did not run first). A worker that
died during the run is not asked to run it again: a new worker learns from ``ctx.died``.
"""
from __future__ import annotations

import itertools
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...report.catalogue import default_catalogue
from ...runtime.child import heap_in_use, memory_info
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from ..instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from ..instruments.common import dae_of, error_evidence, layout_of
from ...runtime.arrays import pick, present
from .calls import INSTANCE_CYCLE, StepCalls

try:
    import resource
except ImportError:  # pragma: no cover - not POSIX: samples at the call interval only
    resource = None  # type: ignore[assignment]

SETTINGS_RULE = "evaluation-fails-late"
FACT = "endurance.path"
SEGMENT_STEPS = 16      # evaluations between two sampled points of the path
EMPHASIS = 2            # extra calls of the emphasised function at every step
CYCLE_EVERY = 8         # steps between two extra instance cycles when the cycle is emphasised
BASE_CALLS = ("fmi3SetTime", "fmi3SetContinuousStates", "fmi3SetFloat64", "fmi3GetFloat64",
              "fmi3GetContinuousStateDerivatives")
LEVELS = ("quick", "long")


@dataclass(frozen=True)
class RunSettings:
    """The budget of the path run at one level, and how often memory is sampled."""

    level: str
    calls: int
    values: int          # values set and read along the path (the arrays' lengths)
    seconds: float       # the safety net: a run it stops is not judged
    samples: int
    max_growth_mib: float

    @classmethod
    def from_options(cls, level: str, options: dict[str, Any]) -> RunSettings:
        return cls(level=level, calls=int(options[f"calls_{level}"]),
                   values=int(options[f"values_{level}"]),
                   seconds=float(options[f"seconds_{level}"]), samples=int(options["samples"]),
                   max_growth_mib=float(options["max_growth_mib"]))


@dataclass
class PathRun:
    """What the path run did: calls made, how it ended, the first failure, memory samples."""

    settings: RunSettings
    calls: int = 0                  # FMI calls made along the path
    steps: int = 0                  # evaluations completed
    laps: int = 0                   # complete laps of the path
    stopped: str = ""               # "budget", "time", "failure" or "memory"
    failure: dict[str, Any] | None = None
    samples: list[tuple[int, int]] = field(default_factory=list)  # (calls so far, VmRSS bytes)
    # the calls of each function of the rotation made so far, at each sample (its columns are
    # ``functions``); the instance cycle counts its fmi3InstantiateModelExchange
    counts: list[list[int]] = field(default_factory=list)
    # the C heap in use at each sample (``runtime.child.heap_in_use``; empty without it)
    heap: list[int] = field(default_factory=list)
    functions: list[str] = field(default_factory=list)
    # the address-space growth the library measured inside each FMI function, at the end
    grown_by: dict[str, int] = field(default_factory=dict)
    memory_note: str = ""           # why there are no memory samples
    budget_calls: int = 0           # the FMI calls the budget allows this model (see _Walk)
    calls_made: dict[str, Any] = field(default_factory=dict)   # StepCalls.info()

    def info(self) -> dict[str, Any]:
        """The summary for the report's ``info["endurance"]`` (no memory figures: they differ
        from run to run)."""
        return {"level": self.settings.level, "path_calls": self.calls,
                "path_steps": self.steps, "laps": self.laps, "stopped": self.stopped,
                "budget_calls": self.budget_calls, **self.calls_made}

    def out_of_time(self) -> str:
        """Why no rule judges a run the safety net stopped ("" when it did not)."""
        if self.stopped != "time":
            return ""
        return (f"time budget: the path run was stopped after {self.calls:,} of "
                f"{self.budget_calls:,} FMI calls by lsdae's wall-clock safety net "
                f"(seconds_{self.settings.level} = {self.settings.seconds:g} s of "
                f"{SETTINGS_RULE}): a faster machine would have gone on, so no verdict")


def level_of(ctx: ProbeContext) -> str:
    if ctx.endurance not in LEVELS:
        raise ProbeSkipped(f"the endurance stage is {ctx.endurance} (--endurance)")
    return ctx.endurance


def remember_settings(ctx: ProbeContext, options: dict[str, Any]) -> None:
    ctx.facts["endurance.settings"] = RunSettings.from_options(level_of(ctx), options)


def _settings(ctx: ProbeContext) -> RunSettings:
    settings = ctx.facts.get("endurance.settings")
    if not isinstance(settings, RunSettings):
        rule = default_catalogue()[SETTINGS_RULE]
        settings = RunSettings.from_options(level_of(ctx), rule.option_values)
    return settings


def path_run(ctx: ProbeContext, run_codes: Sequence[str]) -> PathRun:
    """The path run of this worker (made on first use); ProbeSkipped when it cannot be made,
    or when an earlier worker died during it (in one of ``run_codes``)."""
    memo = ctx.facts.get(FACT)
    if isinstance(memo, PathRun):
        return memo
    if isinstance(memo, ProbeSkipped):
        raise memo
    try:
        died = [code for code in run_codes if code in ctx.died]
        if died:
            raise ProbeSkipped(f"the path run ended an earlier worker during {died[0]} (see "
                               "its binary-* finding): not run again")
        settings = _settings(ctx)
        dae_of(ctx)
        run = _Walk(ctx, settings).walk()
    except ProbeSkipped as exc:
        ctx.facts[FACT] = exc
        raise
    ctx.facts[FACT] = run
    info = ctx.facts.setdefault("info", {})
    if isinstance(info, dict):
        info.setdefault("endurance", {}).update(run.info())
    return run


def lap_points(points: Sequence[Point], steps: int = SEGMENT_STEPS) -> list[Point]:
    """One lap of the closed path through ``points``: ``steps`` points per segment, every
    value interpolated linearly (the keys of the first point; time never below its least)."""
    if not points:
        return []
    keys = list(points[0].values)
    ring = [*points, points[0]] if len(points) > 1 else list(points)
    out = []
    for a, b in itertools.pairwise(ring):
        va = np.array([a.values[vr] for vr in keys], dtype=float)
        vb = np.array([b.values.get(vr, a.values[vr]) for vr in keys], dtype=float)
        for k in range(steps):
            s = k / steps
            values = dict(zip(keys, ((1 - s) * va + s * vb).tolist()))
            out.append(Point((1 - s) * a.t + s * b.t, values, f"{a.label}>{b.label}@{k}"))
    return out or [points[0]]


def _peak_bytes() -> float:
    """The peak resident size so far (getrusage: cheap enough for every step), 0 unknown."""
    if resource is None:
        return 0.0
    return float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024.0   # KiB (Linux)


def resident_bytes() -> int | None:
    """The worker's resident set (VmRSS), or None where /proc/self/status has none."""
    if not sys.platform.startswith("linux"):
        return None
    return memory_info().get("VmRSS")


class _Walk:
    def __init__(self, ctx: ProbeContext, settings: RunSettings):
        self.ctx, self.settings = ctx, settings
        self.layout: Layout = layout_of(ctx)
        self.library: Any = ctx.facts["library"]
        self.run = PathRun(settings)
        self.watch = tuple(dict.fromkeys([*self.layout.residuals, *self.layout.outputs]))
        self.nx = len(self.layout.states)
        self.extra = StepCalls(self.layout)
        self.first = 0
        self.emphasis = ""          # the function made EMPHASIS more times at every step
        self.rotation: list[str] = []

    def _budget_calls(self) -> int:
        """The FMI calls the budget allows: ``calls``, or fewer when the steps' arrays are so
        long that ``values`` runs out first (a count from the layout, not a clock)."""
        layout, nx = self.layout, self.nx
        knowns = len(layout.algebraic) + len(layout.inputs)
        calls_per_step = (1 + 2 * (nx > 0) + (knowns > 0) + (len(self.watch) > 0)
                          + len(self.extra.calls))
        values_per_step = max(1, 2 * nx + knowns + len(self.watch) + self.extra.values())
        steps = max(1, self.settings.values // values_per_step)
        return min(self.settings.calls, steps * calls_per_step)

    def _step(self, inst: Instance, point: Point) -> None:
        inst.set_point(point)
        inst.get_float64(self.watch)
        if self.nx:
            inst.get_derivatives(self.nx)
        self.extra.run(inst)
        if self.emphasis:
            self._emphasise(inst, point, self.emphasis)

    def _rotation(self, point: Point) -> list[str]:
        """The functions one step calls (each base call the layout makes, each optional call
        kept), and the instance cycle: the order in which they are emphasised."""
        layout = self.layout
        knowns = present(layout.algebraic, point.values) or present(layout.inputs,
                                                                     point.values)
        made = {"fmi3SetTime": True, "fmi3SetContinuousStates": self.nx > 0,
                "fmi3SetFloat64": bool(knowns), "fmi3GetFloat64": bool(self.watch),
                "fmi3GetContinuousStateDerivatives": self.nx > 0}
        return [name for name in BASE_CALLS if made[name]] + list(self.extra.calls) + [
            INSTANCE_CYCLE]

    def _emphasise(self, inst: Instance, point: Point, name: str) -> None:
        """The emphasised function, EMPHASIS more times at this step (the same arguments)."""
        if name == INSTANCE_CYCLE:
            if self.run.steps % CYCLE_EVERY == 0:
                self._new().free()
            return
        for _ in range(EMPHASIS):
            if name == "fmi3SetTime":
                inst.set_time(point.t)
            elif name == "fmi3SetContinuousStates":
                inst.set_states(pick(point.values, self.layout.states_for("dae")))
            elif name == "fmi3SetFloat64":
                knowns = [*present(self.layout.algebraic, point.values),
                          *present(self.layout.inputs, point.values)]
                inst.set_float64(knowns, pick(point.values, knowns))
            elif name == "fmi3GetFloat64":
                inst.get_float64(self.watch)
            elif name == "fmi3GetContinuousStateDerivatives":
                inst.get_derivatives(self.nx)
            else:
                self.extra.call(inst, name)

    def _count(self) -> list[int]:
        """The calls of each function of the rotation so far (the cycle: its instantiations)."""
        made = self.library.calls_by_function()
        key = {INSTANCE_CYCLE: "fmi3InstantiateModelExchange"}
        return [made.get(key.get(name, name), 0) for name in self.rotation]

    def _new(self) -> Instance:
        return self.ctx.new_instance("dae")  # type: ignore[return-value]

    def walk(self) -> PathRun:
        lap = lap_points(self.ctx.points)
        self.extra.prepare(self._new, lap[0])
        self.run.calls_made = self.extra.info()
        self.run.budget_calls = self._budget_calls()
        self.rotation = self.run.functions = self._rotation(lap[0])
        inst = self._new()
        try:
            self._loop(inst, lap)
        finally:
            inst.free()
        self.run.grown_by = self.library.growth_by_function()
        return self.run

    def _loop(self, inst: Instance, lap: list[Point]) -> None:
        run, settings = self.run, self.settings
        first = self.first = self.library.calls
        deadline = time.monotonic() + settings.seconds
        budget = run.budget_calls
        interval = max(1, budget // max(1, settings.samples))
        next_sample = 0
        limit = settings.max_growth_mib * (1 << 20)
        jump = limit / max(1, settings.samples)   # peak growth that takes a sample at once
        peak_at_sample = 0.0
        if resident_bytes() is None:
            run.memory_note = "resident memory is read from /proc/self/status (Linux only)"
        while not run.stopped:
            for k, point in enumerate(lap):
                run.calls = self.library.calls - first
                peak = _peak_bytes() if not run.memory_note else 0.0
                if not run.memory_note and (run.calls >= next_sample
                                            or peak - peak_at_sample > jump):
                    rss = resident_bytes()
                    if rss is not None:
                        run.samples.append((run.calls, rss))
                        run.counts.append(self._count())
                        heap = heap_in_use()
                        if heap is not None:
                            run.heap.append(heap)
                        peak_at_sample = peak
                        if rss - run.samples[0][1] > limit:
                            run.stopped = "memory"
                            break
                    if run.calls >= next_sample:
                        next_sample += interval
                        # the next function in turn is emphasised until the next sample
                        self.emphasis = self.rotation[(next_sample // interval)
                                                      % len(self.rotation)]
                if run.calls >= budget:
                    run.stopped = "budget"
                    break
                if time.monotonic() > deadline:  # the safety net: no verdict on this run
                    run.stopped = "time"
                    break
                try:
                    self._step(inst, point)
                except FmiError as exc:
                    run.calls = self.library.calls - first
                    run.stopped = "failure"
                    run.failure = self._failure(inst, exc, point, k)
                    break
                run.steps += 1
            else:
                run.laps += 1
                self._cycle(inst, lap[0])

    def _cycle(self, inst: Instance, point: Point) -> None:
        """One instance instantiated, initialised and freed, as importers do between runs."""
        try:
            self._new().free()
        except FmiError as exc:
            self.run.calls = self.library.calls - self.first
            self.run.stopped = "failure"
            self.run.failure = self._failure(inst, exc, point, 0)

    def _failure(self, inst: Instance, exc: FmiError, point: Point, index: int
                 ) -> dict[str, Any]:
        failure = {**error_evidence(exc), "calls_before": inst.calls - 1,
                   "calls_in_run": self.run.calls, "lap": self.run.laps + 1,
                   "step": self.run.steps + 1, "path_point": point.label, "t": point.t,
                   "values": {self.layout.name(vr): v for vr, v in point.values.items()}}
        failure["fresh_instance"] = self._fresh(point)
        return failure

    def _fresh(self, point: Point) -> str:
        """The same step on a fresh instance: "ok", or what failed there."""
        if self.library.fatal:
            return "not tried: fmi3Fatal invalidates every instance of the FMU"
        try:
            inst: Instance = self.ctx.new_instance("dae")  # type: ignore[assignment]
        except (FmiError, ProbeSkipped) as exc:
            return f"not tried: a fresh instance could not be started ({exc})"
        try:
            self._step(inst, point)
        except FmiError as exc:
            return f"{exc.call} returned {exc.status}"
        finally:
            inst.free()
        return "ok"
