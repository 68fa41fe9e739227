"""The residual/algebraic-variable bipartite graph, as a sparsity pattern with full rows.

Rows are residuals (equations ``0 = g_i``), columns are algebraic variables (unknowns ``w_j``),
and an edge ``(i, j)`` says that ``g_i`` may depend on ``w_j``. The semi-explicit DAE has index 1
only if ``dg/dw`` is non-singular; a necessary condition that can be checked without a binary is
that the sparsity pattern has full *structural* rank, the size of a maximum matching of this
graph (DAE-51): :mod:`conformance.numerics.graphs.matching` finds it, and :mod:`conformance.numerics.graphs.dulmage_mendelsohn`
says why it falls short.

A residual whose ``dependencies`` attribute is absent depends on *every* algebraic variable
(MS-20). Such rows are kept as a flag instead of ``n`` explicit edges, so that a large model that
omits the attribute does not build a dense ``n x n`` graph.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence, Union

import numpy as np
from scipy.sparse import csr_matrix, issparse

__all__ = [
    "INDEX",
    "BipartitePattern",
    "PatternLike",
    "as_pattern",
    "sparse_rows_only",
]

INDEX = np.int64


@dataclass(frozen=True)
class BipartitePattern:
    """A sparsity pattern with optional *full* rows (adjacent to every column).

    Parameters
    ----------
    sparse : scipy.sparse.csr_matrix, shape (n_rows, n_cols)
        Explicit edges; every stored entry counts, whatever its value. Entries stored in a full
        row are ignored.
    full_rows : numpy.ndarray of bool, shape (n_rows,)
        ``True`` for a row that depends on every column (``dependencies`` absent, MS-20).
    """

    sparse: csr_matrix
    full_rows: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        n_rows, n_cols = self.sparse.shape
        return int(n_rows), int(n_cols)

    @classmethod
    def from_rows(cls, rows: Sequence[Iterable[int] | None], n_cols: int) -> BipartitePattern:
        """Build a pattern from one column list per row.

        Parameters
        ----------
        rows : sequence of (iterable of int or None), length n_rows
            The columns each row depends on; ``None`` means every column. Duplicate columns
            are merged.
        n_cols : int
            Number of columns; every column index must lie in ``[0, n_cols)``.
        """
        full = np.fromiter((r is None for r in rows), dtype=bool, count=len(rows))
        row_idx: list[int] = []
        col_idx: list[int] = []
        for i, row in enumerate(rows):
            if row is not None:
                before = len(col_idx)
                col_idx.extend(row)
                row_idx.extend([i] * (len(col_idx) - before))
        r = np.asarray(row_idx, dtype=INDEX)
        c = np.asarray(col_idx, dtype=INDEX)
        bad = (c < 0) | (c >= n_cols)
        if bad.any():
            i = int(r[np.argmax(bad)])
            raise ValueError(f"row {i} names a column outside [0, {n_cols})")
        m = csr_matrix((np.ones(c.size, dtype=np.int8), (r, c)), shape=(len(rows), n_cols))
        m.sum_duplicates()
        m.data[:] = 1
        return cls(m, full)

    @classmethod
    def from_matrix(cls, matrix: object) -> BipartitePattern:
        """Build a pattern from a dense array (non-zero: edge) or a sparse matrix (stored: edge)."""
        if issparse(matrix):
            m = csr_matrix(matrix, copy=True)
            m.data = np.ones(m.data.size, dtype=np.int8)
        else:
            dense = np.atleast_2d(np.asarray(matrix))
            m = csr_matrix((dense != 0).astype(np.int8))
        m.sum_duplicates()
        return cls(m, np.zeros(m.shape[0], dtype=bool))

    def to_dense(self) -> np.ndarray:
        """The pattern as a boolean array of shape (n_rows, n_cols), full rows all ``True``."""
        dense = self.sparse.toarray() != 0
        dense[self.full_rows, :] = True
        return dense


PatternLike = Union[BipartitePattern, csr_matrix, np.ndarray, Sequence[Sequence[float]]]


def as_pattern(pattern: PatternLike) -> BipartitePattern:
    """Return ``pattern`` as a :class:`BipartitePattern` (array-likes: non-zero = edge)."""
    if isinstance(pattern, BipartitePattern):
        return pattern
    return BipartitePattern.from_matrix(pattern)


def sparse_rows_only(p: BipartitePattern) -> csr_matrix:
    """The explicit edges of the rows that are not full (entries of full rows removed)."""
    if not p.full_rows.any():
        return p.sparse
    keep = np.repeat(~p.full_rows, np.diff(p.sparse.indptr))
    coo = p.sparse.tocoo()
    return csr_matrix((np.ones(int(keep.sum()), dtype=np.int8), (coo.row[keep], coo.col[keep])),
                      shape=p.sparse.shape)
