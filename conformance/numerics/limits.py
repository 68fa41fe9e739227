"""Our own limits on a run, and the step loop that enforces them.

SUNDIALS stops on its own only when a step fails. A DAE whose dg/dw approaches singularity (an
impasse point, as in the reduced Van der Pol oscillator at t* = 1.5 - ln 2) does not fail: the
steps shrink until ``t + h == t`` and the solver keeps "succeeding" forever. So the integrators
here are driven one internal step at a time (``method="onestep"``, :class:`Stepper`), and after
each step, and inside every callback, :class:`Budget` checks

* the number of steps (``max_steps``): a count, the same on every machine, and the only budget
  whose end is a verdict (``budget``);
* the wall clock (``wall_seconds``): a safety net only, so that a slow machine cannot hang the
  check; its end is ``time-budget``, after which the simulation rules do not run (a verdict
  must not depend on the machine's speed or load);
* progress in time: ``stall_steps`` steps that together move time by less than a relative
  ``STALL_RTOL`` end the run as a solver failure (the solver cannot go on, it only does not
  say so);

and the DAE integrator checks the condition of dg/dw at every Jacobian evaluation
(:func:`scaled_condition`). A limit raises :class:`Stop`, which SUNDIALS passes through (a
Python exception in a callback makes the callback fail, and scikit-sundae re-raises it).
"""
from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from .conditioning import conditioning
from .jacobians import is_sparse, weighted_row_sums
from .settings import BUDGET, FMU_FAILED, SOLVER, TIME_BUDGET

STALL_RTOL = 1e-10   # relative progress in time that counts as "moving"


class EvaluationFailed(Exception):
    """The model could not be evaluated at a point: an FMI call returned ``status`` (or the
    values were not finite). ``recoverable``: a smaller step may get past it (fmi3Discard,
    NaN), as opposed to fmi3Error, after which the instance may not be used again."""

    def __init__(self, call: str, status: str, log: Any = (), *, recoverable: bool):
        super().__init__(f"{call} returned {status}")
        self.call, self.status, self.log, self.recoverable = call, status, tuple(log), recoverable


class Stop(Exception):
    """A run ends early: ``status`` (see settings), a message, the time and the details."""

    def __init__(self, status: str, message: str, t: float, /, **details: Any):
        super().__init__(message)
        self.status, self.message, self.t, self.details = status, message, float(t), details


class Budget:
    """Steps, wall clock and progress of one run."""

    def __init__(self, *, max_steps: int, wall_seconds: float, stall_steps: int,
                 clock: Callable[[], float] = time.monotonic):
        self.max_steps, self.wall_seconds, self.stall_steps = max_steps, wall_seconds, stall_steps
        self.clock = clock
        self.started = clock()
        self.deadline = self.started + wall_seconds
        self._mark: tuple[float, int] | None = None

    def elapsed(self) -> float:
        return self.clock() - self.started

    def check_clock(self, t: float) -> None:
        """Called from inside the callbacks too: one slow step cannot outlast the safety net."""
        if self.clock() > self.deadline:
            raise Stop(TIME_BUDGET, f"lsdae's wall-clock safety net of {self.wall_seconds:g} s "
                       "ran out (the machine's speed, not the FMU's: no verdict)", t,
                       limit="wall_seconds", value=self.wall_seconds)

    def check_step(self, t: float, steps: int) -> None:
        if steps >= self.max_steps:
            raise Stop(BUDGET, f"the budget of {self.max_steps} steps ran out", t,
                       limit="max_steps", value=self.max_steps)
        self.check_clock(t)

    def progress(self, t: float, steps: int) -> None:
        """After an accepted step: end the run when time has stopped moving."""
        if self._mark is None or t - self._mark[0] > STALL_RTOL * abs(self._mark[0]):
            self._mark = (t, steps)
            return
        if steps - self._mark[1] >= self.stall_steps:
            raise Stop(SOLVER, f"the solver stalled: time did not move over "
                       f"{self.stall_steps} steps", t, limit="stall_steps",
                       value=self.stall_steps, stalled_since=self._mark[0])


def scaled_condition(jac: Any, nx: int, nominal: np.ndarray, *, dense_up_to: int
                     ) -> tuple[float, np.ndarray]:
    """How close dg/dw is to singular, relative to how strongly g depends on everything.

    Parameters
    ----------
    jac : ndarray or scipy.sparse matrix, shape (nx + nw, nx + nw)
        d[f; g]/d[x; w]: rows the derivatives then the residuals, columns the states then the
        algebraic variables.
    nx : int
        Number of states.
    nominal : ndarray, shape (nx + nw,)
        Nominal values of the states and algebraic variables (the columns).
    dense_up_to : int
        Up to this many algebraic variables ``sigma_min`` comes from a dense SVD; above it
        from a sparse LU, as ``1 / ||G^-1||_1`` (Hager-Higham estimate,
        :mod:`.conditioning`), within a factor sqrt(nw) of ``sigma_min``.

    Returns
    -------
    condition : float
        ``1 / sigma_min(G)`` where ``G = D^-1 (dg/dw) N``: columns scaled by the algebraic
        variables' nominals ``N``, each row divided by the residual's total sensitivity
        ``S_i = sum_j |dg_i/dv_j| * nominal_j`` over states and algebraic variables. Every row of
        ``G`` has a 1-norm of at most 1, so this is at least cond(G) / sqrt(nw); unlike cond(G)
        it also grows when g keeps depending on the states while dg/dw vanishes (a scalar
        dg/dw has cond 1 whatever its size). inf when a residual depends on nothing.
    direction : ndarray, shape (nw,)
        The right singular vector of ``sigma_min``: which algebraic variables are involved.
    """
    nw = jac.shape[0] - nx
    if nw <= 0:
        return 1.0, np.zeros(0)
    if is_sparse(jac) or nw > dense_up_to:
        return _sparse_scaled_condition(jac, nx, np.asarray(nominal, dtype=float), dense_up_to)
    g = jac[nx:, :] * np.asarray(nominal, dtype=float)[None, :]
    if not np.all(np.isfinite(g)):
        return np.inf, np.zeros(nw)
    total = np.abs(g).sum(axis=1)
    if np.any(total == 0):
        direction = np.zeros(nw)
        return np.inf, direction
    _, sv, vt = np.linalg.svd(g[:, nx:] / total[:, None])
    return (float(1.0 / sv[-1]) if sv[-1] > 0 else np.inf), vt[-1]


def _sparse_scaled_condition(jac: Any, nx: int, nominal: np.ndarray, dense_up_to: int
                             ) -> tuple[float, np.ndarray]:
    """:func:`scaled_condition` without forming anything of size n x n."""
    import scipy.sparse as sp  # scipy: only for a Jacobian too large for a dense SVD

    rows = sp.csr_array(jac)[nx:, :]
    if not np.all(np.isfinite(rows.data)):
        return np.inf, np.zeros(rows.shape[0])
    total = weighted_row_sums(rows, nominal)
    if np.any(total == 0):
        return np.inf, np.zeros(rows.shape[0])
    g = sp.diags_array(1.0 / total) @ rows[:, nx:] @ sp.diags_array(nominal[nx:])
    found = conditioning(sp.csc_array(g), dense_up_to=dense_up_to)
    smallest = found.smallest
    return (float(1.0 / smallest) if smallest > 0 else np.inf), found.direction


ROOT_RETURN = 2   # IDA_ROOT_RETURN and CV_ROOT_RETURN: a step ended at a root of the events


class Stepper:
    """Steps a scikit-sundae IDA or CVODE solver (after ``init_step``) from ``times[0]`` to
    ``stop`` one internal step at a time, recording the solution at each of ``times`` passed.

    ``steps``, ``t`` and ``y`` follow the last accepted step, also when :meth:`run` ends with
    :class:`Stop` (a limit, or raised by a callback); ``failure`` is the solver's result when
    a step failed; ``root`` says the last step ended at a root of the solver's events function
    (a state event, at ``t``); ``k`` is the next output time to record.

    ``exact``: never step past an output time (each is a stop time of the solver), for runs
    that root-find on event indicators: SUNDIALS cannot interpolate back once a step has ended
    at a root, so no output time may lie inside such a step. Without it the solver steps freely
    and the outputs are interpolated.
    """

    def __init__(self, solver: Any, times: np.ndarray, stop: float, budget: Budget,
                 record: Callable[[int, float, np.ndarray], None], y0: np.ndarray, *,
                 exact: bool = False):
        self.solver, self.times, self.stop, self.budget, self.record = (
            solver, times, stop, budget, record)
        self.steps, self.t, self.y = 0, float(times[0]), np.asarray(y0, dtype=float)
        self.failure: Any = None
        self.exact, self.root, self.k = exact, False, 1

    @property
    def done(self) -> bool:
        """Every output time is recorded (or the run has failed)."""
        return self.k >= len(self.times) or self.failure is not None

    def run(self, until: float | None = None) -> None:
        """Step until every output time is recorded, the stop time or ``until`` (a time event:
        an output at exactly ``until`` is left for :meth:`restart`, after the event) is
        reached, a root of the events function is found (``root``) or a step fails."""
        end = self.stop if until is None else until
        hold = np.inf if until is None else until
        self.root = False
        while self.k < len(self.times):
            self.budget.check_step(self.t, self.steps)
            target = min(end, float(self.times[self.k])) if self.exact else end
            result = self.solver.step(target, method="onestep", tstop=target)
            if not result.success:
                self.failure = result
                return
            self.steps += 1
            self.t, self.y = float(result.t), np.asarray(result.y, dtype=float)
            if result.status == ROOT_RETURN:
                self.root = True  # outputs up to t were recorded (exact); the rest follow
                return
            while self.k < len(self.times) and hold > self.times[self.k] <= self.t:
                at = (result if self.times[self.k] == self.t
                      else self.solver.step(float(self.times[self.k]), method="normal"))
                self.record(self.k, float(self.times[self.k]), np.asarray(at.y, dtype=float))
                self.k += 1
            if self.t >= end:
                return
            self.budget.progress(self.t, self.steps)

    def restart(self, t: float, y: np.ndarray) -> None:
        """After an event at ``t`` (the solver re-initialised there with ``y``): record the
        output times up to ``t`` with the values after the event."""
        self.t, self.y, self.root = float(t), np.asarray(y, dtype=float), False
        while self.k < len(self.times) and self.times[self.k] <= self.t:
            self.record(self.k, float(self.times[self.k]), self.y)
            self.k += 1


def blame_failures(traj: Any, failures: list[tuple[float, str, str]], stop: Stop,
                   solver: str) -> None:
    """A run stopped by a limit while the model kept failing (fmi3Discard, NaN) near where it
    stalled: the failures are the cause, the solver only could not get past them."""
    since = float(stop.details.get("stalled_since", traj.event.get("last_step_t", stop.t)))
    recent = [f for f in failures if f[0] >= since]
    if not recent:
        return
    _, call, status = recent[-1]
    traj.status = FMU_FAILED
    traj.message = (f"{call} returned {status} at the points {solver} tried near "
                    f"t = {since:.10g}; smaller steps did not get past it ({stop.message})")
    traj.event = {**traj.event, "call": call, "status": status,
                  "failed_evaluations": len(recent)}


def blame_solver_failure(traj: Any, failures: list[tuple[float, str, str]], stepper: Stepper,
                         solver: str) -> None:
    """A run the solver gave up: the model's failures (fmi3Discard, NaN) at every step it tried
    beyond where it stopped are the cause, if there were any; otherwise the solver is."""
    failure = stepper.failure
    pending = [f for f in failures if f[0] > stepper.t]
    if pending:
        _, call, status = pending[-1]
        traj.status = FMU_FAILED
        traj.message = (f"{call} returned {status} at every step {solver} tried beyond "
                        f"t = {stepper.t:.10g}; reducing the step did not help")
        traj.event = {"t": stepper.t, "call": call, "status": status,
                      "failed_evaluations": len(pending), "solver": failure.message}
        return
    traj.status = SOLVER
    traj.message = f"{solver} stopped at t = {stepper.t:.10g}: {failure.message}"
    traj.event = {"t": stepper.t, "solver_status": int(failure.status),
                  "solver": failure.message}
