"""One point of a Jacobian measured with few calls, and what that relied on verified.

:func:`measure` takes the column groups of :mod:`.colouring` (from the *declared* sparsity) and
verifies the declared zeros with few extra calls: a row that moves in a group holding none of
its declared columns is caught for free, and the zeros hidden behind a declared column of the
same group are checked along a few random directions through every column (the function must
move as the declared entries predict). Only rows found suspicious are measured again column by
column. It returns the measured entries with their error estimates; the caller (a probe rule)
compares them with its tolerances (:func:`disagreement` is the comparison they share with the
simulation's check of the FMU's Jacobian).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from . import floors, numdiff
from .intsets import isin_ints
from .colouring import (Colouring, Function, Pattern, coloured_differences, coloured_products,
                        colour_rows, per_step, predict, predict_abs, random_directions)

log = logging.getLogger(__name__)



@dataclass(frozen=True)
class Sources:
    """What can be called at one point: ``fun(delta)`` the unknowns (m,) shifted by ``delta``
    (n,); ``directional(seed)`` the FMU's ``J @ seed`` (m,); ``adjoint(v)`` the FMU's ``v @ J``
    (n,); ``dd_columns`` (bool, (n,)) the knowns the FMU's derivatives accept; ``dd_rows``
    (bool, (m,)) the unknowns they may be asked for (the others are measured by finite
    differences only: ``directional`` gives NaN there, and ``adjoint`` ignores their seeds)."""

    fun: Function
    directional: Function | None = None
    adjoint: Function | None = None
    dd_columns: np.ndarray | None = None
    dd_rows: np.ndarray | None = None


@dataclass(frozen=True)
class Entries:
    """The Jacobian measured at one point: every declared entry, and the undeclared entries of
    rows found suspicious (measured column by column).

    Per entry (shape (k,)): ``rows``, ``cols``, ``declared``; ``fd`` the finite difference (units
    of the unknown per unit of the known), ``truncation`` its error estimate, ``rounding`` the
    factor turning the row's noise into a rounding error, ``zero`` the function did not move at
    all; ``dd``, ``adj`` the FMU's values (NaN when not available); ``step`` the step of the
    entry's known (0: not perturbed). Per row (shape (m,)): ``f0``
    and ``basis = eps * (|f| + sum_j |x_j J_ij|)`` (times a number of ulps: the noise).
    ``dot``: (v·(J s) by directional, (vJ)·s by adjoint, |v|·|J|·|s|) or None.
    """

    rows: np.ndarray
    cols: np.ndarray
    declared: np.ndarray
    fd: np.ndarray
    truncation: np.ndarray
    rounding: np.ndarray
    zero: np.ndarray
    dd: np.ndarray
    adj: np.ndarray
    step: np.ndarray
    f0: np.ndarray
    basis: np.ndarray
    localised: np.ndarray
    dot: tuple[float, float, float] | None
    calls: tuple[tuple[str, int], ...]

    def error(self, ulps: float) -> np.ndarray:
        """Error bound of ``fd`` per entry, for a noise of ``ulps`` times ``basis``."""
        return self.truncation + self.rounding * ulps * self.basis[self.rows]


class _Counter:
    def __init__(self, fn: Function | None):
        self.fn, self.calls = fn, 0

    def __call__(self, arg: np.ndarray) -> np.ndarray:
        assert self.fn is not None
        self.calls += 1
        return np.asarray(self.fn(arg), dtype=float)


def measure(sources: Sources, pattern: Pattern, colouring: Colouring, steps: np.ndarray,
            x: np.ndarray, rng: np.random.Generator, *, row_colouring: Colouring | None = None,
            method: str = "central", directions: int = 2, suspicion: float = 3.0,
            ulps: float = numdiff.DEFAULT_ULPS) -> Entries:
    """Measure the Jacobian at one point with few calls, and verify what that relied on.

    1. Coloured finite differences give every declared entry; a row that moves in a group
       holding none of its declared columns comes under suspicion.
    2. The FMU's directional derivatives, coloured the same way, give its declared entries; a
       non-zero where no declared column is perturbed is under suspicion too.
    3. Along ``directions`` random directions through every column, the function must move as
       the declared entries predict, and the directional derivative must be exactly linear in
       the seed with those entries: this covers the zeros hidden behind a declared column.
    4. The adjoint, coloured by rows, gives its declared entries (and the dot-product test).
    5. Rows under suspicion are measured column by column over their declared and candidate
       columns (finite differences, directional derivatives, one adjoint call per row): the
       only calls that grow with the size, spent only where something is off.

    ``suspicion`` (a multiple of the error estimate) only decides what is re-measured; the
    rules decide what is wrong. ``x`` (n,) is the point, for the noise estimate.
    """
    m, n = pattern.shape
    fun, dd, adj = _Counter(sources.fun), _Counter(sources.directional), _Counter(sources.adjoint)
    active = (np.ones(n, dtype=bool) if sources.dd_columns is None
              else np.asarray(sources.dd_columns, dtype=bool))
    rows_ok = (np.ones(m, dtype=bool) if sources.dd_rows is None
               else np.asarray(sources.dd_rows, dtype=bool))
    f0 = fun(np.zeros(n))
    fd = coloured_differences(fun, pattern, colouring, steps, method=method, f0=f0)
    noise = ulps * _basis(pattern.rows, pattern.cols, fd.value, x, f0, m)
    suspects: dict[int, set[int]] = {}
    for i, g, change, trunc, rounding in fd.moved:
        if abs(change) > suspicion * (trunc + rounding * noise[i]):
            suspects.setdefault(i, set()).update(colouring.members(g).tolist())
    dd_vals = np.full(pattern.nnz, np.nan)
    if sources.directional is not None:
        dd_vals, moved, _ = coloured_products(dd, pattern, colouring, active)
        dd_vals[~rows_ok[pattern.rows]] = np.nan
        for i, g in moved:
            if rows_ok[i]:
                suspects.setdefault(i, set()).update(colouring.members(g).tolist())
    dot = _directions(fun, dd if sources.directional is not None else None,
                      adj if sources.adjoint is not None else None, pattern, colouring, fd,
                      dd_vals, steps, active, noise, rng, method, directions, suspicion, f0,
                      suspects, rows_ok)
    adj_vals = np.full(pattern.nnz, np.nan)
    if sources.adjoint is not None:
        adj_vals = _coloured_adjoint(adj, pattern, row_colouring or colour_rows(pattern),
                                     active, suspects, rows_ok)
    keep = ~isin_ints(pattern.rows, np.fromiter(suspects, dtype=np.intp, count=len(suspects)))
    table = [pattern.rows[keep], pattern.cols[keep], np.ones(int(keep.sum()), dtype=bool),
             fd.value[keep], fd.truncation[keep], fd.rounding[keep], fd.zero[keep],
             dd_vals[keep], adj_vals[keep], steps[pattern.cols[keep]]]
    if suspects:
        table = _localise(table, suspects, pattern, fun, dd, adj, sources, active, steps,
                          method, f0, rows_ok)
    basis = _basis(table[0], table[1], np.nan_to_num(table[3]), x, f0, m)
    calls = (("evaluate", fun.calls), ("directional", dd.calls), ("adjoint", adj.calls))
    return Entries(*table, f0=f0, basis=basis,
                   localised=np.array(sorted(suspects), dtype=np.intp), dot=dot, calls=calls)


def _basis(rows: np.ndarray, cols: np.ndarray, values: np.ndarray, x: np.ndarray,
           f0: np.ndarray, m: int) -> np.ndarray:
    terms = np.bincount(rows, weights=np.abs(values * x[cols]), minlength=m)
    return numdiff.noise_level(f0, terms, ulps=1.0)


def _hidden(pattern: Pattern, colouring: Colouring, i: int) -> set[int]:
    """Undeclared columns of row ``i`` that share a group with one of its declared columns."""
    declared = pattern.row(i)
    candidates = np.flatnonzero(isin_ints(colouring.group, colouring.group[declared]))
    return set(candidates.tolist()) - set(declared.tolist())


def _directions(fun, dd, adj, pattern, colouring, fd, dd_vals, steps, active, noise, rng,
                method, count, suspicion, f0, suspects, rows_ok
                ) -> tuple[float, float, float] | None:
    """Step 3 of :func:`measure` (and the dot-product test along the first direction)."""
    dot = None
    fd_err = fd.truncation + fd.rounding * noise[pattern.rows]
    for k, s in enumerate(random_directions(pattern.shape[1], count, rng, steps)):
        diff = numdiff.difference(fun, s, method=method, f0=f0)
        bad = np.abs(diff.value - predict(pattern, fd.value, s)) > suspicion * (
            diff.error(noise) + predict_abs(pattern, fd_err, s))
        if dd is not None:
            known = np.nan_to_num(dd_vals)
            dd_s = dd(s * active)
            bad |= rows_ok & (np.abs(dd_s - predict(pattern, known, s * active)) > 1e-9 * (
                predict_abs(pattern, known, s * active) + np.abs(dd_s)) + 1e-300)
            if k == 0 and adj is not None:
                v = rng.uniform(0.5, 1.0, pattern.shape[0]) * rng.choice([-1.0, 1.0],
                                                                         pattern.shape[0])
                v = v * rows_ok
                a, b = (float(v @ np.nan_to_num(dd_s)),
                        float(np.nan_to_num(adj(v)) @ (s * active)))
                dot = (a, b, float(np.abs(v) @ predict_abs(pattern, fd.value, s * active))
                       + abs(a) + abs(b))
        for i in np.flatnonzero(bad):
            suspects.setdefault(int(i), set()).update(_hidden(pattern, colouring, int(i)))
    return dot


def _coloured_adjoint(adj, pattern, rows: Colouring, active, suspects, rows_ok) -> np.ndarray:
    """Declared entries from one adjoint call per group of rows; a non-zero for a column none
    of the group's rows declares puts those rows under suspicion."""
    order = pattern.transpose_order()
    transposed = Pattern((pattern.shape[1], pattern.shape[0]), pattern.cols[order],
                         pattern.rows[order])
    values_t, moved, _ = coloured_products(adj, transposed, rows)
    values = np.empty(pattern.nnz)
    values[order] = values_t
    for j, q in moved:
        if active[j]:
            for i in rows.members(q).tolist():
                if rows_ok[i]:
                    suspects.setdefault(i, set()).add(j)
    return np.where(active[pattern.cols] & rows_ok[pattern.rows], values, np.nan)


def _localise(table, suspects, pattern, fun, dd, adj, sources, active, steps, method, f0,
              rows_ok):
    """Column-by-column values for the rows under suspicion: declared and candidate columns."""
    m, n = pattern.shape
    wanted = {i: cols | set(pattern.row(i).tolist()) for i, cols in suspects.items()}
    per_col = {}
    for j in sorted(set().union(*wanted.values())):
        unit = np.zeros(n)
        unit[j] = 1.0
        diff = numdiff.difference(fun, unit * steps[j], method=method, f0=f0)
        dd_col = dd(unit) if sources.directional is not None and active[j] else None
        per_col[j] = (diff, dd_col)
    adj_rows = {}
    if sources.adjoint is not None:
        for i in (i for i in wanted if rows_ok[i]):
            unit = np.zeros(m)
            unit[i] = 1.0
            adj_rows[i] = adj(unit)
    extra: list[list] = [[] for _ in range(10)]
    for i in sorted(wanted):
        for j in sorted(wanted[i]):
            diff, dd_col = per_col[j]
            h = np.array([steps[j]])
            row = (i, j, pattern.contains(i, j), per_step(diff.value[i:i + 1], h)[0],
                   per_step(diff.truncation[i:i + 1], h)[0],
                   per_step(np.array([diff.rounding]), h)[0], diff.exact_zero[i],
                   dd_col[i] if dd_col is not None else np.nan,
                   adj_rows[i][j] if i in adj_rows and active[j] else np.nan, steps[j])
            for column, value in zip(extra, row):
                column.append(value)
    dtypes = (np.intp, np.intp, bool, float, float, float, bool, float, float, float)
    return [np.concatenate([old, np.asarray(new, dtype=dt)])
            for old, new, dt in zip(table, extra, dtypes)]


def row_scale(e: Entries, nominal: np.ndarray, m: int, *,
              declared_only: bool = False) -> np.ndarray:
    """S_i = sum_j |J_ij| * nominal_j over the measured entries of each row, shape (m,):
    how much the unknown moves when each known moves by its nominal."""
    weights = np.abs(np.nan_to_num(e.fd)) * nominal[e.cols]
    if declared_only:
        weights = weights * e.declared
    return np.bincount(e.rows, weights=weights, minlength=m)


def floor(e: Entries, m: int, *, ulps: float, row_nominal: np.ndarray | None = None
          ) -> np.ndarray:
    """The absolute floor of every entry's comparison (:mod:`.floors`), shape (k,): below it
    a finite difference of this row and step resolves nothing. ``row_nominal`` (m,): the
    unknowns' nominal values (1 without)."""
    under = floors.underflowing_rows(e.rows, e.fd, m)[e.rows]
    nominal_i = np.ones(e.rows.size) if row_nominal is None else \
        np.asarray(row_nominal, dtype=float)[e.rows]
    return floors.derivative_floor(nominal_i, e.step, under, ulps=ulps)


def disagreement(e: Entries, values: np.ndarray, nominal: np.ndarray, m: int, *, rtol: float,
                 margin: float, ulps: float, row_nominal: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """How far ``values`` (the FMU's entries, shape (k,)) are from the finite differences:
    ``|values - fd|``, the tolerance ``margin * error + rtol * S_i / nominal_j`` but never
    below the entry's :func:`floor`, the error estimate of ``fd`` for a noise of ``ulps``, and
    ``S_i / nominal_j`` (each of shape (k,)). An entry disagrees where the first exceeds the
    second."""
    scale = row_scale(e, nominal, m)[e.rows] / nominal[e.cols]
    err = e.error(ulps)
    tol = np.maximum(margin * err + rtol * scale, floor(e, m, ulps=ulps, row_nominal=row_nominal))
    return np.abs(values - e.fd), tol, err, scale
