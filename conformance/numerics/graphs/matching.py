"""Maximum matching of the residual/algebraic-variable graph, and its structural rank.

The rows that are not full are matched with scipy's Hopcroft-Karp on a CSR graph, so a
25 000 x 25 000 chain takes a few milliseconds; the full rows (``dependencies`` absent, MS-20,
see :mod:`conformance.numerics.graphs.bipartite`) then take the columns the sparse rows left free.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import maximum_bipartite_matching

from .bipartite import INDEX, PatternLike, as_pattern, sparse_rows_only

__all__ = [
    "Matching",
    "maximum_matching",
    "structural_rank",
]


@dataclass(frozen=True)
class Matching:
    """A maximum matching.

    Attributes
    ----------
    row_to_col : numpy.ndarray of int64, shape (n_rows,)
        The column matched to each row, ``-1`` if the row is unmatched.
    col_to_row : numpy.ndarray of int64, shape (n_cols,)
        The row matched to each column, ``-1`` if the column is unmatched.
    """

    row_to_col: np.ndarray
    col_to_row: np.ndarray

    @property
    def size(self) -> int:
        return int(np.count_nonzero(self.row_to_col >= 0))


def maximum_matching(pattern: PatternLike) -> Matching:
    """Find a maximum matching of rows to columns.

    The rows that are not full are matched first with Hopcroft-Karp
    (:func:`scipy.sparse.csgraph.maximum_bipartite_matching`); the full rows then take the
    columns left free, in order. This is maximum: no matching can use more non-full rows than
    the first phase does, and a full row can take any free column, so the size is
    ``min(n_cols, rank(non-full rows) + n_full)``.

    Parameters
    ----------
    pattern : BipartitePattern or array_like or sparse matrix, shape (n_rows, n_cols)

    Returns
    -------
    Matching
    """
    p = as_pattern(pattern)
    n_rows, n_cols = p.shape
    row_to_col = np.full(n_rows, -1, dtype=INDEX)
    col_to_row = np.full(n_cols, -1, dtype=INDEX)
    if n_rows and n_cols:
        sparse = sparse_rows_only(p)
        if sparse.nnz:
            found = np.asarray(maximum_bipartite_matching(sparse, perm_type="column"), dtype=INDEX)
            row_to_col[:] = found
            matched = np.flatnonzero(found >= 0)
            col_to_row[found[matched]] = matched
        free_rows = np.flatnonzero(p.full_rows & (row_to_col < 0))
        free_cols = np.flatnonzero(col_to_row < 0)
        k = min(free_rows.size, free_cols.size)
        row_to_col[free_rows[:k]] = free_cols[:k]
        col_to_row[free_cols[:k]] = free_rows[:k]
    return Matching(row_to_col, col_to_row)


def structural_rank(pattern: PatternLike) -> int:
    """The structural rank: the size of a maximum matching of the pattern.

    It is the largest rank any matrix with this sparsity pattern can have, and almost every
    matrix with the pattern has it (the set of values that give less is of measure zero).

    Parameters
    ----------
    pattern : BipartitePattern or array_like or sparse matrix, shape (n_rows, n_cols)

    Returns
    -------
    int
        Between 0 and ``min(n_rows, n_cols)``.
    """
    return maximum_matching(pattern).size
