"""Simulation probes (DAE801-DAE839): integrate the FMU in DAE mode (IDA) and ODE mode (CVODE).

The runs themselves are :func:`conformance.simulate.integrate.simulate_instance`; here they are
started on fresh instances, kept in ``ctx.facts`` so every rule reads the same runs, and judged:

* ``simulation-failed``: IDA (DAE mode) or CVODE (ODE mode) cannot get from the start to the
  stop time, or stalls, or no consistent initial point exists. This rule carries the simulation
  settings (tolerance, stop time, output grid, budgets, condition limits) for all of them;
* ``algebraic-jacobian-singular-along-trajectory``: dg/dw became singular on the way (the run
  stopped there instead of crawling on);
* ``evaluation-failed-during-simulation``: fmi3Discard/NaN that smaller steps did not get past,
  or fmi3Error;
* ``simulation-budget-exceeded``: our step or wall-clock budget ran out;
* ``ode-dae-trajectory-mismatch``: the two modes compared at common output times.

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

import numpy as np

from ..catalogue import default_catalogue
from ..findings import Location, Violation, evidence
from ..numerics import settings as st
from ..numerics.compare import compare
from ..numerics.settings import Settings, Trajectory
from ..simulate.integrate import simulate_instance
from .api import FmiError, ProbeContext, ProbeSkipped
from .common import layout_of, root_location

log = logging.getLogger(__name__)

SETTINGS_RULE = "simulation-failed"
MAX_PUBLISHED_TIMES = 100_000
SAME_CONDITION = 10.0   # dg/dw no worse than this factor of its start: not "along the way"


# ------------------------------------------------------------------------------- helpers

def _algebraic_location(ctx: ProbeContext, name: str | None) -> Location:
    """The manifest's AlgebraicVariable element of the variable called ``name``."""
    layout, m = layout_of(ctx), ctx.manifest
    vr = next((v for v in layout.algebraic if layout.name(v) == name), None)
    for ref in (m.algebraic if m is not None and vr is not None else ()):
        if ref.vr == vr:
            return Location(file=m.file, line=ref.line, path=ref.path)
    return root_location(ctx)


# ------------------------------------------------------------------------------- the runs

def _settings(ctx: ProbeContext) -> Settings:
    """The settings given to simulation-failed, else that rule's catalogue defaults."""
    settings = ctx.facts.get("simulation.settings")
    if not isinstance(settings, Settings):
        rule = default_catalogue().get(SETTINGS_RULE)
        settings = Settings.from_options(rule.option_values if rule else {})
        ctx.facts["simulation.settings"] = settings
    return settings


def _stop(ctx: ProbeContext, settings: Settings) -> tuple[float, float]:
    start = float(layout_of(ctx).start_time)
    experiment = getattr(ctx.model, "default_experiment", None)
    default = getattr(experiment, "stop_time", None) if experiment is not None else None
    return start, settings.stop(start, default)


def _run(ctx: ProbeContext, mode: str) -> Trajectory:
    """The run in ``mode`` ("dae" or "ode"), once per worker; ProbeSkipped if impossible, or
    when what ended it is another rule's (see :func:`_owned_elsewhere`)."""
    key = f"simulation.{mode}"
    memo = ctx.facts.get(key)
    if isinstance(memo, Trajectory):
        return memo
    if isinstance(memo, ProbeSkipped):
        raise memo
    try:
        if mode == "ode" and _settings(ctx).mode == "both":
            dae = _run(ctx, "dae")
            if not dae.ok:
                raise ProbeSkipped(f"not run: the DAE-mode run ended early at t = "
                                   f"{dae.t_end:.9g} ({dae.status})")
        traj = _simulate(ctx, mode)
        ctx.facts.setdefault("simulation.runs", {})[mode] = traj
        _publish(ctx)
        owner = _owned_elsewhere(traj)
        if owner:
            raise ProbeSkipped(owner)
    except ProbeSkipped as exc:
        ctx.facts[key] = exc
        raise
    except FmiError as exc:
        skipped = ProbeSkipped(f"the {mode.upper()}-mode instance could not be started: "
                               f"{exc.call} returned {exc.status}")
        ctx.facts[key] = skipped
        raise skipped from None
    ctx.facts[key] = traj
    return traj


def _owned_elsewhere(traj: Trajectory) -> str:
    """One fault, one finding: why another rule owns how ``traj`` ended, or "". A run that ends
    at its first point ends on something the point probes see (a rejected set, an evaluation
    that fails or is NaN at the start, an ODE mode that cannot evaluate); a dg/dw that was
    already as ill-conditioned at the start (within ``SAME_CONDITION``) is their finding too."""
    if traj.status == st.SINGULAR:
        start = traj.init.get("condition")
        end = traj.event.get("condition")
        start = float("inf") if start == "inf" else start
        end = float("inf") if end == "inf" else end
        if not traj.steps or (isinstance(start, float) and isinstance(end, float)
                              and end <= SAME_CONDITION * start):
            return ("dg/dw is as ill-conditioned at the initial point, where the run stopped "
                    "(algebraic-jacobian-ill-conditioned and -singular report it)")
    if traj.steps or traj.ok:
        return ""
    if traj.event.get("call") or traj.status == st.FMU_FAILED:
        what = traj.event.get("call") or "an evaluation"
        return (f"the {traj.mode.upper()}-mode run ends at its initial point ({what}: "
                f"{traj.message}): the point probes report it")
    return ""


def _simulate(ctx: ProbeContext, mode: str, settings: Settings | None = None) -> Trajectory:
    """One run in ``mode`` on a fresh instance, freed afterwards."""
    settings = settings or _settings(ctx)
    if settings.mode not in (mode, "both"):
        raise ProbeSkipped(f"the simulation runs in {settings.mode.upper()} mode only")
    layout = layout_of(ctx)
    start, stop = _stop(ctx, settings)
    if mode == "dae":
        if len(layout.residuals) != len(layout.algebraic):
            raise ProbeSkipped(f"{len(layout.residuals)} residuals for "
                               f"{len(layout.algebraic)} algebraic variables: no square DAE "
                               "to integrate (residual-count-mismatch)")
        if not layout.states and not layout.algebraic:
            raise ProbeSkipped("no states and no algebraic variables to integrate")
    elif not layout.ode_states:
        raise ProbeSkipped("no continuous states in ODE mode")
    inst = ctx.new_instance(mode)
    try:
        return simulate_instance(inst, layout, settings, start=start, stop=stop,
                                 model=ctx.model, manifest=ctx.manifest)
    finally:
        inst.free()


def _publish(ctx: ProbeContext) -> None:
    """ctx.facts["info"]["simulation"]: the primary run, the other mode, the comparison."""
    done = ctx.facts.get("simulation.runs") or {}
    runs = [done[m] for m in ("dae", "ode") if m in done]
    if not runs:
        return
    timing = _settings(ctx).record_wall_time
    info = runs[0].to_info(limit=MAX_PUBLISHED_TIMES, timing=timing)
    if len(runs) == 2:
        info["ode"] = runs[1].to_info(limit=MAX_PUBLISHED_TIMES, timing=timing)
        found = compare(runs[0], runs[1])
        if found is not None:
            info["comparison"] = {"gaps": found.gaps, "worst": found.worst,
                                  "compared_times": found.compared_times,
                                  "left_out": found.left_out,
                                  "gap_unit": "rtol * max(|dae|, |ode|) + atol_i"}
    ctx.facts.setdefault("info", {})["simulation"] = info


def _both(ctx: ProbeContext) -> list[Trajectory]:
    """The runs the settings ask for (the ODE-mode one only after a complete DAE-mode run)."""
    out = []
    for mode in ("dae", "ode"):
        try:
            out.append(_run(ctx, mode))
        except ProbeSkipped:
            continue
    if not out:
        _run(ctx, "dae" if _settings(ctx).mode != "ode" else "ode")  # raises the reason
    return out


def _points_fail(ctx: ProbeContext, mode: str) -> bool:
    """Whether evaluating at the sampled points already fails or gives NaN/Inf in ``mode``:
    then evaluation-failed, nan-or-inf or enable-handshake report it, not the simulation."""
    layout = layout_of(ctx)
    inst = ctx.dae if mode == "dae" else ctx.ode
    if inst is None:
        return False
    unknowns = ([*layout.derivatives, *layout.residuals] if mode == "dae"
                else list(layout.ode_derivatives))
    for point in ctx.points:
        try:
            values = inst.evaluate(point, unknowns)
        except (FmiError, ProbeSkipped):
            return True
        if not np.all(np.isfinite(values)):
            return True
    return False


def _run_evidence(traj: Trajectory, **extra: Any) -> Any:
    return evidence(
        mode=traj.mode, t_start=traj.t_start, t_reached=traj.t_end, stop_time=traj.stop_time,
        rtol=traj.rtol, atol="atol_factor * rtol * nominal of each variable", steps=traj.steps,
        jacobian=traj.jacobian, event=traj.event, **extra)


# ------------------------------------------------------------------------------ the probes

def simulation_failed(ctx: ProbeContext, **options: Any) -> Iterator[Violation]:
    """IDA integrates the FMU in DAE mode from a consistent initial point to the stop time,
    and CVODE in ODE mode (after a complete DAE-mode run). Carries the settings of all the
    simulation rules (``options``)."""
    settings = Settings.from_options(options)
    ctx.facts["simulation.settings"] = settings
    for traj in _both(ctx):
        if traj.status == st.INIT:
            yield Violation(
                "no consistent initial point in DAE mode: from the FMU's initial values, "
                f"Newton's method with the FMU's dg/dw fails ({traj.message})",
                root_location(ctx), _run_evidence(traj, init=traj.init), subject="dae:init")
        elif traj.status == st.SOLVER:
            solver = "IDA" if traj.mode == "dae" else "CVODE"
            yield Violation(
                f"{solver} cannot integrate the FMU in {traj.mode.upper()} mode: "
                f"{traj.message} (stop time {traj.stop_time:g})", root_location(ctx),
                _run_evidence(traj, init=traj.init), subject=f"{traj.mode}:solver")


def singular_along_trajectory(ctx: ProbeContext) -> Iterator[Violation]:
    """dg/dw stays non-singular along the DAE-mode trajectory (DAE-51)."""
    traj = _run(ctx, "dae")
    if traj.status != st.SINGULAR:
        return
    involved = list(traj.event.get("involved") or [])
    yield Violation(
        f"dg/dw becomes singular along the DAE-mode trajectory at t = {traj.event['t']:.9g}: "
        "the DAE is not index 1 there and the integration was stopped",
        _algebraic_location(ctx, involved[0] if involved else None),
        _run_evidence(traj, t=traj.event["t"], condition=traj.event.get("condition"),
                      threshold=traj.event.get("threshold"),
                      scale="1 / smallest singular value of dg/dw, columns scaled by nominal "
                            "values, rows by each residual's total sensitivity"),
        subject=involved[0] if involved else None)


def evaluation_failed_during_simulation(ctx: ProbeContext) -> Iterator[Violation]:
    """The FMU can be evaluated wherever the integrator needs it, or fails recoverably
    (fmi3Discard, NaN) where a smaller step gets past it. Failures the sampled points show too
    are the point probes' findings."""
    for traj in _both(ctx):
        if traj.status != st.FMU_FAILED or _points_fail(ctx, traj.mode):
            continue
        yield Violation(
            f"the FMU failed during the {traj.mode.upper()}-mode simulation at t = "
            f"{traj.event.get('t', traj.t_end):.9g}: {traj.message}", root_location(ctx),
            _run_evidence(traj, recovered=traj.recovered),
            subject=f"{traj.mode}:{traj.event.get('call', '')}")


def simulation_budget_exceeded(ctx: ProbeContext) -> Iterator[Violation]:
    """The run reaches the stop time within our step and wall-clock budget."""
    for traj in _both(ctx):
        if traj.status != st.BUDGET:
            continue
        yield Violation(
            f"the {traj.mode.upper()}-mode simulation was stopped at t = {traj.t_end:.9g} of "
            f"{traj.stop_time:g}: {traj.message}", root_location(ctx),
            _run_evidence(traj), subject=f"{traj.mode}:{traj.event.get('limit', '')}")


def _ode(ctx: ProbeContext) -> Trajectory:
    if layout_of(ctx).enable_status != "ok":
        raise ProbeSkipped("the FMU has no usable enable parameter, hence no ODE mode")
    return _run(ctx, "ode")


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
    dae = _run(ctx, "dae")
    found = compare(dae, ode)
    if found is None:
        raise ProbeSkipped("the two runs have no output time or variable in common")
    if found.largest <= factor:
        return
    start = compare(_first(dae), _first(ode))
    if start is not None and start.largest > factor:
        raise ProbeSkipped("the two modes differ at the initial point already "
                           "(ode-dae-inconsistent reports it)")
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
    yield Violation(
        f"DAE mode and ODE mode give different trajectories: {worst['variable']} differs by "
        f"{worst['gap']:.3g} tolerance units at t = {worst['t']:.9g} (limit {factor:g}), and "
        "not less with tighter tolerances", root_location(ctx),
        evidence(worst=worst, gaps=found.gaps, limit=factor, rtol=dae.rtol,
                 gap_unit="rtol * max(|dae|, |ode|) + atol_i, atol_i = atol_factor * rtol * "
                          "nominal_i", compared_times=found.compared_times,
                 left_out=found.left_out, dae_status=dae.status, ode_status=ode.status,
                 confirmation=tries),
        subject=str(worst["variable"]))


def _first(traj: Trajectory) -> Trajectory:
    return dataclasses.replace(traj, times=traj.times[:1], values=traj.values[:1])


def _confirm(ctx: ProbeContext, worst: dict[str, Any], rtol: float, *,
             budget_share: float) -> dict[str, Any]:
    """Both modes again at ``rtol``, on the same output grid, each with ``budget_share`` of
    the wall-clock budget: their difference at the worst variable and time."""
    settings = _settings(ctx)
    if rtol < 1e-13:
        return {"rtol": rtol, "note": "not confirmed: the tolerance cannot be tightened"}
    tight = dataclasses.replace(settings, rtol=rtol,
                                wall_seconds=settings.wall_seconds * budget_share)
    try:
        runs = [_simulate(ctx, mode, tight) for mode in ("dae", "ode")]
    except (ProbeSkipped, FmiError) as exc:
        return {"rtol": rtol, "note": f"not confirmed: {exc}"}
    values = []
    for traj in runs:
        if worst["t"] not in traj.times or worst["variable"] not in traj.names:
            return {"rtol": rtol, "note": f"not confirmed: the {traj.mode.upper()}-mode run "
                    f"ended at t = {traj.t_end:g} ({traj.status})"}
        values.append(float(traj.series(worst["variable"])[traj.times.index(worst["t"])]))
    return {"rtol": rtol, "dae": values[0], "ode": values[1],
            "difference": abs(values[0] - values[1])}


PROBES = {
    "DAE801": simulation_failed,
    "DAE802": singular_along_trajectory,
    "DAE803": evaluation_failed_during_simulation,
    "DAE804": simulation_budget_exceeded,
    "DAE805": ode_dae_trajectory_mismatch,
}
