"""Jacobians from few calls: Curtis-Powell-Reid column groups from the declared sparsity.

Two columns of a Jacobian that never share a non-zero row can be perturbed together: one
function evaluation (or one directional derivative) then yields both columns, each row's change
belonging to the one column of the group it depends on (Curtis, Powell & Reid, "On the
estimation of sparse Jacobian matrices", J. Inst. Math. Appl. 13 (1974) 117-119). Finding few
groups is a distance-2 graph colouring; the greedy algorithm with the largest-first ordering is
the usual choice (Coleman & Moré, "Estimation of sparse Jacobian matrices and graph coloring
problems", SIAM J. Numer. Anal. 20 (1983) 187-209). For banded or chain-like structure the
number of groups is the bandwidth, independent of the size.

The groups come from the *declared* sparsity (the manifest ``dependencies``), exactly what an
importer relies on and what is being checked. :func:`measure` then verifies the declared zeros
with few extra calls: a row that moves in a group holding none of its declared columns is
caught for free, and the zeros hidden behind a declared column of the same group are checked
along a few random directions through every column (the function must move as the declared
entries predict). Only rows found suspicious are measured again column by column.

``m`` rows (unknowns), ``n`` columns (knowns), ``nnz`` declared entries. Memory is O(nnz + m + n)
whatever the number of groups, so the column-by-column reference (one group per column) costs
calls, not a dense matrix.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable, Iterable, Sequence

import numpy as np

from . import numdiff

log = logging.getLogger(__name__)

Function = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Pattern:
    """A sparsity pattern in coordinate form, sorted by row then column.

    ``shape`` is ``(m, n)``; ``rows``, ``cols`` (int, shape (nnz,)) the declared entries.
    """

    shape: tuple[int, int]
    rows: np.ndarray
    cols: np.ndarray

    @classmethod
    def from_rows(cls, n: int, row_columns: Sequence[Iterable[int]]) -> Pattern:
        """Build from, for each row, the columns it depends on (duplicates are ignored)."""
        rows: list[int] = []
        cols: list[int] = []
        for i, columns in enumerate(row_columns):
            unique = sorted({int(j) for j in columns})
            if unique and (unique[0] < 0 or unique[-1] >= n):
                raise ValueError(f"row {i}: column out of range 0..{n - 1}")
            rows.extend([i] * len(unique))
            cols.extend(unique)
        return cls((len(row_columns), n), np.asarray(rows, dtype=np.intp),
                   np.asarray(cols, dtype=np.intp))

    @property
    def nnz(self) -> int:
        return int(self.rows.size)

    def transpose_order(self) -> np.ndarray:
        """Permutation of the entries into the order of the transpose (by column, then row)."""
        return np.lexsort((self.rows, self.cols))

    def transpose(self) -> Pattern:
        order = self.transpose_order()
        return Pattern((self.shape[1], self.shape[0]), self.cols[order], self.rows[order])

    def row(self, i: int) -> np.ndarray:
        lo, hi = np.searchsorted(self.rows, [i, i + 1])
        return self.cols[lo:hi]

    def contains(self, i: int, j: int) -> bool:
        return bool(np.any(self.row(i) == j))

    def to_dense(self) -> np.ndarray:
        out = np.zeros(self.shape, dtype=bool)
        out[self.rows, self.cols] = True
        return out


@dataclass(frozen=True)
class Colouring:
    """Column groups of a pattern: ``group[j]`` is the group of column ``j``.

    ``count`` groups, hence ``count`` perturbations (or directional derivatives) per Jacobian.
    ``entries[g]`` are the indices of the declared entries whose column is in group ``g``.
    """

    group: np.ndarray
    count: int
    entries: tuple[np.ndarray, ...]
    _members: tuple[np.ndarray, ...]

    @classmethod
    def from_groups(cls, pattern: Pattern, group: np.ndarray) -> Colouring:
        count = int(group.max()) + 1 if group.size else 0
        return cls(group, count, _split(group[pattern.cols], count), _split(group, count))

    def members(self, g: int) -> np.ndarray:
        return self._members[g]

    def seed(self, g: int, scale: np.ndarray | None = None) -> np.ndarray:
        """The direction that perturbs group ``g``: ``scale[j]`` (or 1) on its columns, (n,)."""
        out = np.zeros(self.group.size)
        members = self._members[g]
        out[members] = 1.0 if scale is None else np.asarray(scale, dtype=float)[members]
        return out


def _split(keys: np.ndarray, count: int) -> tuple[np.ndarray, ...]:
    """Indices of ``keys`` grouped by value 0..count-1."""
    order = np.argsort(keys, kind="stable")
    bounds = np.searchsorted(keys[order], np.arange(count + 1))
    return tuple(order[bounds[g]:bounds[g + 1]] for g in range(count))


def colour_columns(pattern: Pattern) -> Colouring:
    """Greedy distance-2 colouring of the columns, largest-first (Coleman & Moré 1983).

    Each column takes the smallest group not used by a column that shares one of its rows.
    Cost O(nnz * groups per row); a dense row puts every column in a group of its own.
    """
    m, n = pattern.shape
    col_rows: list[list[int]] = [[] for _ in range(n)]
    for i, j in zip(pattern.rows.tolist(), pattern.cols.tolist()):
        col_rows[j].append(i)
    order = sorted(range(n), key=lambda j: (-len(col_rows[j]), j))
    row_groups: list[set[int]] = [set() for _ in range(m)]
    group = np.full(n, -1, dtype=np.intp)
    for j in order:
        taken: set[int] = set()
        for i in col_rows[j]:
            taken |= row_groups[i]
        g = 0
        while g in taken:
            g += 1
        group[j] = g
        for i in col_rows[j]:
            row_groups[i].add(g)
    return Colouring.from_groups(pattern, group)


def colour_rows(pattern: Pattern) -> Colouring:
    """Groups of rows for adjoint derivatives: the column colouring of the transpose."""
    return colour_columns(pattern.transpose())


def one_per_group(pattern: Pattern, *, rows: bool = False) -> Colouring:
    """Column by column (or row by row): the reference a colouring is measured against."""
    size = pattern.shape[0 if rows else 1]
    target = pattern.transpose() if rows else pattern
    return Colouring.from_groups(target, np.arange(size, dtype=np.intp))


def is_valid(pattern: Pattern, colouring: Colouring) -> bool:
    """No row has two declared columns in one group (the property extraction relies on)."""
    keys = pattern.rows * max(colouring.count, 1) + colouring.group[pattern.cols]
    return bool(np.unique(keys).size == keys.size)


@dataclass(frozen=True)
class Coloured:
    """Finite differences along every group's seed, as declared entries.

    Per entry (shape (nnz,)): ``value`` the estimate of ``J[rows, cols]``, ``truncation`` its
    estimated truncation error, ``rounding`` the factor that turns the row's noise (units of
    the function) into a rounding error, ``zero`` the row did not change at all.
    ``moved``: rows that changed in a group holding none of their declared columns, as
    (row, group, change, truncation, rounding factor) in the units of the function.
    """

    value: np.ndarray
    truncation: np.ndarray
    rounding: np.ndarray
    zero: np.ndarray
    moved: list[tuple[int, int, float, float, float]]
    calls: int


def coloured_differences(fun: Function, pattern: Pattern, colouring: Colouring,
                         steps: np.ndarray, *, method: str = "central",
                         f0: np.ndarray | None = None) -> Coloured:
    """One finite difference per group, each column of the group shifted by its own step.

    ``fun(delta)`` returns the unknowns (m,) at the point shifted by ``delta`` (n,); ``steps``
    (n,) come from :func:`numdiff.step_sizes`; ``f0 = fun(0)`` saves a call per group of a
    forward difference.
    """
    m = pattern.shape[0]
    value = np.zeros(pattern.nnz)
    truncation = np.zeros(pattern.nnz)
    zero = np.zeros(pattern.nnz, dtype=bool)
    rounding = 1.0
    moved: list[tuple[int, int, float, float, float]] = []
    calls = 0
    owned = np.zeros(m, dtype=bool)
    for g in range(colouring.count):
        diff = numdiff.difference(fun, colouring.seed(g, steps), method=method, f0=f0)
        calls += diff.calls
        rounding = diff.rounding
        k = colouring.entries[g]
        r, h = pattern.rows[k], steps[pattern.cols[k]]
        value[k] = _per_step(diff.value[r], h)
        truncation[k] = _per_step(diff.truncation[r], h)
        zero[k] = diff.exact_zero[r]
        owned[:] = False
        owned[r] = True
        for i in np.flatnonzero(~owned & ~diff.exact_zero):
            moved.append((int(i), g, float(diff.value[i]), float(diff.truncation[i]), rounding))
    return Coloured(value, truncation, _per_step(np.full(pattern.nnz, rounding),
                                                 steps[pattern.cols]), zero, moved, calls)


def _per_step(value: np.ndarray, h: np.ndarray) -> np.ndarray:
    """``value / h``; NaN where the column was not perturbed (step 0: no room at a bound)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, value / np.where(h > 0, h, 1.0), np.nan)


def coloured_products(product: Function, pattern: Pattern, colouring: Colouring,
                      active: np.ndarray | None = None) -> tuple[np.ndarray, list, int]:
    """Declared entries from one product ``product(seed) = J @ seed`` per group.

    ``active`` (bool, (n,)): the columns the product accepts (others are left out of the seeds
    and their entries are NaN). Returns the values (nnz,), the (row, group) pairs that came out
    non-zero without a declared column in the group, and the number of calls.
    """
    values = np.full(pattern.nnz, np.nan)
    moved: list[tuple[int, int]] = []
    owned = np.zeros(pattern.shape[0], dtype=bool)
    for g in range(colouring.count):
        seed = colouring.seed(g)
        if active is not None:
            seed = seed * active
        out = np.asarray(product(seed), dtype=float)
        k = colouring.entries[g]
        values[k] = out[pattern.rows[k]]
        owned[:] = False
        owned[pattern.rows[k]] = True
        moved.extend((int(i), g) for i in np.flatnonzero(~owned & (np.nan_to_num(out) != 0)))
    if active is not None:
        values[~active[pattern.cols]] = np.nan
    return values, moved, colouring.count


def random_directions(n: int, count: int, rng: np.random.Generator,
                      scale: np.ndarray | None = None) -> np.ndarray:
    """``count`` directions through every column, shape (count, n): ``scale[j] * s`` with ``s``
    uniform in ±[0.5, 1], so no column is left out and cancellation is improbable."""
    out = rng.uniform(0.5, 1.0, size=(count, n)) * rng.choice(np.array([-1.0, 1.0]),
                                                               size=(count, n))
    return out if scale is None else out * np.asarray(scale, dtype=float)[None, :]


def predict(pattern: Pattern, values: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """``J @ direction`` from the declared entries only, shape (m,)."""
    return np.bincount(pattern.rows, weights=values * np.asarray(direction)[pattern.cols],
                       minlength=pattern.shape[0])


def predict_abs(pattern: Pattern, values: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """``|J| @ |direction|`` from the declared entries: the size of the prediction's terms."""
    return np.bincount(pattern.rows, weights=np.abs(values * np.asarray(direction)[pattern.cols]),
                       minlength=pattern.shape[0])


# ---------------------------------------------------------------------- one point, verified

@dataclass(frozen=True)
class Sources:
    """What can be called at one point: ``fun(delta)`` the unknowns (m,) shifted by ``delta``
    (n,); ``directional(seed)`` the FMU's ``J @ seed`` (m,); ``adjoint(v)`` the FMU's ``v @ J``
    (n,); ``dd_columns`` (bool, (n,)) the knowns the FMU's derivatives accept."""

    fun: Function
    directional: Function | None = None
    adjoint: Function | None = None
    dd_columns: np.ndarray | None = None


@dataclass(frozen=True)
class Entries:
    """The Jacobian measured at one point: every declared entry, and the undeclared entries of
    rows found suspicious (measured column by column).

    Per entry (shape (k,)): ``rows``, ``cols``, ``declared``; ``fd`` the finite difference (units
    of the unknown per unit of the known), ``truncation`` its error estimate, ``rounding`` the
    factor turning the row's noise into a rounding error, ``zero`` the function did not move at
    all; ``dd``, ``adj`` the FMU's values (NaN when not available). Per row (shape (m,)): ``f0``
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
        for i, g in moved:
            suspects.setdefault(i, set()).update(colouring.members(g).tolist())
    dot = _directions(fun, dd if sources.directional is not None else None,
                      adj if sources.adjoint is not None else None, pattern, colouring, fd,
                      dd_vals, steps, active, noise, rng, method, directions, suspicion, f0,
                      suspects)
    adj_vals = np.full(pattern.nnz, np.nan)
    if sources.adjoint is not None:
        adj_vals = _coloured_adjoint(adj, pattern, row_colouring or colour_rows(pattern),
                                     active, suspects)
    keep = ~np.isin(pattern.rows, np.fromiter(suspects, dtype=np.intp, count=len(suspects)))
    table = [pattern.rows[keep], pattern.cols[keep], np.ones(int(keep.sum()), dtype=bool),
             fd.value[keep], fd.truncation[keep], fd.rounding[keep], fd.zero[keep],
             dd_vals[keep], adj_vals[keep]]
    if suspects:
        table = _localise(table, suspects, pattern, fun, dd, adj, sources, active, steps,
                          method, f0)
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
    candidates = np.flatnonzero(np.isin(colouring.group, colouring.group[declared]))
    return set(candidates.tolist()) - set(declared.tolist())


def _directions(fun, dd, adj, pattern, colouring, fd, dd_vals, steps, active, noise, rng,
                method, count, suspicion, f0, suspects) -> tuple[float, float, float] | None:
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
            bad |= np.abs(dd_s - predict(pattern, known, s * active)) > 1e-9 * (
                predict_abs(pattern, known, s * active) + np.abs(dd_s)) + 1e-300
            if k == 0 and adj is not None:
                v = rng.uniform(0.5, 1.0, pattern.shape[0]) * rng.choice([-1.0, 1.0],
                                                                         pattern.shape[0])
                a, b = float(v @ dd_s), float(np.nan_to_num(adj(v)) @ (s * active))
                dot = (a, b, float(np.abs(v) @ predict_abs(pattern, fd.value, s * active))
                       + abs(a) + abs(b))
        for i in np.flatnonzero(bad):
            suspects.setdefault(int(i), set()).update(_hidden(pattern, colouring, int(i)))
    return dot


def _coloured_adjoint(adj, pattern, rows: Colouring, active, suspects) -> np.ndarray:
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
                suspects.setdefault(i, set()).add(j)
    return np.where(active[pattern.cols], values, np.nan)


def _localise(table, suspects, pattern, fun, dd, adj, sources, active, steps, method, f0):
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
        for i in wanted:
            unit = np.zeros(m)
            unit[i] = 1.0
            adj_rows[i] = adj(unit)
    extra: list[list] = [[] for _ in range(9)]
    for i in sorted(wanted):
        for j in sorted(wanted[i]):
            diff, dd_col = per_col[j]
            h = np.array([steps[j]])
            row = (i, j, pattern.contains(i, j), _per_step(diff.value[i:i + 1], h)[0],
                   _per_step(diff.truncation[i:i + 1], h)[0],
                   _per_step(np.array([diff.rounding]), h)[0], diff.exact_zero[i],
                   dd_col[i] if dd_col is not None else np.nan,
                   adj_rows[i][j] if i in adj_rows and active[j] else np.nan)
            for column, value in zip(extra, row):
                column.append(value)
    dtypes = (np.intp, np.intp, bool, float, float, float, bool, float, float)
    return [np.concatenate([old, np.asarray(new, dtype=dt)])
            for old, new, dt in zip(table, extra, dtypes)]
