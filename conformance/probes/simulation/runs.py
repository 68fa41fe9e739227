"""The simulation runs the simulation probes judge: started once per worker, shared, published.

:func:`run` integrates the FMU in one mode on a fresh instance (through
:func:`conformance.simulate.integrate.simulate_instance`), once per worker: the trajectory, or
the reason there is none, is kept in ``ctx.facts`` so that every simulation rule reads the same
run. :func:`publish` puts the runs and their comparison into the report's
``info["simulation"]``. :func:`owned_elsewhere` and :func:`points_fail` say when the way a run
ended is another rule's finding (one fault, one finding).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ...report.catalogue import default_catalogue
from ...report.findings import evidence
from ...numerics import settings as st
from ...numerics.compare import compare
from ...numerics.settings import Settings, Trajectory
from ...simulate.integrate import simulate_instance
from ...simulate.jacobian_check import DerivativeCheck
from ..instruments.api import FmiError, ProbeContext, ProbeSkipped
from ..instruments.common import layout_of
from ..instruments.entry_comparison import directional_options, directional_verdict
from ..instruments.jacobian import FACT, Survey

SETTINGS_RULE = "simulation-failed"
MAX_PUBLISHED_TIMES = 100_000
SAME_CONDITION = 10.0   # dg/dw no worse than this factor of its start: not "along the way"


def settings_of(ctx: ProbeContext) -> Settings:
    """The settings given to simulation-failed, else that rule's catalogue defaults."""
    settings = ctx.facts.get("simulation.settings")
    if not isinstance(settings, Settings):
        rule = default_catalogue().get(SETTINGS_RULE)
        settings = Settings.from_options(rule.option_values if rule else {})
        ctx.facts["simulation.settings"] = settings
    return settings


def start_and_stop(ctx: ProbeContext, settings: Settings) -> tuple[float, float]:
    start = float(layout_of(ctx).start_time)
    experiment = getattr(ctx.model, "default_experiment", None)
    default = getattr(experiment, "stop_time", None) if experiment is not None else None
    return start, settings.stop(start, default)


def run(ctx: ProbeContext, mode: str) -> Trajectory:
    """The run in ``mode`` ("dae" or "ode"), once per worker; ProbeSkipped if impossible, or
    when what ended it is another rule's (see :func:`_owned_elsewhere`)."""
    key = f"simulation.{mode}"
    memo = ctx.facts.get(key)
    if isinstance(memo, Trajectory):
        return memo
    if isinstance(memo, ProbeSkipped):
        raise memo
    try:
        if mode == "ode" and settings_of(ctx).mode == "both":
            dae = run(ctx, "dae")
            if not dae.ok:
                raise ProbeSkipped(f"the DAE-mode run ended early at t = "
                                   f"{dae.t_end:.9g} ({dae.status})")
        traj = simulate_mode(ctx, mode)
        ctx.facts.setdefault("simulation.runs", {})[mode] = traj
        publish(ctx)
        if traj.status == st.TIME_BUDGET:
            raise OutOfTime(time_budget(traj))
        owner = owned_elsewhere(traj)
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


class OutOfTime(ProbeSkipped):
    """A run was stopped by the wall-clock safety net: no simulation rule may judge."""


def time_budget(traj: Trajectory) -> str:
    """Why no rule judges a run the wall-clock safety net stopped."""
    return (f"time budget: the {traj.mode.upper()}-mode run was stopped at t = "
            f"{traj.t_end:.9g} of {traj.stop_time:g} after {traj.steps} steps by lsdae's "
            f"wall-clock safety net (wall_seconds = {traj.event.get('value')} s of "
            "simulation-failed): a faster machine could have finished it, so no verdict")


def owned_elsewhere(traj: Trajectory) -> str:
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


def simulate_mode(ctx: ProbeContext, mode: str, settings: Settings | None = None) -> Trajectory:
    """One run in ``mode`` on a fresh instance, freed afterwards."""
    settings = settings or settings_of(ctx)
    if settings.mode not in (mode, "both"):
        raise ProbeSkipped(f"the simulation runs in {settings.mode.upper()} mode only")
    layout = layout_of(ctx)
    start, stop = start_and_stop(ctx, settings)
    if mode == "dae":
        if len(layout.residuals) != len(layout.algebraic):
            raise ProbeSkipped(f"{len(layout.residuals)} residuals for "
                               f"{len(layout.algebraic)} algebraic variables: no square DAE "
                               "to integrate (residual-count-mismatch)")
        if not layout.states and not layout.algebraic:
            raise ProbeSkipped("no states and no algebraic variables to integrate")
    elif not layout.ode_states:
        raise ProbeSkipped("no continuous states in ODE mode")
    by_name = {layout.name(vr): vr for vr in layout.names}
    start_values = {by_name[name]: value for name, value in settings.start_values
                    if name in by_name}
    inst = ctx.new_instance(mode, start_values=start_values) if start_values else \
        ctx.new_instance(mode)
    try:
        return simulate_instance(inst, layout, settings, start=start, stop=stop,
                                 model=ctx.model, manifest=ctx.manifest,
                                 derivatives=derivative_check(ctx))
    finally:
        inst.free()


def derivative_check(ctx: ProbeContext) -> DerivativeCheck:
    """Whether the runs may use the FMU's directional derivatives: the verdict of the
    derivative probes' survey when it ran in this worker (for both modes: derivatives refuted
    in DAE mode are not trusted in ODE mode either), else a check at the initial point of each
    run; both with the options of directional-derivative-mismatch."""
    options = directional_options(ctx)
    survey = ctx.facts.get(FACT)
    verdict = None
    if isinstance(survey, Survey) and survey.layout is not None and survey.points:
        use, note = directional_verdict(ctx, survey)
        verdict = "" if use else note
    return DerivativeCheck(rtol=float(options["rtol"]), margin=float(options["margin"]),
                           ulps=float(options["ulps"]), verdict=verdict)


def publish(ctx: ProbeContext) -> None:
    """ctx.facts["info"]["simulation"]: the primary run, the other mode, the comparison."""
    done = ctx.facts.get("simulation.runs") or {}
    runs = [done[m] for m in ("dae", "ode") if m in done]
    if not runs:
        return
    settings = settings_of(ctx)
    timing, series = settings.record_wall_time, settings.published_series
    info = runs[0].to_info(limit=MAX_PUBLISHED_TIMES, timing=timing, series=series)
    if len(runs) == 2:
        info["ode"] = runs[1].to_info(limit=MAX_PUBLISHED_TIMES, timing=timing, series=series)
        found = compare(runs[0], runs[1])
        if found is not None:
            info["comparison"] = {"gaps": found.gaps, "worst": found.worst,
                                  "compared_times": found.compared_times,
                                  "left_out": found.left_out,
                                  "gap_unit": "rtol * max(|dae|, |ode|) + atol_i"}
    ctx.facts.setdefault("info", {})["simulation"] = info


def both_runs(ctx: ProbeContext) -> list[Trajectory]:
    """The runs the settings ask for (the ODE-mode one only after a complete DAE-mode run)."""
    out = []
    for mode in ("dae", "ode"):
        try:
            out.append(run(ctx, mode))
        except OutOfTime:
            raise  # a verdict on the other run alone could differ on a faster machine
        except ProbeSkipped:
            continue
    if not out:
        run(ctx, "dae" if settings_of(ctx).mode != "ode" else "ode")  # raises the reason
    return out


def points_fail(ctx: ProbeContext, mode: str) -> bool:
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


def run_evidence(traj: Trajectory, **extra: Any) -> Any:
    return evidence(
        mode=traj.mode, t_start=traj.t_start, t_reached=traj.t_end, stop_time=traj.stop_time,
        rtol=traj.rtol, atol="atol_factor * rtol * nominal of each variable", steps=traj.steps,
        jacobian=traj.jacobian, event=traj.event, **extra)
