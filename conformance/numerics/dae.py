"""DAE mode with SUNDIALS IDA: the residual, the FMU's Jacobian (initialisation: consistent.py).

The unknowns of IDA are ``y = [x; w]`` (states, then algebraic variables) and the residual is

    F(t, y, y') = [ f(t, x, w) - x' ;  g(t, x, w) ]

so its iteration matrix is ``dF/dy + cj dF/dy' = [[f_x - cj I, f_w], [g_x, g_w]]``, assembled
from the system's partial derivatives (for an FMU: its directional derivatives, coloured by the
declared sparsity; see ``system.py``). IDA's own finite-difference Jacobian is not used: measured
on Robertson at rtol 1e-4 it took 12 times more steps and ended 16 times less accurate. A
system whose partial derivatives come as a sparse matrix (above ``dense_up_to`` unknowns) is
integrated with SUNDIALS' sparse direct solver (SuperLU_MT) on its declared pattern
(``system.pattern``, :class:`~conformance.numerics.jacobians.SparseTemplate`): time and memory
grow with the Jacobian's nonzeros, not with n^2.

Tolerances are per variable: ``atol_i = atol_factor * rtol * nominal_i``. A scalar atol fails on
Robertson, where y2 (nominal 1e-5) falls to 1e-13 while y1 and y3 are of order 1.

A failed evaluation (:class:`~conformance.numerics.limits.EvaluationFailed`) that is recoverable
(fmi3Discard), or non-finite values, fill the residual with NaN: IDA's Newton iteration then
fails to converge, which IDA treats as recoverable and answers by cutting the step (scikit-sundae
offers no other way to return a recoverable error). Only when that does not help does the run
end, as an ``fmu-failure``. fmi3Error ends the run at once: the instance may not be used again.
"""
from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import jacobians
from .consistent import DaeSystem, consistent_start
from .events import EventLog, first_time_event, read_indicators, run_through_events, summarise
from .limits import (Budget, EvaluationFailed, Stepper, Stop, blame_failures, blame_solver_failure,
                     scaled_condition)
from .settings import BUDGET, FMU_FAILED, INIT, OK, SINGULAR, SOLVER, Settings, Trajectory

log = logging.getLogger(__name__)

#: The message of a run that failed, stalled or ran out of steps where dg/dw was worse than
#: ``stalled_condition`` (:func:`_diagnose_at_end`): singular by lsdae's attribution, not because
#: ``max_condition`` stopped it on the way (the simulation probe tells the two apart by it).
STALLED_SINGULAR = "dg/dw became nearly singular and the solver could not go on"

@dataclass
class _Run:
    """Counters and the record of failed evaluations, shared by the callbacks."""

    system: DaeSystem
    settings: Settings
    budget: Budget
    function_calls: int = 0
    jacobian_calls: int = 0
    failures: list[tuple[float, str, str]] = field(default_factory=list)  # t, call, status
    last_jacobian: Any = None             # ndarray, or a sparse matrix (see jacobians.py)
    template: jacobians.SparseTemplate | None = None   # the sparse solver's pattern
    max_condition: float = 0.0
    max_condition_t: float | None = None


def _initial_slope(system: DaeSystem, t0: float, y: np.ndarray) -> np.ndarray:
    """y'(t0): x' = f; w' = -g_w^-1 g_x x' (explicit time dependence of g neglected)."""
    nx = system.nx
    yp = np.zeros_like(y)
    yp[:nx] = system.evaluate(t0, y)[:nx]
    if system.nw:
        jac = system.partials(t0, y)
        try:
            yp[nx:] = jacobians.solve(jac[nx:, nx:], -(jac[nx:, :nx] @ yp[:nx]))
        except np.linalg.LinAlgError:
            pass
    return np.where(np.isfinite(yp), yp, 0.0)


def _callbacks(run: _Run):
    system, nx = run.system, run.system.nx
    diagonal = np.arange(nx)            # the differential rows' diagonal (no nx x nx identity)
    shift = np.zeros(nx + system.nw)   # -cj on the differential rows (the sparse template)

    def residual(t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        run.budget.check_clock(t)
        run.function_calls += 1
        try:
            value = system.evaluate(t, y)
        except EvaluationFailed as exc:
            run.failures.append((t, exc.call, exc.status))
            if not exc.recoverable:
                raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status}", t, call=exc.call,
                           status=exc.status, log=list(exc.log)[:5]) from None
            out[:] = np.nan  # IDA's Newton iteration fails and IDA cuts the step
            return
        if not np.all(np.isfinite(value)):
            run.failures.append((t, "non-finite values", "NaN or Inf"))
            out[:] = np.nan
            return
        out[:nx] = value[:nx] - yp[:nx]
        out[nx:] = value[nx:]

    def events(t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        run.budget.check_clock(t)
        out[:] = read_indicators(system, t, y)

    def jacobian(t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray, cj: float,
                 out: np.ndarray) -> None:
        run.budget.check_clock(t)
        run.jacobian_calls += 1
        try:
            jac = system.partials(t, y)
        except EvaluationFailed as exc:
            if not exc.recoverable:
                raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status}", t, call=exc.call,
                           status=exc.status, log=list(exc.log)[:5]) from None
            jac = _fallback(run, len(y))
        if not jacobians.finite(jac):
            jac = _fallback(run, len(y))
        run.last_jacobian = jac
        _watch_condition(run, t, y, jac)
        if run.template is not None:
            shift[:nx] = -cj
            run.template.fill(jac, out, diagonal_shift=shift)
            return
        out[:, :] = jac
        out[diagonal, diagonal] -= cj

    return residual, jacobian, events


def _fallback(run: _Run, n: int) -> Any:
    """What stands in for a Jacobian that failed: the last good one, else the identity."""
    if run.last_jacobian is not None:
        return run.last_jacobian
    return jacobians.identity(n, sparse=run.template is not None)


def _restart(run: _Run, solver: Any, atol: np.ndarray, log: EventLog):
    """After an event: consistent algebraic variables for the new residuals (they may jump;
    the largest jump goes to ``log``), then IDA re-initialised at the event (its root finding
    stays)."""
    def restart(t: float, y: np.ndarray) -> np.ndarray:
        try:
            y, info = consistent_start(run.system, t, y, atol, run.settings.rtol)
            log.residual_jump = max(log.residual_jump,
                                    info["residual_before"].get("max_abs") or 0.0)
            yp = _initial_slope(run.system, t, y)
        except EvaluationFailed as exc:
            raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status} after the event at "
                       f"t = {t:.10g}", t, call=exc.call, status=exc.status,
                       log=list(exc.log)[:5]) from None
        except Stop as exc:
            if exc.status != INIT:
                raise
            raise Stop(SOLVER, f"no consistent algebraic variables after the event at "
                       f"t = {t:.10g}: {exc.message}", t, after_event=True,
                       **exc.details) from None
        solver.init_step(t, y, yp)
        return y
    return restart


def _watch_condition(run: _Run, t: float, y: np.ndarray, jac: Any) -> None:
    system = run.system
    cond, direction = scaled_condition(jac, system.nx, system.nominal,
                                       dense_up_to=run.settings.dense_up_to)
    if cond > run.max_condition:
        run.max_condition, run.max_condition_t = cond, float(t)
    if cond > run.settings.max_condition:
        raise Stop(SINGULAR, "dg/dw became singular", t, **_singular_details(
            system, y, cond, direction, run.settings.max_condition))


def _finite_or_text(value: float) -> float | str:
    return float(value) if np.isfinite(value) else "inf"


def _singular_details(system: DaeSystem, y: np.ndarray, cond: float, direction: np.ndarray,
                      threshold: float) -> dict[str, Any]:
    names = list(system.names)
    order = np.argsort(-np.abs(direction))[:5]
    involved = [names[system.nx + k] for k in order if abs(direction[k]) > 1e-3]
    return {"condition": _finite_or_text(cond), "threshold": threshold,
            "involved": involved, "values": {n: float(v) for n, v in zip(names[:20], y[:20])}}


def integrate_dae(system: DaeSystem, settings: Settings, *, t0: float, y0: np.ndarray,
                  stop: float, times: np.ndarray | None = None,
                  start_update: Any = None) -> Trajectory:
    """Integrate from the (possibly inconsistent) point ``y0 = [x0; w0]`` at ``t0`` to ``stop``.

    A system with ``indicator_names`` (an :class:`~conformance.numerics.events.EventSystem`)
    has its state events found and handled, and the time events its updates schedule, the
    first by ``start_update`` (the event update that ended initialisation, whose
    ``terminateSimulation`` ends the run at once). Never raises for a bad model: every way a
    run can end is a :class:`Trajectory` status.
    """
    from sksundae.ida import IDA  # SUNDIALS: loaded only when a DAE is integrated

    times = settings.times(t0, stop) if times is None else np.asarray(times, dtype=float)
    n = system.nx + system.nw
    atol = settings.atol_factor * settings.rtol * np.asarray(system.nominal, dtype=float)
    budget = Budget(max_steps=settings.max_steps, wall_seconds=settings.wall_seconds,
                    stall_steps=settings.stall_steps)
    run = _Run(system, settings, budget)
    values = np.full((len(times), n), np.nan)
    traj = Trajectory(mode="dae", names=list(system.names),
                      kinds=["state"] * system.nx + ["algebraic"] * system.nw,
                      times=[float(t) for t in times], values=values, t_start=t0, t_end=t0,
                      stop_time=stop, rtol=settings.rtol, atol=[float(a) for a in atol],
                      jacobian=system.jacobian_source)
    calls0 = system.fmi_calls
    reached = 0
    log = EventLog(indicators=len(getattr(system, "indicator_names", ())))

    def record(k: int, t: float, y: np.ndarray) -> None:
        nonlocal reached
        values[k] = y
        reached = k + 1

    stepper = None
    try:
        y, traj.init = consistent_start(system, t0, np.asarray(y0, dtype=float), atol,
                                        settings.rtol)
        start_jac = system.partials(t0, y)
        cond, _ = scaled_condition(start_jac, system.nx, system.nominal,
                                   dense_up_to=settings.dense_up_to)
        traj.init["condition"] = _finite_or_text(cond)
        _watch_condition(run, t0, y, start_jac)
        record(0, t0, y)
        residual, jacobian, events = _callbacks(run)
        watch = {"eventsfn": events, "num_events": log.indicators} if log.indicators else {}
        if jacobians.is_sparse(start_jac):
            run.template = jacobians.SparseTemplate(n, *system.pattern)  # type: ignore
            watch.update(linsolver="sparse", sparsity=run.template.pattern)
        else:
            watch.update(linsolver="dense")
        with warnings.catch_warnings():  # "custom sparse Jacobian ... ignored": ours is used
            warnings.simplefilter("ignore", UserWarning)
            solver = IDA(residual, jacfn=jacobian, rtol=settings.rtol, atol=atol,
                         algebraic_idx=list(range(system.nx, n)) or None, **watch)
        solver.init_step(t0, y, _initial_slope(system, t0, y))
        stepper = Stepper(solver, times, stop, budget, record, y, exact=bool(log.indicators))
        if getattr(start_update, "terminate", False):
            log.terminated_at = t0
        else:
            run_through_events(stepper, system, log,  # type: ignore[arg-type]
                               next_time=first_time_event(start_update, t0),
                               restart=_restart(run, solver, atol, log))
        _finish(traj, run, stepper)
    except Stop as stop_:
        _stopped(traj, run, stepper, stop_)
    except EvaluationFailed as exc:  # during initialisation
        traj.status, traj.message = (INIT if stepper is None else FMU_FAILED), str(exc)
        traj.event = {"t": t0, "call": exc.call, "status": exc.status, "log": list(exc.log)[:5]}
    traj.times, traj.values = traj.times[:reached], values[:reached]
    traj.steps = stepper.steps if stepper else 0
    traj.t_end = stepper.t if stepper else t0
    traj.function_calls, traj.jacobian_calls = run.function_calls, run.jacobian_calls
    traj.fmi_calls = system.fmi_calls - calls0
    traj.wall_s = budget.elapsed()
    traj.max_condition, traj.max_condition_t = run.max_condition, run.max_condition_t
    traj.recovered = sum(1 for t, _, _ in run.failures if t <= traj.t_end)
    summarise(log, traj)
    return traj


def _finish(traj: Trajectory, run: _Run, stepper: Stepper) -> None:
    failure = stepper.failure
    if failure is None:
        traj.status = OK
        return
    _diagnose_at_end(traj, run, stepper)
    if traj.status != SINGULAR:
        blame_solver_failure(traj, run.failures, stepper, "IDA")


def _diagnose_at_end(traj: Trajectory, run: _Run, stepper: Stepper) -> None:
    """A run that failed or ran out of budget: was dg/dw (nearly) singular where it stopped?"""
    try:
        jac = run.system.partials(stepper.t, stepper.y)
    except EvaluationFailed:
        return
    cond, direction = scaled_condition(jac, run.system.nx, run.system.nominal,
                                       dense_up_to=run.settings.dense_up_to)
    if cond > run.max_condition:
        run.max_condition, run.max_condition_t = cond, stepper.t
    if cond > run.settings.stalled_condition:
        traj.status = SINGULAR
        traj.message = STALLED_SINGULAR
        traj.event = {"t": stepper.t, **_singular_details(
            run.system, stepper.y, cond, direction, run.settings.stalled_condition)}


def _stopped(traj: Trajectory, run: _Run, stepper: Stepper | None, stop: Stop) -> None:
    traj.status, traj.message = stop.status, stop.message
    traj.event = {"t": stop.t, **stop.details}
    if stop.status == INIT:
        traj.init = {k: v for k, v in stop.details.items()}
    elif stepper is not None and stop.status in (BUDGET, SOLVER):
        _diagnose_at_end(traj, run, stepper)
        if traj.status != SINGULAR:
            blame_failures(traj, run.failures, stop, "IDA")
    if stepper is not None:
        traj.event.setdefault("last_step_t", stepper.t)
