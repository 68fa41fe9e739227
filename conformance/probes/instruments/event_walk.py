"""One walk through Event Mode per mode, as an importer drives it, shared by the event probes.

A fresh instance (in DAE mode and in ODE mode) is taken from its initial point through a few
event instants in increasing time: each time event the FMU announces (nextEventTime) and
fixed fractions of the experiment (0.25, 0.5, 0.75 and 0.95 of start to stop), which an
importer may also enter Event Mode at (step and input events). At each:

1. fmi3SetTime(t) in Continuous-Time Mode, the states read (fmi3GetContinuousStates);
2. fmi3EnterEventMode, then fmi3UpdateDiscreteStates until discreteStatesNeedUpdate is false
   (at most ``MAX_UPDATES`` calls), each call with its output arguments preset to a sentinel
   (the byte 0xA5 for the Booleans, which is neither false nor true; an impossible time for
   nextEventTime): a sentinel left in place is an output the FMU did not write;
3. in Event Mode, right after the iteration: the derivatives, outputs (and residuals in DAE
   mode) read with fmi3GetFloat64, and the states;
4. fmi3EnterContinuousTimeMode, then fmi3SetTime(t) and fmi3SetContinuousStates with the same
   values (and the same algebraic variables in DAE mode) and the same variables read again: a
   fresh evaluation at the same point.

The walk records what it saw; the probes (``events/updates.py``) decide. The states stay where the
initialisation left them (nothing is integrated): a legal call sequence at legal values, which
is all the checks need. A call that fails outside fmi3UpdateDiscreteStates ends the walk of
that mode without a finding (other probes report failing evaluations).
"""
from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...numerics.events import MAX_UPDATES
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from .api import FmiError, ProbeContext, ProbeSkipped
from .common import layout_of

FLAG_NAMES = ("discreteStatesNeedUpdate", "terminateSimulation",
              "nominalsOfContinuousStatesChanged", "valuesOfContinuousStatesChanged",
              "nextEventTimeDefined")
SENTINEL_FLAG = 0xA5          # a byte no C bool holds: the FMU did not write the argument
SENTINEL_TIME = -7.77e307     # a time no FMU announces
FRACTIONS = (0.25, 0.5, 0.75, 0.95)
MAX_EVENTS = 16               # event instants per walk
FACT = "event_walk"


@dataclass
class Instant:
    """One event instant of a walk: what the iteration said and what was read around it."""

    t: float
    updates: int = 0
    unwritten: tuple[str, ...] = ()          # output arguments the first such call left alone
    endless: bool = False                    # still discreteStatesNeedUpdate after MAX_UPDATES
    error: FmiError | None = None            # fmi3UpdateDiscreteStates failed
    next_time: float | None = None           # the last call's nextEventTime, when defined
    values_changed: bool = False
    states_before: np.ndarray | None = None
    states_after: np.ndarray | None = None
    vrs: tuple[int, ...] = ()
    at_event: np.ndarray | None = None       # read in Event Mode right after the iteration
    fresh: np.ndarray | None = None          # read again after setting the same point


@dataclass
class Walk:
    """The walk of one mode: the initialisation's nextEventTime and the instants visited."""

    mode: str
    start_time: float
    initial_next: float | None = None
    instants: list[Instant] = field(default_factory=list)
    stopped: str = ""                        # why the walk ended early, if it did


def walks(ctx: ProbeContext) -> list[Walk]:
    """The walks of every mode that can be started (memoised in ``ctx.facts``)."""
    held = ctx.facts.get(FACT)
    if held is None:
        layout = layout_of(ctx)
        held = []
        for mode in layout.modes:
            if getattr(ctx, mode) is None:
                continue
            held.append(_walk(ctx, layout, mode))
        ctx.facts[FACT] = held
    if not held:
        raise ProbeSkipped("no mode of the FMU could be started")
    return held  # type: ignore[return-value]


def stop_time(ctx: ProbeContext, start: float) -> float:
    """The DefaultExperiment's stopTime when it lies after ``start``, else start + 1."""
    experiment = getattr(ctx.model, "default_experiment", None)
    stop = getattr(experiment, "stop_time", None) if experiment is not None else None
    if stop is not None and math.isfinite(stop) and stop > start:
        return float(stop)
    return start + 1.0


def _walk(ctx: ProbeContext, layout: Layout, mode: str) -> Walk:
    t0 = layout.start_time
    walk = Walk(mode, t0)
    try:
        inst = ctx.new_instance(mode)
    except (FmiError, ProbeSkipped) as exc:
        walk.stopped = f"no fresh instance: {exc}"
        return walk
    try:
        discrete = inst.discrete
        walk.initial_next = discrete.next_time if discrete is not None else None
        _visit(ctx, layout, inst, walk)
    finally:
        inst.free()
    return walk


def _visit(ctx: ProbeContext, layout: Layout, inst: Instance, walk: Walk) -> None:
    t0 = walk.start_time
    stop = stop_time(ctx, t0)
    fixed = [t0 + f * (stop - t0) for f in FRACTIONS]
    announced = walk.initial_next
    t = t0
    nx = len(layout.states_for(walk.mode))
    vrs = tuple(dict.fromkeys([*layout.derivatives_for(walk.mode),
                               *layout.outputs_for(walk.mode),
                               *(layout.residuals if walk.mode == "dae" else ())]))
    algebraic = tuple(layout.algebraic) if walk.mode == "dae" else ()
    while len(walk.instants) < MAX_EVENTS:
        ahead = [s for s in fixed if s > t]
        if announced is not None and t < announced <= stop:
            ahead.append(announced)
        if not ahead:
            return
        t = min(ahead)
        instant = Instant(t, vrs=vrs)
        try:
            inst.set_time(t)
            instant.states_before = inst.get_states(nx)
            inst.enter_event_mode()
        except FmiError as exc:
            walk.stopped = f"{exc.call} returned {exc.status} at t = {t:.10g}"
            return
        walk.instants.append(instant)
        if not _iterate(inst, instant):
            return
        try:
            instant.states_after = inst.get_states(nx)
            instant.at_event = inst.get_float64(list(vrs))
            w = inst.get_float64(list(algebraic))
            inst.enter_continuous_time_mode()
            inst.set_time(t)
            inst.set_states(instant.states_after)
            inst.set_float64(list(algebraic), w)
            instant.fresh = inst.get_float64(list(vrs))
        except FmiError as exc:
            walk.stopped = f"{exc.call} returned {exc.status} at t = {t:.10g}"
            return
        announced = instant.next_time


def _iterate(inst: Instance, instant: Instant) -> bool:
    """The event iteration at ``instant``; False when the walk cannot go on."""
    for k in range(1, MAX_UPDATES + 1):
        try:
            flags, next_time = update_with_sentinels(inst)
        except FmiError as exc:
            instant.error = exc
            return False
        instant.updates = k
        unwritten = tuple(n for n, f in zip(FLAG_NAMES, flags) if f not in (0, 1))
        if flags[4] == 1 and next_time == SENTINEL_TIME:
            unwritten += ("nextEventTime",)
        if unwritten:
            instant.unwritten = unwritten
            return False
        needs, terminate, _, changed, defined = (bool(f) for f in flags)
        instant.values_changed = instant.values_changed or changed
        instant.next_time = float(next_time) if defined else None
        if terminate:
            return False
        if not needs:
            return True
    instant.endless = True
    return False


def update_with_sentinels(inst: Instance) -> tuple[list[int], float]:
    """One fmi3UpdateDiscreteStates with every output argument preset to a sentinel: the five
    Booleans as raw bytes (0, 1, or ``SENTINEL_FLAG`` when not written) and nextEventTime."""
    flags = [ctypes.c_uint8(SENTINEL_FLAG) for _ in FLAG_NAMES]
    next_time = ctypes.c_double(SENTINEL_TIME)
    as_bool: Any = ctypes.POINTER(ctypes.c_bool)
    inst.call("fmi3UpdateDiscreteStates",
              *(ctypes.cast(ctypes.pointer(f), as_bool) for f in flags), ctypes.byref(next_time))
    return [int(f.value) for f in flags], float(next_time.value)
