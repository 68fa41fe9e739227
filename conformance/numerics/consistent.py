"""Consistent initialisation of a semi-explicit index-1 DAE: g(t0, x0, w) = 0 solved for w.

The DAE is ``x' = f(t, x, w), 0 = g(t, x, w)`` with ``y = [x; w]`` (:class:`DaeSystem`).
:func:`consistent_start` runs a damped Newton iteration with the system's own dg/dw from the
given start, and reports the residual before and after, scaled by each residual's sensitivity
``S_i = sum_j |dg_i/dv_j| * nominal_j``.
"""
from __future__ import annotations

from typing import Any, Protocol, Sequence

import numpy as np

from . import jacobians
from .limits import Stop
from .settings import INIT, SINGULAR

NEWTON_ITERATIONS = 50
NEWTON_STEP = 1e-3   # converged when the correction is below this fraction of the tolerance
ROUNDING = 1e3 * float(np.finfo(float).eps)  # ... or the residuals at rounding level, times S_i


class DaeSystem(Protocol):
    """A semi-explicit index-1 DAE ``x' = f(t, x, w), 0 = g(t, x, w)`` with ``y = [x; w]``."""

    nx: int
    nw: int
    names: Sequence[str]
    nominal: np.ndarray          # (nx + nw,)
    jacobian_source: str
    fmi_calls: int

    def evaluate(self, t: float, y: np.ndarray) -> np.ndarray:
        """``[f; g]`` at (t, y), shape (nx + nw,); raises EvaluationFailed."""
        ...

    def partials(self, t: float, y: np.ndarray) -> Any:
        """``d[f; g]/d[x; w]`` at (t, y), shape (nx + nw, nx + nw): an ndarray, or a
        scipy.sparse matrix of the entries of ``pattern`` (a large system; see
        ``jacobians.py``); raises EvaluationFailed."""
        ...


def scales_of(system: DaeSystem, jac: Any) -> np.ndarray:
    """S_i = sum_j |dg_i/dv_j| * nominal_j: the size of each residual's sensitivity, (nw,)."""
    return jacobians.weighted_row_sums(jac[system.nx:, :], system.nominal)


def _residual_summary(g: np.ndarray, scales: np.ndarray) -> dict[str, float | None]:
    if g.size == 0:
        return {"max_abs": 0.0, "max_scaled": 0.0}
    finite = bool(np.all(np.isfinite(g)))
    scaled = np.abs(g) / np.where(scales > 0, scales, 1.0)
    return {"max_abs": float(np.max(np.abs(g))) if finite else None,
            "max_scaled": float(np.max(scaled)) if finite else None}


def consistent_start(system: DaeSystem, t0: float, y0: np.ndarray, atol: np.ndarray,
                     rtol: float) -> tuple[np.ndarray, dict[str, Any]]:
    """Solve g(t0, x0, w) = 0 for w by damped Newton with the system's dg/dw, from ``y0``.

    Returns the consistent ``y`` and a summary: the residual before and after (largest absolute
    value, and largest relative to the residual's sensitivity S_i), the iterations, whether the
    correction came below ``NEWTON_STEP`` times the integration tolerance. Raises Stop(INIT)
    when no consistent point is found, EvaluationFailed when the system cannot be evaluated.
    """
    nx, y = system.nx, np.array(y0, dtype=float)
    g = system.evaluate(t0, y)[nx:]
    jac = system.partials(t0, y)
    before = _residual_summary(g, scales_of(system, jac))
    info: dict[str, Any] = {"residual_before": before, "iterations": 0}
    if system.nw == 0:
        info.update(residual_after=before, converged=True)
        return y, info
    if not np.all(np.isfinite(g)):
        raise Stop(INIT, "the residuals are not finite at the FMU's initial point", t0, **info)
    converged = False
    for it in range(1, NEWTON_ITERATIONS + 1):
        scales = np.maximum(scales_of(system, jac), 1e-300)
        if np.all(np.abs(g) <= ROUNDING * scales):
            converged = True  # zero up to rounding: a further step would only add noise
            break
        try:
            dw = jacobians.solve(jac[nx:, nx:], -g)
        except np.linalg.LinAlgError:
            raise Stop(SINGULAR, "dg/dw is singular at the initial point: Newton cannot "
                       "correct the algebraic variables", t0, **info) from None
        size = np.max(np.abs(g) / scales)
        lam = 1.0
        while True:  # backtracking on the scaled residual
            trial = y.copy()
            trial[nx:] += lam * dw
            g_trial = system.evaluate(t0, trial)[nx:]
            better = np.max(np.abs(g_trial) / scales) <= (1 - 1e-4 * lam) * size
            if (np.all(np.isfinite(g_trial)) and better) or lam < 1e-4:
                break
            lam /= 2
        y, g = trial, g_trial
        info["iterations"] = it
        if not np.all(np.isfinite(g)):
            break
        jac = system.partials(t0, y)
        tol = atol[nx:] + rtol * np.abs(y[nx:])
        if np.max(np.abs(lam * dw) / tol) <= NEWTON_STEP:
            converged = True
            break
    info.update(residual_after=_residual_summary(g, scales_of(system, jac)), converged=converged)
    if not converged:
        raise Stop(INIT, f"Newton's method did not find consistent algebraic variables in "
                   f"{info['iterations']} iterations", t0, **info)
    return y, info
