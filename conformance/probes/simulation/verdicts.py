"""Simulation probes (DAE801-DAE839): integrate the FMU in DAE mode (IDA) and ODE mode (CVODE).

The runs themselves are :func:`conformance.simulate.integrate.simulate_instance`, started and
shared by :mod:`.runs` so that every rule reads the same runs; here they are judged:

* ``simulation-failed``: IDA (DAE mode) or CVODE (ODE mode) cannot get from the start to the
  stop time, or stalls, or no consistent initial point exists. This rule carries the simulation
  settings (tolerance, stop time, output grid, budgets, condition limits) for all of them;
* ``algebraic-jacobian-singular-along-trajectory``: dg/dw became singular on the way (the run
  stopped there instead of crawling on);
* ``evaluation-failed-during-simulation``: fmi3Discard/NaN that smaller steps did not get past,
  or fmi3Error;
* ``simulation-budget-exceeded``: our budget of steps ran out (a run that lsdae's wall-clock
  safety net stopped is judged by no rule: the simulation rules are not run then);
* ``ode-dae-trajectory-mismatch``: the two modes compared at common output times;
* ``next-event-time-behind-during-simulation``: at an event of either run (a state event found
  by root finding on the trajectory, or a time event) the FMU announced a nextEventTime at or
  before the event's time, which the run could only drop.

One fault, one finding: the ODE-mode run only follows a complete DAE-mode run; a run that ends
at its first point, a dg/dw as bad at the start as where a run stopped, a failure the sampled
points show too, and modes that differ at the initial point already are the point probes'
findings (evaluation-failed, nan-or-inf, enable-handshake, algebraic-jacobian-ill-conditioned
and -singular, ode-dae-inconsistent), not the simulation's.

The trajectory summary goes to the report's ``info["simulation"]`` for the HTML plot: the
DAE-mode run (or the ODE-mode one with mode ``ode``), its ``times``, ``series`` by variable name,
``mode``, ``rtol``, ``steps`` and more (``wall_s`` with ``record_wall_time``), with the ODE-mode
run under ``"ode"`` and the comparison under ``"comparison"`` (see docs/simulate.md).
"""
from __future__ import annotations

import dataclasses
import logging
from typing import Any, Iterator

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ...numerics import settings as st
from ...numerics.compare import compare
from ...numerics.dae import STALLED_SINGULAR
from ...numerics.settings import Settings, Trajectory
from ..instruments.api import (EVENT_INDICATOR_FAULT, NEXT_EVENT_FAULT, ODE_DAE_FAULT, PLANNED,
                               FmiError, ProbeContext, ProbeSkipped)
from ..instruments.common import layout_of, root_location, var_location
from .runs import (OutOfTime, both_runs, points_fail, run, run_evidence, settings_of, simulate_mode,
                   time_budget)

log = logging.getLogger(__name__)


# ------------------------------------------------------------------------------- helpers

def _algebraic_location(ctx: ProbeContext, name: str | None) -> Location:
    """The manifest's AlgebraicVariable element of the variable called ``name``."""
    layout, m = layout_of(ctx), ctx.manifest
    vr = next((v for v in layout.algebraic if layout.name(v) == name), None)
    for ref in (m.algebraic if m is not None and vr is not None else ()):
        if ref.vr == vr:
            return Location(file=m.file, line=ref.line, path=ref.path)
    return root_location(ctx)


def _declared_location(ctx: ProbeContext, name: str) -> Location:
    """Where the variable called ``name`` is declared: an algebraic variable at its manifest
    element, any other at its modelDescription.xml element; the manifest's root when no
    variable has the name."""
    if any(layout_of(ctx).name(vr) == name for vr in layout_of(ctx).algebraic):
        return _algebraic_location(ctx, name)
    model = ctx.model
    var = next((v for v in (model.by_vr.values() if model is not None else ())
                if v.name == name), None)
    return var_location(ctx, var.vr) if var is not None else root_location(ctx)


# ------------------------------------------------------------------------------ the probes

def simulation_failed(ctx: ProbeContext, **options: Any) -> Iterator[Violation]:
    """IDA integrates the FMU in DAE mode from a consistent initial point to the stop time,
    and CVODE in ODE mode (after a complete DAE-mode run). Carries the settings of all the
    simulation rules (``options``)."""
    settings = Settings.from_options(options)
    ctx.facts["simulation.settings"] = settings
    for traj in both_runs(ctx):
        if traj.status == st.INIT:
            yield Violation(
                "no consistent initial point in DAE mode: from the FMU's initial values, "
                f"Newton's method with the FMU's dg/dw fails ({traj.message})",
                root_location(ctx), run_evidence(traj, init=traj.init), subject="dae:init",
                part="no-consistent-start")
        elif traj.status == st.SOLVER:
            solver = "IDA" if traj.mode == "dae" else "CVODE"
            # numerics.dae._restart: Newton found no consistent algebraic variables after an
            # event (a solver failure that carries after_event)
            restart = traj.mode == "dae" and bool(traj.event.get("after_event"))
            yield Violation(
                f"{solver} cannot integrate the FMU in {traj.mode.upper()} mode: "
                f"{traj.message} (stop time {traj.stop_time:g})", root_location(ctx),
                run_evidence(traj, init=traj.init), subject=f"{traj.mode}:solver",
                part="restart-after-event" if restart else None)


def singular_along_trajectory(ctx: ProbeContext) -> Iterator[Violation]:
    """dg/dw stays non-singular along the DAE-mode trajectory (DAE-51)."""
    traj = run(ctx, "dae")
    if traj.status != st.SINGULAR:
        return
    involved = list(traj.event.get("involved") or [])
    # numerics.dae._diagnose_at_end: a run that failed, stalled or ran out of steps where dg/dw
    # was worse than stalled_condition, not stopped by max_condition on the way
    stalled = traj.message == STALLED_SINGULAR
    yield Violation(
        f"dg/dw becomes singular along the DAE-mode trajectory at t = {traj.event['t']:.9g}: "
        "the DAE is not index 1 there and the integration was stopped",
        _algebraic_location(ctx, involved[0] if involved else None),
        run_evidence(traj, t=traj.event["t"], condition=traj.event.get("condition"),
                      threshold=traj.event.get("threshold"),
                      scale="1 / smallest singular value of dg/dw, columns scaled by nominal "
                            "values, rows by each residual's total sensitivity"),
        subject=involved[0] if involved else None,
        part="stalled-run-blamed" if stalled else None)


def evaluation_failed_during_simulation(ctx: ProbeContext) -> Iterator[Violation]:
    """The FMU can be evaluated wherever the integrator needs it, or fails recoverably
    (fmi3Discard, NaN) where a smaller step gets past it. Failures the sampled points show too
    are the point probes' findings."""
    for traj in both_runs(ctx):
        if traj.status != st.FMU_FAILED or points_fail(ctx, traj.mode):
            continue
        yield Violation(
            f"the FMU failed during the {traj.mode.upper()}-mode simulation at t = "
            f"{traj.event.get('t', traj.t_end):.9g}: {traj.message}", root_location(ctx),
            run_evidence(traj, recovered=traj.recovered),
            subject=f"{traj.mode}:{traj.event.get('call', '')}")


def simulation_budget_exceeded(ctx: ProbeContext) -> Iterator[Violation]:
    """The run reaches the stop time within our budget of steps (a count: the same verdict on
    every machine)."""
    for traj in both_runs(ctx):
        if traj.status != st.BUDGET:
            continue
        yield Violation(
            f"the {traj.mode.upper()}-mode simulation was stopped at t = {traj.t_end:.9g} of "
            f"{traj.stop_time:g}: {traj.message}", root_location(ctx),
            run_evidence(traj), subject=f"{traj.mode}:{traj.event.get('limit', '')}")


def _ode(ctx: ProbeContext) -> Trajectory:
    if layout_of(ctx).enable_status != "ok":
        raise ProbeSkipped("the FMU has no usable enable parameter, hence no ODE mode")
    return run(ctx, "ode")


def ode_dae_trajectory_mismatch(ctx: ProbeContext, *, factor: float,
                                confirm_rtol_ratio: float, confirm_levels: int,
                                confirm_shrink: float) -> Iterator[Violation]:
    """DAE mode and ODE mode give the same trajectories, within ``factor`` tolerance units.

    A gap above ``factor`` is confirmed at tighter tolerances (``confirm_rtol_ratio`` times
    the last, at most ``confirm_levels`` times): a gap that is the integrators' error shrinks
    (to ``confirm_shrink`` of the first or less), one that is the model's does not. Robertson
    in ODE mode drifts to negative concentrations and diverges up to rtol 3e-7; the FMU is
    fine."""
    ode = _ode(ctx)
    dae = run(ctx, "dae")
    fault = ctx.facts.get(EVENT_INDICATOR_FAULT)
    if fault and (dae.has_events or ode.has_events):
        raise ProbeSkipped(f"the runs root-find on event indicators that are faulty in DAE mode "
                           f"({str(fault)[:160]}); that finding is the cause of any gap")
    found = compare(dae, ode)
    if found is None:
        raise ProbeSkipped("the two runs have no output time or variable in common")
    if found.largest <= factor:
        return
    start = compare(_first(dae), _first(ode))
    if start is not None and start.largest > factor:
        owner = _initial_gap_owner(ctx, start, factor)
        if owner:
            raise ProbeSkipped(owner)
        # No rule of this check owns it (under lsdae simulate no point probe runs, or the
        # sampled points missed it): the verdict is this rule's, at the initial point. Both
        # runs start from the same states: the modes contradict each other at that point (the
        # rule's own case). They start from other states: the initialisations differ, which
        # alpha.1 leaves open for DAE mode (the part).
        part = {} if _same_states(start, dae, factor) else dict(part="initial-gap")
        yield _mismatch(found, start.worst, factor, dae, ode, [],
                        at="already at the initial point",
                        location=_declared_location(ctx, str(start.worst["variable"])), **part)
        return
    worst = found.worst
    tries = []
    rtol = dae.rtol
    for _ in range(max(0, int(confirm_levels))):
        rtol *= confirm_rtol_ratio
        tries.append(_confirm(ctx, worst, rtol, budget_share=1.0 / (2 * confirm_levels)))
        difference = tries[-1].get("difference")
        if isinstance(difference, float) and difference <= confirm_shrink * worst["difference"]:
            return  # integration error: it shrinks with the tolerance
        if "difference" not in tries[-1]:
            break
    yield _mismatch(found, worst, factor, dae, ode, tries, at="and not less with tighter "
                    "tolerances", location=_declared_location(ctx, str(worst["variable"])),
                    part="after-events" if _born_after_event(dae, ode, factor) else None)


def _same_states(start: Any, dae: Trajectory, factor: float) -> bool:
    """Whether the two runs' states agree at the initial point (within ``factor`` tolerance
    units), so that a gap there is in what the modes compute from them."""
    states = {n for n, kind in zip(dae.names, dae.kinds) if kind == "state"}
    return all(gap <= factor for name, gap in start.gaps.items() if name in states)


#: The rule that judges whether fresh instances of one process start alike.
INSTANCES_RULE = "DAE762"


def _initial_gap_owner(ctx: ProbeContext, start: Any, factor: float) -> str:
    """Why a gap between the two runs at their first output time is another rule's first
    cause, or "": ode-dae-inconsistent reported the modes apart at a point, or the runs' fresh
    instances start from different states, which instances-not-independent judges when it is
    to run (the endurance probes run last)."""
    first_cause = ctx.facts.get(ODE_DAE_FAULT)
    if first_cause:
        return (f"the two modes differ at the initial point already, the first cause of the "
                f"gap ({str(first_cause)[:160]})")
    layout = layout_of(ctx)
    states = [layout.name(vr) for vr in layout.states]
    apart = [name for name in states if start.gaps.get(name, 0.0) > factor]
    if apart and INSTANCES_RULE in ctx.facts.get(PLANNED, ()):
        return (f"the two runs' fresh instances start from different states ({apart[0]}), "
                "so the gap is not the modes'; instances-not-independent judges the instances")
    return ""


def _mismatch(found: Any, worst: dict[str, Any], factor: float, dae: Trajectory,
              ode: Trajectory, tries: list[dict[str, Any]], *, at: str, location: Location,
              part: str | None = None) -> Violation:
    return Violation(
        f"DAE mode and ODE mode give different trajectories: {worst['variable']} differs by "
        f"{worst['gap']:.3g} tolerance units at t = {worst['t']:.9g} (limit {factor:g}), {at}",
        location,
        evidence(worst=worst, gaps=found.gaps, limit=factor, rtol=dae.rtol,
                 gap_unit="rtol * max(|dae|, |ode|) + atol_i, atol_i = atol_factor * rtol * "
                          "nominal_i", compared_times=found.compared_times,
                 left_out=found.left_out, dae_status=dae.status, ode_status=ode.status,
                 confirmation=tries),
        subject=str(worst["variable"]), part=part, cause=causes.through(str(worst["variable"])))


def _first(traj: Trajectory) -> Trajectory:
    return dataclasses.replace(traj, times=traj.times[:1], values=traj.values[:1])


def _born_after_event(dae: Trajectory, ode: Trajectory, factor: float) -> bool:
    """Whether the gap between the runs is born at or after an event: the runs had one, and
    at the output times before the first event of either run they agree within ``factor``
    (lsdae re-solves the algebraic variables after each event in DAE mode; alpha.1 2.2 leaves
    event handling out of scope)."""
    first = min(dae.event_times[:1] + ode.event_times[:1], default=None)
    if first is None:
        return False
    before = compare(_until(dae, first), _until(ode, first))
    return before is None or before.largest <= factor


def _until(traj: Trajectory, t: float) -> Trajectory:
    """``traj`` at its output times before ``t``."""
    n = sum(1 for time in traj.times if time < t)
    return dataclasses.replace(traj, times=traj.times[:n], values=traj.values[:n])


def _confirm(ctx: ProbeContext, worst: dict[str, Any], rtol: float, *,
             budget_share: float) -> dict[str, Any]:
    """Both modes again at ``rtol``, on the same output grid, each with ``budget_share`` of
    the wall-clock budget: their difference at the worst variable and time."""
    settings = settings_of(ctx)
    if rtol < 1e-13:
        return {"rtol": rtol, "note": "not confirmed: the tolerance cannot be tightened"}
    tight = dataclasses.replace(settings, rtol=rtol,
                                wall_seconds=settings.wall_seconds * budget_share)
    try:
        runs = [simulate_mode(ctx, mode, tight) for mode in ("dae", "ode")]
    except (ProbeSkipped, FmiError) as exc:
        return {"rtol": rtol, "note": f"not confirmed: {exc}"}
    values = []
    for traj in runs:
        if traj.status == st.TIME_BUDGET:  # the safety net: no verdict may rest on it
            raise OutOfTime(f"{time_budget(traj)} (a confirmation run at rtol {rtol:g})")
        if worst["t"] not in traj.times or worst["variable"] not in traj.names:
            return {"rtol": rtol, "note": f"not confirmed: the {traj.mode.upper()}-mode run "
                    f"ended at t = {traj.t_end:g} ({traj.status})"}
        values.append(float(traj.series(worst["variable"])[traj.times.index(worst["t"])]))
    return {"rtol": rtol, "dae": values[0], "ode": values[1],
            "difference": abs(values[0] - values[1])}


def next_event_time_behind_during_simulation(ctx: ProbeContext) -> Iterator[Violation]:
    """SM-06, FMI 3.0.2 §3.1: at every event of the runs, a defined nextEventTime lies after
    the event (the walk of next-event-time-not-ahead enters Event Mode at fixed instants only;
    the runs reach the state events of the trajectory). One fault, one finding: when
    next-event-time-not-ahead has reported it already, this rule leaves it there."""
    fault = ctx.facts.get(NEXT_EVENT_FAULT)
    if fault:
        raise ProbeSkipped(f"next-event-time-not-ahead reports the fault already "
                           f"({str(fault)[:160]})")
    for traj in both_runs(ctx):
        if not traj.events_behind:
            continue
        t, announced = traj.events_behind[0]
        yield Violation(
            f"at the event at t = {t:.17g} of the {traj.mode.upper()}-mode simulation, "
            f"fmi3UpdateDiscreteStates announces nextEventTime = {announced:.17g}, not after "
            f"the event ({traj.events_behind_count} such event(s) in the run): the run can "
            "only drop it", root_location(ctx),
            run_evidence(traj, t=t, next_event_time=announced, behind=t - announced,
                         events_behind=[list(e) for e in traj.events_behind],
                         count=traj.events_behind_count,
                         place=f"{traj.mode.upper()}-mode simulation, t = {t:.10g}"),
            subject=f"{traj.mode}:nextEventTime", cause=causes.NEXT_EVENT_NOT_AHEAD)


PROBES = {
    "DAE801": simulation_failed,
    "DAE802": singular_along_trajectory,
    "DAE803": evaluation_failed_during_simulation,
    "DAE804": simulation_budget_exceeded,
    "DAE805": ode_dae_trajectory_mismatch,
    "DAE807": next_event_time_behind_during_simulation,
}
