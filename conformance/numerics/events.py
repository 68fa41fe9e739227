"""Events during a simulation: state events found on the event indicators, time events, and the
event iteration, as an importer of a Model Exchange FMU runs them (FMI 3.0 §3.1.1, §3.2.2).

Between events the integrators (``dae.py``, ``ode.py``) root-find on the event indicators
``z(t, y)`` (IDA and CVODE root finding, both directions) and stop at the next time event. At an
event, :func:`event_update` does what FMI prescribes: the values at the event are set, Event Mode
is entered, ``fmi3UpdateDiscreteStates`` is called until the FMU needs no further update (at most
``MAX_UPDATES`` times), Continuous-Time Mode is entered again and, if the FMU says the values of
the states changed, they are read back. The update's ``nextEventTime`` is the next time event;
``terminateSimulation`` ends the run there, without error. :func:`run_through_events` drives a
:class:`~conformance.numerics.limits.Stepper` from event to event; the integrator restarts after
each one (in DAE mode from consistent algebraic variables, since the residuals may jump).

Everything here works on an :class:`EventSystem` (for an FMU: ``conformance.simulate.system``),
so it can be tested with plain Python models.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Protocol, Sequence

import numpy as np

from .limits import EvaluationFailed, Stepper, Stop
from .settings import FMU_FAILED

MAX_UPDATES = 100        # fmi3UpdateDiscreteStates calls at one event before we give up
LISTED_EVENTS = 1000     # event times kept in the trajectory (all are counted)
LISTED_BEHIND = 10       # nextEventTimes at or before their event kept (all are counted)
STATE, TIME = "state", "time"


class Update(Protocol):
    """What one fmi3UpdateDiscreteStates said (``runtime.instance.DiscreteStates``)."""

    needs_update: bool
    terminate: bool
    values_changed: bool
    next_time: float | None


class EventSystem(Protocol):
    """A system with event indicators and an event iteration; ``y`` as the integrator's."""

    indicator_names: Sequence[str]   # one per event indicator: nz = len(indicator_names)

    def indicators(self, t: float, y: np.ndarray) -> np.ndarray:
        """z at (t, y), shape (nz,); raises EvaluationFailed."""
        ...

    def enter_event_mode(self, t: float, y: np.ndarray) -> None:
        """Set (t, y), then enter Event Mode; raises EvaluationFailed."""
        ...

    def update_discrete_states(self) -> Update:
        """One fmi3UpdateDiscreteStates; raises EvaluationFailed."""
        ...

    def enter_continuous_time_mode(self) -> None: ...

    def read_states(self, y: np.ndarray) -> np.ndarray:
        """``y`` with the states replaced by the system's (after they changed at an event)."""
        ...


@dataclass
class Outcome:
    """What an event left: the values to go on from, whether to stop, the next time event."""

    y: np.ndarray
    terminate: bool
    next_time: float | None
    updates: int
    states_changed: bool
    announced: float | None = None   # the nextEventTime the FMU gave, ahead or not


@dataclass
class EventLog:
    """The events of one run: counts by kind, their times (the first ``LISTED_EVENTS``), the
    update calls, where the FMU asked to terminate, and (DAE mode) the largest residual the
    consistent restart after an event started from."""

    indicators: int = 0
    state: int = 0
    time: int = 0
    times: list[float] = field(default_factory=list)
    updates: int = 0
    terminated_at: float | None = None
    residual_jump: float = 0.0
    # (t, nextEventTime) of the events whose announced next time event was not ahead (the
    # first LISTED_BEHIND), and how many there were: the run drops them (``_future``)
    behind: list[tuple[float, float]] = field(default_factory=list)
    behind_count: int = 0

    def add(self, kind: str, t: float, outcome: Outcome) -> None:
        if kind == STATE:
            self.state += 1
        else:
            self.time += 1
        if len(self.times) < LISTED_EVENTS:
            self.times.append(float(t))
        announced = outcome.announced
        if announced is not None and not outcome.terminate and announced <= t:
            self.behind_count += 1
            if len(self.behind) < LISTED_BEHIND:
                self.behind.append((float(t), float(announced)))
        self.updates += outcome.updates
        if outcome.terminate:
            self.terminated_at = float(t)


def read_indicators(system: EventSystem, t: float, y: np.ndarray) -> np.ndarray:
    """z at (t, y) for the integrator's events function. A failed or non-finite reading ends
    the run: the root finding cannot step around it as the step control steps around a failed
    residual."""
    try:
        z = np.asarray(system.indicators(t, y), dtype=float)
    except EvaluationFailed as exc:
        raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status}", t, call=exc.call,
                   status=exc.status, log=list(exc.log)[:5]) from None
    if not np.all(np.isfinite(z)):
        bad = [str(n) for n, v in zip(system.indicator_names, z) if not np.isfinite(v)]
        raise Stop(FMU_FAILED, "fmi3GetEventIndicators gave NaN or Inf", t,
                   call="fmi3GetEventIndicators", status="NaN or Inf", indicators=bad[:5])
    return z


def event_update(system: EventSystem, t: float, y: np.ndarray, *,
                 max_updates: int = MAX_UPDATES) -> Outcome:
    """The event iteration at (t, y): Event Mode, fmi3UpdateDiscreteStates until no further
    update is needed or the FMU asks to terminate, Continuous-Time Mode (not after a request to
    terminate), and the states read back when their values changed. Raises Stop(FMU_FAILED)
    when a call fails or the iteration does not settle in ``max_updates`` calls."""
    changed = False
    try:
        system.enter_event_mode(t, y)
        for updates in range(1, max_updates + 1):
            update = system.update_discrete_states()
            changed = changed or bool(update.values_changed)
            if update.terminate or not update.needs_update:
                break
        else:
            raise Stop(FMU_FAILED, f"fmi3UpdateDiscreteStates still asked for another update "
                       f"after {max_updates} calls at the event at t = {t:.10g}", t,
                       call="fmi3UpdateDiscreteStates", status="discreteStatesNeedUpdate",
                       updates=max_updates)
        if update.terminate:
            return Outcome(np.asarray(y, dtype=float), True, None, updates, changed)
        system.enter_continuous_time_mode()
        out = system.read_states(np.asarray(y, dtype=float)) if changed else np.asarray(y, float)
    except EvaluationFailed as exc:
        raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status} at the event at "
                   f"t = {t:.10g}", t, call=exc.call, status=exc.status,
                   log=list(exc.log)[:5]) from None
    if not np.all(np.isfinite(out)):
        raise Stop(FMU_FAILED, f"the states after the event at t = {t:.10g} are not finite",
                   t, call="fmi3GetContinuousStates", status="NaN or Inf")
    return Outcome(out, False, _future(update.next_time, t), updates, changed,
                   _announced(update.next_time))


def _announced(next_time: float | None) -> float | None:
    """The nextEventTime as the FMU gave it, when defined and a number."""
    if next_time is None or not np.isfinite(next_time):
        return None
    return float(next_time)


def _future(next_time: float | None, t: float) -> float | None:
    """A nextEventTime that lies ahead (one at or before t is no event: FMI requires it ahead)."""
    if next_time is None or not np.isfinite(next_time) or next_time <= t:
        return None
    return float(next_time)


def first_time_event(update: Any, t0: float) -> float | None:
    """The time event the update at the end of initialisation scheduled (or None)."""
    return _future(getattr(update, "next_time", None), t0) if update is not None else None


def run_through_events(stepper: Stepper, system: EventSystem, log: EventLog, *,
                       next_time: float | None,
                       restart: Callable[[float, np.ndarray], np.ndarray]) -> None:
    """Drive ``stepper`` to the end of its output times through the events: at a root of the
    indicators (a state event) or at ``next_time`` (a time event, at or before the stop time),
    run :func:`event_update`, then ``restart(t, y)`` (which re-initialises the integrator at
    ``t`` and returns the values it starts from) unless the FMU asked to terminate.

    Returns when the outputs are recorded, a step failed (``stepper.failure``) or the FMU ended
    the run (``log.terminated_at``); raises Stop as the stepper and the event update do.
    """
    while not stepper.done:
        until = next_time if next_time is not None and next_time <= stepper.stop else None
        stepper.run(until)
        if stepper.failure is not None:
            return
        if stepper.root:
            kind = STATE
        elif until is not None and stepper.t >= until:
            kind = TIME
        else:
            return
        t = stepper.t
        outcome = event_update(system, t, stepper.y)
        log.add(kind, t, outcome)
        if outcome.terminate:
            stepper.restart(t, outcome.y)  # an output time at t: the values the run ended with
            return
        next_time = outcome.next_time
        stepper.restart(t, restart(t, outcome.y))


def summarise(log: EventLog, traj: Any) -> None:
    """Copy the events of ``log`` into the trajectory; a run the FMU ended is still ``ok``, with
    a note in its message and ``event``."""
    traj.indicators, traj.state_events, traj.time_events = log.indicators, log.state, log.time
    traj.event_times, traj.event_updates = list(log.times), log.updates
    traj.terminated_at, traj.residual_jump = log.terminated_at, log.residual_jump
    traj.events_behind, traj.events_behind_count = list(log.behind), log.behind_count
    if log.terminated_at is not None and traj.ok:
        traj.message = (f"the FMU ended the run at t = {log.terminated_at:.10g} "
                        "(terminateSimulation)")
        traj.event = {"t": log.terminated_at, "terminate_simulation": True}
