"""ODE mode with SUNDIALS CVODE (BDF): the FMU with its enable parameter false.

In ODE mode the FMU solves g = 0 itself; the integrator sees ``x' = f(t, x)`` and the Jacobian
``df/dx`` from the FMU's directional derivatives (total derivatives in this mode). The algebraic
variables are read from the FMU at the output times, so the trajectory has the same columns as
in DAE mode and the two can be compared (``compare.py``). Tolerances, limits and the handling of
failed evaluations are those of DAE mode (``dae.py``): NaN in the right-hand side makes CVODE's
Newton iteration fail, and CVODE cuts the step.
"""
from __future__ import annotations

import warnings
from typing import Any, Protocol, Sequence

import numpy as np

from . import jacobians
from .events import EventLog, first_time_event, read_indicators, run_through_events, summarise
from .limits import Budget, EvaluationFailed, Stepper, Stop, blame_failures, blame_solver_failure
from .settings import BUDGET, FMU_FAILED, OK, SOLVER, Settings, Trajectory


class OdeSystem(Protocol):
    """``x' = f(t, x)``, plus the algebraic variables the model computes along the way."""

    nx: int
    names: Sequence[str]
    algebraic_names: Sequence[str]
    nominal: np.ndarray          # (nx,)
    jacobian_source: str
    fmi_calls: int

    def evaluate(self, t: float, x: np.ndarray) -> np.ndarray: ...

    def partials(self, t: float, x: np.ndarray) -> Any: ...   # ndarray, or sparse: see dae.py

    def algebraic_values(self, t: float, x: np.ndarray) -> np.ndarray: ...


def integrate_ode(system: OdeSystem, settings: Settings, *, t0: float, x0: np.ndarray,
                  stop: float, times: np.ndarray | None = None,
                  algebraic_nominal: np.ndarray | None = None,
                  start_update: Any = None) -> Trajectory:
    """Integrate ``x' = f(t, x)`` from ``x0`` at ``t0`` to ``stop``; never raises for a bad
    model: every way a run can end is a :class:`Trajectory` status. Events as in DAE mode
    (``integrate_dae``): a system with ``indicator_names`` has its state events handled, and
    ``start_update`` schedules the first time event."""
    from sksundae.cvode import CVODE  # SUNDIALS: loaded only when an ODE is integrated

    times = settings.times(t0, stop) if times is None else np.asarray(times, dtype=float)
    nx, nw = system.nx, len(system.algebraic_names)
    atol = settings.atol_factor * settings.rtol * np.asarray(system.nominal, dtype=float)
    w_nominal = np.ones(nw) if algebraic_nominal is None else np.asarray(algebraic_nominal)
    budget = Budget(max_steps=settings.max_steps, wall_seconds=settings.wall_seconds,
                    stall_steps=settings.stall_steps)
    values = np.full((len(times), nx + nw), np.nan)
    traj = Trajectory(mode="ode", names=[*system.names, *system.algebraic_names],
                      kinds=["state"] * nx + ["algebraic"] * nw,
                      times=[float(t) for t in times], values=values, t_start=t0, t_end=t0,
                      stop_time=stop, rtol=settings.rtol,
                      atol=[float(a) for a in atol] + list(
                          settings.atol_factor * settings.rtol * w_nominal),
                      jacobian=system.jacobian_source)
    counts = {"rhs": 0, "jac": 0}
    failures: list[tuple[float, str, str]] = []
    calls0 = system.fmi_calls
    reached = 0
    log = EventLog(indicators=len(getattr(system, "indicator_names", ())))

    def rhs(t: float, x: np.ndarray, xp: np.ndarray) -> None:
        budget.check_clock(t)
        counts["rhs"] += 1
        try:
            value = system.evaluate(t, x)
        except EvaluationFailed as exc:
            failures.append((t, exc.call, exc.status))
            if not exc.recoverable:
                raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status}", t, call=exc.call,
                           status=exc.status, log=list(exc.log)[:5]) from None
            xp[:] = np.nan
            return
        if not np.all(np.isfinite(value)):
            failures.append((t, "non-finite values", "NaN or Inf"))
        xp[:] = value

    last: dict[str, Any] = {}
    template: list[jacobians.SparseTemplate] = []   # the sparse solver's pattern, if sparse

    def jac(t: float, x: np.ndarray, xp: np.ndarray, out: np.ndarray) -> None:
        budget.check_clock(t)
        counts["jac"] += 1
        try:
            j = system.partials(t, x)
        except EvaluationFailed as exc:
            if not exc.recoverable:
                raise Stop(FMU_FAILED, f"{exc.call} returned {exc.status}", t, call=exc.call,
                           status=exc.status, log=list(exc.log)[:5]) from None
            j = last.get("jac", jacobians.identity(nx, sparse=bool(template)))
        if not jacobians.finite(j):
            j = last.get("jac", jacobians.identity(nx, sparse=bool(template)))
        last["jac"] = j
        if template:
            template[0].fill(j, out)
            return
        out[:, :] = j

    def events(t: float, x: np.ndarray, out: np.ndarray) -> None:
        budget.check_clock(t)
        out[:] = read_indicators(system, t, x)  # type: ignore[arg-type]

    def record(k: int, t: float, x: np.ndarray) -> None:
        nonlocal reached
        values[k, :nx] = x
        values[k, nx:] = system.algebraic_values(t, x)
        reached = k + 1

    stepper = None
    try:
        x0 = np.asarray(x0, dtype=float)
        record(0, t0, x0)
        watch = {"eventsfn": events, "num_events": log.indicators} if log.indicators else {}
        if nx > settings.dense_up_to and getattr(system, "pattern", None) is not None:
            template.append(jacobians.SparseTemplate(nx, *system.pattern))  # type: ignore
            watch.update(linsolver="sparse", sparsity=template[0].pattern)
        else:
            watch.update(linsolver="dense")
        with warnings.catch_warnings():  # "custom sparse Jacobian ... ignored": ours is used
            warnings.simplefilter("ignore", UserWarning)
            solver = CVODE(rhs, jacfn=jac, method="BDF", rtol=settings.rtol, atol=atol,
                           **watch)
        solver.init_step(t0, x0)
        stepper = Stepper(solver, times, stop, budget, record, x0, exact=bool(log.indicators))

        def restart(t: float, x: np.ndarray) -> np.ndarray:
            solver.init_step(t, x)
            return x

        if getattr(start_update, "terminate", False):
            log.terminated_at = t0
        else:
            run_through_events(stepper, system, log,  # type: ignore[arg-type]
                               next_time=first_time_event(start_update, t0), restart=restart)
        if stepper.failure is None:
            traj.status = OK
        else:
            blame_solver_failure(traj, failures, stepper, "CVODE")
    except Stop as stop_:
        traj.status, traj.message = stop_.status, stop_.message
        traj.event = {"t": stop_.t, **stop_.details}
        if stepper is not None and stop_.status in (BUDGET, SOLVER):
            traj.event.setdefault("last_step_t", stepper.t)
            blame_failures(traj, failures, stop_, "CVODE")
    except EvaluationFailed as exc:  # at the initial point
        traj.status, traj.message = FMU_FAILED, str(exc)
        traj.event = {"t": t0, "call": exc.call, "status": exc.status}
    traj.times, traj.values = traj.times[:reached], values[:reached]
    traj.steps = stepper.steps if stepper else 0
    traj.t_end = stepper.t if stepper else t0
    traj.function_calls, traj.jacobian_calls = counts["rhs"], counts["jac"]
    traj.fmi_calls = system.fmi_calls - calls0
    traj.wall_s = budget.elapsed()
    traj.recovered = sum(1 for t, _, _ in failures if t <= traj.t_end)
    summarise(log, traj)
    return traj
