"""The residual/algebraic bipartite graph: matching, structural rank, Dulmage-Mendelsohn.

Property tests (hypothesis) check the graph code against linear algebra: the structural rank of a
pattern is the rank of almost every matrix with that pattern, so it must equal the numerical rank
of a random matrix with that pattern (random values from a seeded generator: generic with
probability one). The Dulmage-Mendelsohn parts must partition rows and columns, have the sizes the
rank implies, put the zeros where the block triangular form has them, and not depend on which
maximum matching was found.
"""
from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import structural_rank as scipy_structural_rank

from conformance.numerics.graphs.bipartite import BipartitePattern
from conformance.numerics.graphs.dulmage_mendelsohn import dulmage_mendelsohn
from conformance.numerics.graphs.matching import maximum_matching, structural_rank

MAX = 12


@st.composite
def patterns(draw, max_size: int = MAX, full_rows: bool = True):
    """A random pattern (boolean m x n array) and a random full-row mask."""
    m = draw(st.integers(0, max_size))
    n = draw(st.integers(0, max_size))
    density = draw(st.sampled_from([0.05, 0.15, 0.3, 0.6]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    dense = rng.random((m, n)) < density
    full = (rng.random(m) < 0.1) if full_rows else np.zeros(m, dtype=bool)
    return dense, full


def _pattern(dense: np.ndarray, full: np.ndarray) -> BipartitePattern:
    rows = [None if full[i] else np.flatnonzero(dense[i]).tolist() for i in range(dense.shape[0])]
    return BipartitePattern.from_rows(rows, dense.shape[1])


def _numeric_rank(mask: np.ndarray, seed: int) -> int:
    if mask.size == 0:
        return 0
    rng = np.random.default_rng(seed)
    values = rng.uniform(1.0, 2.0, mask.shape) * rng.choice([-1.0, 1.0], mask.shape)
    return int(np.linalg.matrix_rank(np.where(mask, values, 0.0)))


# --- properties ---------------------------------------------------------------------------------

@settings(max_examples=300, deadline=None)
@given(patterns(), st.integers(0, 2**32 - 1))
def test_structural_rank_equals_numerical_rank_of_a_generic_matrix(pat, seed):
    dense, full = pat
    p = _pattern(dense, full)
    assert structural_rank(p) == _numeric_rank(p.to_dense(), seed)


@settings(max_examples=200, deadline=None)
@given(patterns())
def test_greedy_prepass_never_exceeds_the_maximum_matching(pat):
    # The index-1 check trusts a full-size greedy matching without calling scipy; that is
    # sound only because a greedy matching is a matching, so never larger than a maximum one.
    from conformance.checks.index1 import _greedy_matching_size

    dense, full = pat
    rows = [None if full[i] else np.flatnonzero(dense[i]).tolist() for i in range(dense.shape[0])]
    greedy = _greedy_matching_size(rows, dense.shape[1])
    assert greedy <= structural_rank(_pattern(dense, full))


@given(patterns(full_rows=False))
def test_structural_rank_agrees_with_scipy(pat):
    dense, _ = pat
    if dense.size == 0:
        return
    assert structural_rank(dense) == scipy_structural_rank(csr_matrix(dense.astype(np.int8)))


@settings(max_examples=300, deadline=None)
@given(patterns())
def test_matching_is_a_valid_matching(pat):
    dense, full = pat
    p = _pattern(dense, full)
    mt = maximum_matching(p)
    mask = p.to_dense()
    rows = np.flatnonzero(mt.row_to_col >= 0)
    cols = mt.row_to_col[rows]
    assert len(set(cols.tolist())) == cols.size
    assert mask[rows, cols].all()
    assert (mt.col_to_row[cols] == rows).all()
    assert np.count_nonzero(mt.col_to_row >= 0) == rows.size


@settings(max_examples=300, deadline=None)
@given(patterns())
def test_dulmage_mendelsohn_parts_are_consistent(pat):
    dense, full = pat
    p = _pattern(dense, full)
    m, n = p.shape
    dm = dulmage_mendelsohn(p)
    mask = p.to_dense()
    # the parts partition the rows and the columns
    rows = np.concatenate([dm.over_rows, dm.under_rows, dm.square_rows])
    cols = np.concatenate([dm.over_cols, dm.under_cols, dm.square_cols])
    assert sorted(rows.tolist()) == list(range(m))
    assert sorted(cols.tolist()) == list(range(n))
    # sizes: the square part is square; the excesses are the unmatched rows and columns
    assert dm.square_rows.size == dm.square_cols.size
    assert dm.over_rows.size - dm.over_cols.size == m - dm.rank
    assert dm.under_cols.size - dm.under_rows.size == n - dm.rank
    assert dm.rank == dm.over_cols.size + dm.under_rows.size + dm.square_rows.size
    assert dm.is_perfect == (m == n == dm.rank)
    # block triangular form: zeros below the diagonal blocks
    assert not mask[np.ix_(dm.over_rows, np.concatenate([dm.under_cols, dm.square_cols]))].any()
    assert not mask[np.ix_(dm.square_rows, dm.under_cols)].any()
    # the matching stays inside each part
    r2c = dm.matching.row_to_col
    assert np.isin(r2c[dm.square_rows], dm.square_cols).all()
    assert np.isin(r2c[dm.under_rows], dm.under_cols).all()
    assert np.isin(dm.matching.col_to_row[dm.over_cols], dm.over_rows).all()
    # the over-determined part is structurally rank deficient exactly by its excess
    assert structural_rank(mask[np.ix_(dm.over_rows, dm.over_cols)]) == dm.over_cols.size
    assert structural_rank(mask[np.ix_(dm.square_rows, dm.square_cols)]) == dm.square_rows.size


@settings(max_examples=200, deadline=None)
@given(patterns(), st.integers(0, 2**32 - 1))
def test_dulmage_mendelsohn_does_not_depend_on_the_matching(pat, seed):
    dense, full = pat
    m, n = dense.shape
    rng = np.random.default_rng(seed)
    rp, cp = rng.permutation(m), rng.permutation(n)
    dm = dulmage_mendelsohn(_pattern(dense, full))
    dmp = dulmage_mendelsohn(_pattern(dense[np.ix_(rp, cp)], full[rp]))
    for part in ("over_rows", "under_rows", "square_rows"):
        assert sorted(rp[getattr(dmp, part)].tolist()) == getattr(dm, part).tolist()
    for part in ("over_cols", "under_cols", "square_cols"):
        assert sorted(cp[getattr(dmp, part)].tolist()) == getattr(dm, part).tolist()


@settings(max_examples=200, deadline=None)
@given(patterns())
def test_full_rows_equal_their_dense_form(pat):
    dense, full = pat
    implicit = dulmage_mendelsohn(_pattern(dense, full))
    explicit = dulmage_mendelsohn(_pattern(dense, full).to_dense())
    assert implicit.rank == explicit.rank
    for part in ("over_rows", "over_cols", "under_rows", "under_cols"):
        assert getattr(implicit, part).tolist() == getattr(explicit, part).tolist()


# --- examples -----------------------------------------------------------------------------------

def test_hello_world_and_its_broken_form():
    # g1, g2 x y, z: both residuals depend on both algebraic variables
    assert dulmage_mendelsohn([[1, 1], [1, 1]]).is_perfect
    dm = dulmage_mendelsohn([[1, 0], [1, 0]])
    assert dm.rank == 1
    assert dm.over_rows.tolist() == [0, 1] and dm.over_cols.tolist() == [0]
    assert dm.under_rows.tolist() == [] and dm.under_cols.tolist() == [1]


def test_empty_and_degenerate_shapes():
    for shape in [(0, 0), (0, 3), (3, 0)]:
        dm = dulmage_mendelsohn(np.zeros(shape))
        assert dm.rank == 0
        assert dm.over_rows.size == shape[0] and dm.under_cols.size == shape[1]
    dm = dulmage_mendelsohn(BipartitePattern.from_rows([None, None], 0))
    assert dm.rank == 0 and dm.over_rows.tolist() == [0, 1]
    assert structural_rank(BipartitePattern.from_rows([None, None, None], 2)) == 2


def test_from_rows_merges_duplicates_and_checks_bounds():
    p = BipartitePattern.from_rows([[1, 1, 0], None, []], 3)
    assert p.to_dense().tolist() == [[True, True, False], [True, True, True],
                                      [False, False, False]]
    assert p.sparse.data.tolist() == [1, 1]
    with pytest.raises(ValueError):
        BipartitePattern.from_rows([[0], [3]], 3)


def test_from_matrix_counts_stored_entries():
    sparse = csr_matrix((np.array([0.0, 2.0]), (np.array([0, 1]), np.array([0, 0]))), shape=(2, 2))
    assert structural_rank(sparse) == 1          # a stored zero is still an edge
    assert structural_rank(np.array([[0.0, 0.0], [3.0, 0.0]])) == 1


def test_full_row_entries_do_not_steal_the_matching():
    # row 0 is full but also stores an edge to column 0, which row 1 needs
    p = BipartitePattern(csr_matrix(np.array([[1, 0], [1, 0]], dtype=np.int8)),
                         np.array([True, False]))
    assert structural_rank(p) == 2


def _chain(n: int, broken: int | None = None) -> BipartitePattern:
    rows: list[list[int] | None] = [[k - 1, k] if k else [0] for k in range(n)]
    if broken is not None:
        rows[broken] = [broken - 1]
    return BipartitePattern.from_rows(rows, n)


def test_large_chain_is_fast():
    n = 25_000
    start = time.perf_counter()
    dm = dulmage_mendelsohn(_chain(n))
    assert dm.is_perfect and dm.rank == n
    dm = dulmage_mendelsohn(_chain(n, broken=n // 2))
    elapsed = time.perf_counter() - start
    assert dm.rank == n - 1
    assert (dm.over_rows.size, dm.over_cols.size) == (n // 2 + 1, n // 2)
    assert (dm.under_rows.size, dm.under_cols.size) == (n - n // 2 - 1, n - n // 2)
    assert elapsed < 0.5


def test_many_full_rows_stay_sparse():
    n = 25_000
    start = time.perf_counter()
    p = BipartitePattern.from_rows([None] * n, n)
    dm = dulmage_mendelsohn(p)
    assert dm.is_perfect
    assert p.sparse.nnz == 0
    assert time.perf_counter() - start < 0.5
