"""ODE mode against DAE mode at one sampling point, for ``ode-dae-inconsistent`` (dgdw.py).

From the algebraic variables w that ODE mode gives at (t, x, u), solve g = 0 for w by Newton with
the FMU's dg/dw (if the survey confirmed it, else central differences), then compare the
derivatives and outputs of both modes, each within its tolerance and rounding noise (never
below the absolute floor of :mod:`conformance.numerics.floors`). Up to ``dense_up_to``
algebraic variables dg/dw is measured column by column and solved densely; above it, it is
measured in the groups of columns of its declared sparsity (as an importer would) and solved
with a sparse LU: calls and memory grow with its nonzeros, not with n^2.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...numerics import colouring as col
from ...numerics import floors, jacobians, numdiff
from ..instruments.api import Evaluator, FmiError, Point
from ..instruments.entry_comparison import directional_verdict
from ..instruments.jacobian import PointSurvey, Survey, point_evidence, row_scale
from ..instruments.jacobian_layout import JacobianLayout

SHOWN = 20   # values per evidence item (a model of 10,000 variables is not listed whole)


@dataclass
class _Solve:
    w: np.ndarray
    residual: np.ndarray
    iterations: int
    converged: bool


@dataclass(frozen=True)
class Sparse:
    """The declared sparsity of dg/dw and its column groups (a large dg/dw)."""

    pattern: col.Pattern
    colouring: col.Colouring


def sparse_dgdw(layout: JacobianLayout, res_i: np.ndarray, alg_j: np.ndarray) -> Sparse:
    """The declared entries of dg/dw (residual rows, algebraic columns, in their order)."""
    p = layout.pattern
    rpos = np.full(len(layout.rows), -1, dtype=np.intp)
    rpos[res_i] = np.arange(res_i.size)
    cpos = np.full(len(layout.cols), -1, dtype=np.intp)
    cpos[alg_j] = np.arange(alg_j.size)
    keep = (rpos[p.rows] >= 0) & (cpos[p.cols] >= 0)
    pattern = col.Pattern((res_i.size, alg_j.size), rpos[p.rows[keep]], cpos[p.cols[keep]])
    return Sparse(pattern, col.colour_columns(pattern))


def _dgdw(ev: Evaluator, point: Point, res: list[int], alg: list[int], directional: bool,
          steps: np.ndarray, sparse: Sparse | None = None) -> object:
    """dg/dw from the FMU (column by column), or central differences without it; with
    ``sparse``, from one call (or difference) per group of columns, as a sparse matrix."""
    if sparse is not None:
        return _coloured_dgdw(ev, point, res, alg, directional, steps, sparse)
    n = len(alg)
    out = np.zeros((len(res), n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = 1.0
        if directional:
            out[:, k] = ev.directional(point, res, alg, e)
        else:
            plus = Point(point.t, {**point.values, alg[k]: point.values[alg[k]] + steps[k]})
            minus = Point(point.t, {**point.values, alg[k]: point.values[alg[k]] - steps[k]})
            out[:, k] = (ev.evaluate(plus, res) - ev.evaluate(minus, res)) / (2 * steps[k])
    return out


def _coloured_dgdw(ev: Evaluator, point: Point, res: list[int], alg: list[int],
                   directional: bool, steps: np.ndarray, sparse: Sparse) -> object:
    import scipy.sparse as sp  # scipy: only for a dg/dw too large to be dense

    p = sparse.pattern
    if directional:
        values, _, _ = col.coloured_products(lambda seed: ev.directional(point, res, alg, seed),
                                             p, sparse.colouring)
    else:
        w = np.array([point.values[vr] for vr in alg])

        def fun(delta: np.ndarray) -> np.ndarray:
            shifted = {**point.values, **dict(zip(alg, (w + delta).tolist()))}
            return ev.evaluate(Point(point.t, shifted, point.label), res)

        values = col.coloured_differences(fun, p, sparse.colouring, steps,
                                          method="central").value
    return sp.csc_array((np.nan_to_num(values), (p.rows, p.cols)), shape=p.shape)


def _newton(ev: Evaluator, base: Point, res: list[int], alg: list[int], w0: np.ndarray,
            nominal: np.ndarray, noise: np.ndarray, weights: np.ndarray, directional: bool,
            max_iterations: int, sparse: Sparse | None = None) -> _Solve:
    """Solve g(t, x, w, u) = 0 for w from w0: Newton with the FMU's dg/dw, halving the step
    while the weighted residual norm does not decrease; converged when every residual is
    within its rounding noise."""
    def point(w: np.ndarray) -> Point:
        return Point(base.t, {**base.values, **dict(zip(alg, w.tolist()))}, base.label)

    positive = weights[weights > 0]
    weights = np.where(weights > 0, weights, positive.min() if positive.size else 1.0)

    def size(g: np.ndarray) -> float:
        return float(np.linalg.norm(g / weights))

    w = np.asarray(w0, dtype=float).copy()
    g = ev.evaluate(point(w), res)
    for it in range(max_iterations):
        if np.all(np.abs(g) <= noise):
            return _Solve(w, g, it, True)
        jac = _dgdw(ev, point(w), res, alg, directional,
                    numdiff.step_sizes(w, nominal, method="central"), sparse)
        dw = (jacobians.solve(jac, -g) if sparse is not None
              else np.linalg.lstsq(jac, -g, rcond=None)[0])
        lam = 1.0
        while True:
            trial = w + lam * dw
            g_trial = ev.evaluate(point(trial), res)
            if size(g_trial) < size(g) or lam < 1e-4:
                break
            lam /= 2
        w, g = trial, g_trial
        if np.max(np.abs(lam * dw) / nominal) <= 1e-14:
            return _Solve(w, g, it + 1, bool(np.all(np.abs(g) <= 1e3 * noise)))
    return _Solve(w, g, max_iterations, bool(np.all(np.abs(g) <= noise)))


def compare_modes(ctx, s: Survey, ps: PointSurvey, res_i, cmp_i, alg_j, res, cmp, alg, *,
                  rtol, margin, ulps, max_iterations, sparse: Sparse | None = None):
    """The worst disagreement of the two modes at ``ps`` (ratio, evidence), or None. With
    ``sparse`` (a large dg/dw), Newton uses its coloured, sparse form."""
    layout = s.layout
    values = {c.vr: float(v) for c, v in zip(layout.cols, ps.x)
              if c.role in ("state", "input")}
    ode_point = Point(ps.point.t, values, ps.point.label)
    try:
        ode = ctx.ode.evaluate(ode_point, cmp)
    except FmiError:
        return None  # ODE mode cannot evaluate here: the handshake probe reports it
    try:
        w0 = np.asarray(ctx.ode.evaluate(ode_point, alg), dtype=float)
    except FmiError:  # w is not readable in ODE mode: start from the sampling point's w
        w0 = ps.x[alg_j]
    e = ps.entries
    noise = margin * ulps * e.basis
    scale = row_scale(layout, e)
    base = Point(ps.point.t, {**values, **dict(zip(alg, w0.tolist()))}, ps.point.label)
    try:
        g0 = ctx.dae.evaluate(base, res)
        res_tol = noise[res_i] + rtol * scale[res_i]
        if np.all(np.abs(g0) <= res_tol):
            solve = _Solve(w0, g0, 0, True)
        else:
            solve = _newton(ctx.dae, base, res, alg, w0, layout.nominal[alg_j],
                            noise[res_i], res_tol, directional_verdict(ctx, s)[0],
                            max_iterations, sparse)
        at = Point(base.t, {**base.values, **dict(zip(alg, solve.w.tolist()))}, base.label)
        dae = ctx.dae.evaluate(at, cmp)
    except (FmiError, np.linalg.LinAlgError):
        return None
    under = floors.underflowing_rows(e.rows, e.fd, len(layout.rows))[cmp_i]
    tol = np.maximum(rtol * (np.abs(ode) + scale[cmp_i]) + noise[cmp_i],
                     floors.value_floor(layout.row_nominal[cmp_i], under, ulps=ulps))
    diff = np.abs(dae - ode)
    finite = np.isfinite(diff) & np.isfinite(tol)   # non-finite values: nan-or-inf
    if not np.all(np.isfinite(g0)) or np.all(diff[finite] <= tol[finite]) and (
            solve.converged or np.all(np.abs(g0) <= res_tol)):
        return None
    diff = np.where(finite, diff, 0.0)
    k = int(np.argmax(diff / np.maximum(tol, np.finfo(float).tiny)))
    names = [layout.rows[i].name for i in cmp_i]
    return float(diff[k] / tol[k]) if tol[k] > 0 else np.inf, {
        "worst": names[k], "ode": dict(zip(names, ode.tolist())),
        "dae": dict(zip(names, dae.tolist())), "tolerance": dict(zip(names, tol.tolist())),
        "algebraic_ode": _shown([layout.cols[j].name for j in alg_j], w0),
        "algebraic_dae": _shown([layout.cols[j].name for j in alg_j], solve.w),
        "residual_at_ode_algebraic": _shown([layout.rows[i].name for i in res_i], g0),
        "newton_iterations": solve.iterations, "newton_converged": solve.converged,
        "scale": "rtol * (|ODE value| + S_i) + margin * noise, S_i = sum_j |J_ij| * nominal_j",
        "point": point_evidence(layout, ps)}


def _shown(names: list[str], values: np.ndarray) -> dict[str, float]:
    """The first :data:`SHOWN` values by name (all of a small model)."""
    return dict(zip(names[:SHOWN], values[:SHOWN].tolist()))
