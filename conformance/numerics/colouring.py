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
importer relies on and what is being checked; :mod:`.measure` verifies the declared zeros.

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
from .intsets import unique_ints

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
    Cost O(nnz * groups per row / 64); a dense row puts every column in a group of its own.
    The groups a row has used are the bits of one Python integer, so a column's taken groups
    are an OR of its rows' integers and its group is the lowest bit that is still zero.
    """
    m, n = pattern.shape
    counts = np.bincount(pattern.cols, minlength=n)
    rows_by_col = pattern.rows[np.argsort(pattern.cols, kind="stable")].tolist()
    bounds = np.concatenate(([0], np.cumsum(counts))).tolist()
    order = np.lexsort((np.arange(n), -counts)).tolist()   # most rows first, then by index
    used = [0] * m
    group = [0] * n
    for j in order:
        rows = rows_by_col[bounds[j]:bounds[j + 1]]
        taken = 0
        for i in rows:
            taken |= used[i]
        free = ~taken & (taken + 1)      # the lowest zero bit of taken
        group[j] = free.bit_length() - 1
        for i in rows:
            used[i] |= free
    return Colouring.from_groups(pattern, np.asarray(group, dtype=np.intp))


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
    return bool(unique_ints(keys).size == keys.size)


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
        value[k] = per_step(diff.value[r], h)
        truncation[k] = per_step(diff.truncation[r], h)
        zero[k] = diff.exact_zero[r]
        owned[:] = False
        owned[r] = True
        for i in np.flatnonzero(~owned & ~diff.exact_zero):
            moved.append((int(i), g, float(diff.value[i]), float(diff.truncation[i]), rounding))
    return Coloured(value, truncation, per_step(np.full(pattern.nnz, rounding),
                                                 steps[pattern.cols]), zero, moved, calls)


def per_step(value: np.ndarray, h: np.ndarray) -> np.ndarray:
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
