"""The coarse Dulmage-Mendelsohn decomposition of the residual/algebraic-variable graph.

When the matching (:mod:`conformance.numerics.graphs.matching`) is not perfect, the decomposition says why, in
terms a vendor can act on. With a maximum matching ``M``:

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

Full rows (``dependencies`` absent, MS-20) cost one hub node in the alternating-path search
instead of ``n`` edges per row; the search itself is scipy's breadth-first search on a CSR graph.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order

from .bipartite import INDEX, PatternLike, as_pattern, sparse_rows_only
from .matching import Matching, maximum_matching

__all__ = [
    "DulmageMendelsohn",
    "dulmage_mendelsohn",
]


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
    s = np.concatenate([src, np.full(sources.size, root, dtype=INDEX)])
    d = np.concatenate([dst, sources.astype(INDEX)])
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
    sparse = sparse_rows_only(p).tocoo()
    e_row = sparse.row.astype(INDEX)
    e_col = sparse.col.astype(INDEX) + m
    full = np.flatnonzero(p.full_rows).astype(INDEX)
    cols = np.arange(m, m + n, dtype=INDEX)
    matched_rows = np.flatnonzero(mt.row_to_col >= 0).astype(INDEX)
    matched_to = mt.row_to_col[matched_rows] + m
    hub_edges = full.size > 0

    # Over-determined: row -(any edge)-> column -(matching)-> row, from the unmatched rows.
    src = [e_row, matched_to]
    dst = [e_col, matched_rows]
    if hub_edges:
        src += [full, np.full(n, hub, dtype=INDEX)]
        dst += [np.full(full.size, hub, dtype=INDEX), cols]
    over = _reachable(n_nodes, np.concatenate(src), np.concatenate(dst),
                      np.flatnonzero(mt.row_to_col < 0))

    # Under-determined: column -(any edge)-> row -(matching)-> column, from the unmatched columns.
    src = [e_col, matched_rows]
    dst = [e_row, matched_to]
    if hub_edges:
        src += [cols, np.full(full.size, hub, dtype=INDEX)]
        dst += [np.full(n, hub, dtype=INDEX), full]
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
