"""The residual/algebraic-variable bipartite graph: matching, structural rank, Dulmage-Mendelsohn.

Rows are residuals (equations ``0 = g_i``), columns are algebraic variables (unknowns ``w_j``),
and an edge ``(i, j)`` says that ``g_i`` may depend on ``w_j``. The semi-explicit DAE has index 1
only if ``dg/dw`` is non-singular; a necessary condition that can be checked without a binary is
that the sparsity pattern has full *structural* rank, the size of a maximum matching of this
graph (DAE-51).

When the matching is not perfect, the coarse Dulmage-Mendelsohn decomposition says why, in terms
a vendor can act on. With a maximum matching ``M``:

- the *over-determined* part holds the rows reachable from an unmatched row by an alternating
  path (row -> any adjacent column -> the row matched to it) and the columns on those paths;
  it has more equations than unknowns, so some of its residuals are structurally redundant;
- the *under-determined* part holds the columns reachable from an unmatched column by an
  alternating path (column -> any adjacent row -> the column matched to it) and the rows on
  those paths; it has more unknowns than equations, so some of its variables are determined
  by no residual;
- the rest is square and perfectly matched.

The parts do not depend on which maximum matching was found (Dulmage and Mendelsohn, "Coverings
of bipartite graphs", Canad. J. Math. 10, 1958; Pothen and Fan, "Computing the block triangular
form of a sparse matrix", ACM TOMS 16(4), 1990, section 2).

A residual whose ``dependencies`` attribute is absent depends on *every* algebraic variable
(MS-20). Such rows are kept as a flag instead of ``n`` explicit edges, so that a large model that
omits the attribute does not build a dense ``n x n`` graph: the matching gives them the columns
the sparse rows left free, and the alternating-path search passes through one hub node instead
of ``n`` edges per row. Everything else is scipy's Hopcroft-Karp matching and breadth-first
search on CSR graphs, so a 25 000 x 25 000 chain takes a few milliseconds.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Iterable, Sequence, Union

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix, issparse
from scipy.sparse.csgraph import breadth_first_order, maximum_bipartite_matching

log = logging.getLogger(__name__)

__all__ = [
    "BipartitePattern",
    "DulmageMendelsohn",
    "Matching",
    "as_pattern",
    "dulmage_mendelsohn",
    "maximum_matching",
    "structural_rank",
]

_INDEX = np.int64


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
        r = np.asarray(row_idx, dtype=_INDEX)
        c = np.asarray(col_idx, dtype=_INDEX)
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


def _sparse_rows_only(p: BipartitePattern) -> csr_matrix:
    """The explicit edges of the rows that are not full (entries of full rows removed)."""
    if not p.full_rows.any():
        return p.sparse
    keep = np.repeat(~p.full_rows, np.diff(p.sparse.indptr))
    coo = p.sparse.tocoo()
    return csr_matrix((np.ones(int(keep.sum()), dtype=np.int8), (coo.row[keep], coo.col[keep])),
                      shape=p.sparse.shape)


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
    row_to_col = np.full(n_rows, -1, dtype=_INDEX)
    col_to_row = np.full(n_cols, -1, dtype=_INDEX)
    if n_rows and n_cols:
        sparse = _sparse_rows_only(p)
        if sparse.nnz:
            found = np.asarray(maximum_bipartite_matching(sparse, perm_type="column"), dtype=_INDEX)
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


@dataclass(frozen=True)
class DulmageMendelsohn:
    """The coarse Dulmage-Mendelsohn decomposition of a pattern.

    Each attribute ending in ``_rows`` or ``_cols`` is a sorted int64 array of indices. The three
    row sets partition the rows and the three column sets partition the columns.

    Attributes
    ----------
    rank : int
        Structural rank (size of the maximum matching).
    over_rows, over_cols : numpy.ndarray
        Over-determined part: ``len(over_rows) - len(over_cols)`` rows stay unmatched in every
        maximum matching; they are structurally redundant.
    under_rows, under_cols : numpy.ndarray
        Under-determined part: ``len(under_cols) - len(under_rows)`` columns stay unmatched in
        every maximum matching; no row determines them.
    square_rows, square_cols : numpy.ndarray
        Well-determined part, of equal length and perfectly matched.
    matching : Matching
        The maximum matching the decomposition was computed from.
    """

    rank: int
    over_rows: np.ndarray
    over_cols: np.ndarray
    under_rows: np.ndarray
    under_cols: np.ndarray
    square_rows: np.ndarray
    square_cols: np.ndarray
    matching: Matching

    @property
    def is_perfect(self) -> bool:
        """True when every row and every column is matched (the pattern is square, full rank)."""
        return not (self.over_rows.size or self.under_cols.size)


def _reachable(n_nodes: int, src: np.ndarray, dst: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """Boolean mask of the nodes reachable from any of ``sources`` along the edges ``src -> dst``.

    A super-source node (index ``n_nodes``) joined to every source turns the multi-source search
    into one call of scipy's breadth-first search, which runs in O(nodes + edges).
    """
    mask = np.zeros(n_nodes, dtype=bool)
    if sources.size == 0:
        return mask
    root = n_nodes
    s = np.concatenate([src, np.full(sources.size, root, dtype=_INDEX)])
    d = np.concatenate([dst, sources.astype(_INDEX)])
    graph = coo_matrix((np.ones(s.size, dtype=np.int8), (s, d)),
                       shape=(n_nodes + 1, n_nodes + 1)).tocsr()
    order = breadth_first_order(graph, root, directed=True, return_predecessors=False)
    mask[order[order != root]] = True
    return mask


def dulmage_mendelsohn(pattern: PatternLike, matching: Matching | None = None) -> DulmageMendelsohn:
    """Compute the coarse Dulmage-Mendelsohn decomposition by alternating-path search.

    Node numbering for the searches: rows ``0..m-1``, columns ``m..m+n-1``, and one hub node
    ``m+n`` that stands for the edges of all full rows (full row -> hub -> every column in the
    row-to-column direction, every column -> hub -> full rows in the other).

    Parameters
    ----------
    pattern : BipartitePattern or array_like or sparse matrix, shape (m, n)
    matching : Matching, optional
        A *maximum* matching of ``pattern``; computed with :func:`maximum_matching` if omitted.

    Returns
    -------
    DulmageMendelsohn
    """
    p = as_pattern(pattern)
    mt = matching if matching is not None else maximum_matching(p)
    m, n = p.shape
    hub = m + n
    n_nodes = m + n + 1
    sparse = _sparse_rows_only(p).tocoo()
    e_row = sparse.row.astype(_INDEX)
    e_col = sparse.col.astype(_INDEX) + m
    full = np.flatnonzero(p.full_rows).astype(_INDEX)
    cols = np.arange(m, m + n, dtype=_INDEX)
    matched_rows = np.flatnonzero(mt.row_to_col >= 0).astype(_INDEX)
    matched_to = mt.row_to_col[matched_rows] + m
    hub_edges = full.size > 0

    # Over-determined: row -(any edge)-> column -(matching)-> row, from the unmatched rows.
    src = [e_row, matched_to]
    dst = [e_col, matched_rows]
    if hub_edges:
        src += [full, np.full(n, hub, dtype=_INDEX)]
        dst += [np.full(full.size, hub, dtype=_INDEX), cols]
    over = _reachable(n_nodes, np.concatenate(src), np.concatenate(dst),
                      np.flatnonzero(mt.row_to_col < 0))

    # Under-determined: column -(any edge)-> row -(matching)-> column, from the unmatched columns.
    src = [e_col, matched_rows]
    dst = [e_row, matched_to]
    if hub_edges:
        src += [cols, np.full(full.size, hub, dtype=_INDEX)]
        dst += [np.full(n, hub, dtype=_INDEX), full]
    under = _reachable(n_nodes, np.concatenate(src), np.concatenate(dst),
                       np.flatnonzero(mt.col_to_row < 0) + m)

    over_rows = np.flatnonzero(over[:m])
    over_cols = np.flatnonzero(over[m:hub])
    under_rows = np.flatnonzero(under[:m])
    under_cols = np.flatnonzero(under[m:hub])
    square_rows = np.flatnonzero(~(over[:m] | under[:m]))
    square_cols = np.flatnonzero(~(over[m:hub] | under[m:hub]))
    return DulmageMendelsohn(mt.size, over_rows, over_cols, under_rows, under_cols,
                             square_rows, square_cols, mt)
