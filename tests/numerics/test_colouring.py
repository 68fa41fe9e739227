"""Curtis-Powell-Reid colouring, extraction, and the verification of declared zeros."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conformance.numerics import colouring as col
from conformance.numerics import measure


def banded(n: int, half: int = 1) -> col.Pattern:
    return col.Pattern.from_rows(n, [range(max(0, i - half), min(n, i + half + 1))
                                     for i in range(n)])


def test_pattern_basics():
    p = col.Pattern.from_rows(3, [[2, 0, 0], [], [1]])
    assert p.rows.tolist() == [0, 0, 2] and p.cols.tolist() == [0, 2, 1]
    assert p.contains(0, 2) and not p.contains(1, 0)
    t = p.transpose()
    assert t.shape == (3, 3) and t.to_dense().tolist() == p.to_dense().T.tolist()
    with pytest.raises(ValueError):
        col.Pattern.from_rows(2, [[2]])


@pytest.mark.parametrize("n", [10, 100, 1000, 10000])
def test_groups_of_a_banded_pattern_do_not_grow_with_its_size(n):
    c = col.colour_columns(banded(n))
    assert c.count == 3
    assert col.is_valid(banded(n), c)


def _greedy_with_sets(pattern: col.Pattern) -> np.ndarray:
    """The greedy largest-first colouring written plainly, with a set of groups per row: what
    colour_columns' bitsets must give, group for group."""
    m, n = pattern.shape
    col_rows: list[list[int]] = [[] for _ in range(n)]
    for i, j in zip(pattern.rows.tolist(), pattern.cols.tolist()):
        col_rows[j].append(i)
    row_groups: list[set[int]] = [set() for _ in range(m)]
    group = np.full(n, -1, dtype=np.intp)
    for j in sorted(range(n), key=lambda j: (-len(col_rows[j]), j)):
        taken = set().union(*(row_groups[i] for i in col_rows[j]))
        g = next(g for g in range(n + 1) if g not in taken)
        group[j] = g
        for i in col_rows[j]:
            row_groups[i].add(g)
    return group


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 80), st.integers(1, 80), st.integers(0, 2**32 - 1), st.floats(0.0, 1.0))
def test_the_colouring_is_the_plain_greedy_one(m, n, seed, density):
    """Up to 80 columns, so that more than 64 groups (beyond one machine word) occur."""
    rng = np.random.default_rng(seed)
    mask = rng.random((m, n)) < density
    p = col.Pattern.from_rows(n, [np.flatnonzero(row) for row in mask])
    c = col.colour_columns(p)
    assert c.group.tolist() == _greedy_with_sets(p).tolist()
    assert col.is_valid(p, c)


def test_a_dense_row_puts_every_column_in_its_own_group():
    p = col.Pattern.from_rows(5, [[0], [1, 2], range(5)])
    c = col.colour_columns(p)
    assert c.count == 5
    assert col.one_per_group(p).count == 5
    assert col.one_per_group(p, rows=True).count == 3


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 12), st.integers(1, 12), st.integers(0, 2**32 - 1), st.floats(0.05, 0.6))
def test_colouring_is_valid_and_extraction_exact_for_linear_functions(m, n, seed, density):
    rng = np.random.default_rng(seed)
    mask = rng.random((m, n)) < density
    a = np.where(mask, rng.normal(size=(m, n)), 0.0)
    p = col.Pattern.from_rows(n, [np.flatnonzero(row) for row in mask])
    c = col.colour_columns(p)
    assert col.is_valid(p, c)
    assert c.count <= n
    steps = rng.uniform(0.5, 2.0, n)
    comp = col.coloured_differences(lambda d: a @ d, p, c, steps, method="central",
                                    f0=np.zeros(m))
    np.testing.assert_allclose(comp.value, a[p.rows, p.cols], rtol=1e-12, atol=1e-12)
    assert comp.moved == []
    values, moved, calls = col.coloured_products(lambda s: a @ s, p, c)
    np.testing.assert_allclose(values, a[p.rows, p.cols], rtol=1e-12, atol=1e-12)
    assert moved == [] and calls == c.count


def test_random_directions_are_seeded_and_never_small():
    d1 = col.random_directions(50, 3, np.random.default_rng(7), np.full(50, 2.0))
    d2 = col.random_directions(50, 3, np.random.default_rng(7), np.full(50, 2.0))
    np.testing.assert_array_equal(d1, d2)
    assert np.all(np.abs(d1) >= 1.0) and np.all(np.abs(d1) <= 2.0)


def test_predict():
    p = col.Pattern.from_rows(3, [[0, 2], [1]])
    values = np.array([1.0, -2.0, 3.0])
    np.testing.assert_allclose(col.predict(p, values, np.array([1.0, 1.0, 1.0])), [-1.0, 3.0])
    np.testing.assert_allclose(col.predict_abs(p, values, np.array([1.0, -1.0, 1.0])), [3.0, 3.0])


# ---------------------------------------------------------------------- measure at a point

def _chain(n: int, hidden: tuple[int, int] | None = None, wrong_dd: tuple[int, int] | None = None):
    """g_i = 4 w_i + sin w_i - w_{i-1} - w_{i+1}; optionally an undeclared term, and a
    directional derivative that is wrong at one entry."""
    x0 = np.linspace(-0.5, 0.5, n)

    def fun(delta):
        w = x0 + delta
        g = 4 * w + np.sin(w)
        g[1:] -= w[:-1]
        g[:-1] -= w[1:]
        if hidden:
            i, j = hidden
            g[i] += 0.5 * w[j] ** 2
        return g

    def jac():
        a = np.diag(4 + np.cos(x0)) - np.eye(n, k=1) - np.eye(n, k=-1)
        if hidden:
            a[hidden] += x0[hidden[1]]
        return a

    def directional(seed):
        a = jac()
        if wrong_dd:
            a[wrong_dd] *= 2
        return a @ seed

    return fun, directional, lambda v: v @ jac(), x0


def _measure(n, **kw):
    fun, dd, adj, x0 = _chain(n, **kw)
    p = banded(n)
    c = col.colour_columns(p)
    steps = np.full(n, 1e-5)
    sources = measure.Sources(fun, dd, adj)
    return measure.measure(sources, p, c, steps, x0, np.random.default_rng(0)), p, c


def test_clean_measurement_costs_a_number_of_calls_independent_of_the_size():
    calls = []
    for n in (10, 100, 1000):
        e, p, _ = _measure(n)
        assert e.localised.size == 0
        assert e.declared.all() and e.rows.size == p.nnz
        np.testing.assert_allclose(e.fd, e.dd, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(e.adj, e.dd, rtol=1e-12)
        a, b, size = e.dot
        assert abs(a - b) <= 1e-12 * size
        calls.append(dict(e.calls))
    assert calls[0] == calls[1] == calls[2]
    assert calls[0] == {"evaluate": 1 + 4 * 3 + 4 * 2, "directional": 3 + 2, "adjoint": 3 + 1}


def test_undeclared_dependency_in_an_unowned_group_is_localised():
    # row 0 depends on w_5, a column of a group that holds none of row 0's declared columns
    e, _, _ = _measure(12, hidden=(0, 5))
    assert 0 in e.localised.tolist()
    k = [(i, j) for i, j in zip(e.rows.tolist(), e.cols.tolist())].index((0, 5))
    assert not e.declared[k] and not e.zero[k]
    assert e.fd[k] == pytest.approx(-0.5 + 5 / 11, rel=1e-6)


def test_undeclared_dependency_hidden_behind_a_declared_column_is_localised():
    e, p, c = _measure(12)
    # find a column sharing a group with a declared column of row 0, but not declared itself
    j = next(j for j in range(12)
             if c.group[j] in c.group[p.row(0)] and not p.contains(0, j))
    e, _, _ = _measure(12, hidden=(0, j))
    assert 0 in e.localised.tolist()
    pairs = list(zip(e.rows.tolist(), e.cols.tolist()))
    assert (0, j) in pairs
    k = pairs.index((0, j))
    x0 = np.linspace(-0.5, 0.5, 12)
    assert e.fd[k] == pytest.approx(x0[j], rel=1e-6)
    # the declared entries of row 0 come from column-by-column values, not contaminated ones
    k0 = pairs.index((0, 0))
    assert e.fd[k0] == pytest.approx(4 + np.cos(x0[0]), rel=1e-8)


def test_wrong_directional_derivative_is_measured_on_its_own():
    e, _, _ = _measure(12, wrong_dd=(3, 4))
    pairs = list(zip(e.rows.tolist(), e.cols.tolist()))
    k = pairs.index((3, 4))
    assert e.dd[k] == pytest.approx(2 * e.fd[k], rel=1e-6)


def test_without_derivatives_the_random_directions_alone_find_a_hidden_dependency():
    # no directional derivative to betray it: only the finite differences along the random
    # directions disagree with what the declared entries predict
    _, p, c = _measure(12)
    j = next(j for j in range(12)
             if c.group[j] in c.group[p.row(0)] and not p.contains(0, j))
    fun, _, _, x0 = _chain(12, hidden=(0, j))
    e = measure.measure(measure.Sources(fun), p, c, np.full(12, 1e-5), x0,
                        np.random.default_rng(0))
    assert e.localised.tolist() == [0]
    pairs = list(zip(e.rows.tolist(), e.cols.tolist()))
    assert e.fd[pairs.index((0, j))] == pytest.approx(x0[j], rel=1e-6)
    assert np.isnan(e.dd).all() and np.isnan(e.adj).all() and e.dot is None


def test_coloured_differences_are_central_by_default_with_boolean_zeros():
    # f = (x0^2, 3, x1^3) at x = (1, 2): row 1 does not move; central differences of x0^2 are
    # exact, forward ones would be off by h
    x = np.array([1.0, 2.0])
    p = col.Pattern.from_rows(2, [[0], [1], [1]])
    c = col.colour_columns(p)
    steps = np.array([1e-3, 1e-3])

    def fun(delta):
        y = x + delta
        return np.array([y[0] ** 2, 3.0, y[1] ** 3])

    found = col.coloured_differences(fun, p, c, steps)
    assert found.zero.dtype == bool and found.zero.tolist() == [False, True, False]
    assert found.value[0] == pytest.approx(2.0, rel=1e-12)
    assert found.value[2] == pytest.approx(12.0 + 1e-6, rel=1e-12)   # 3 x^2 + h^2
    assert found.calls == 4 * c.count and found.moved == []   # f(±h), f(±2h) per group


def _entries(**columns) -> measure.Entries:
    k = len(columns["rows"])
    base = dict(declared=np.ones(k, dtype=bool), truncation=np.zeros(k), rounding=np.zeros(k),
                zero=np.zeros(k, dtype=bool), dd=np.full(k, np.nan), adj=np.full(k, np.nan),
                f0=np.zeros(3), basis=np.zeros(3), localised=np.zeros(0, dtype=np.intp),
                dot=None, calls=())
    base.update({name: np.asarray(v) for name, v in columns.items()})
    return measure.Entries(**base)


def test_row_scale_sums_measured_entries_times_the_knowns_nominal():
    e = _entries(rows=[0, 0, 1], cols=[0, 1, 1], fd=[2.0, -4.0, np.nan], step=[1e-6] * 3,
                 declared=[True, False, True])
    nominal = np.array([1.0, 10.0])
    assert measure.row_scale(e, nominal, 3).tolist() == [42.0, 0.0, 0.0]
    assert measure.row_scale(e, nominal, 3, declared_only=True).tolist() == [2.0, 0.0, 0.0]


def test_floor_of_an_underflowing_row_follows_its_unknowns_nominal_and_the_step():
    # row 0: every difference below the smallest normal double (underflows); row 1 resolved
    e = _entries(rows=[0, 0, 1], cols=[0, 1, 1], fd=[0.0, 1e-320, 2.0],
                 step=[1e-6, 0.5, 1e-3])
    tiny, eps = np.finfo(float).tiny, np.finfo(float).eps
    plain = measure.floor(e, 2, ulps=100.0)
    assert plain.tolist() == [(tiny + 100.0 * eps) / 1e-6, (tiny + 100.0 * eps) / 0.5,
                              tiny / 1e-3]
    scaled = measure.floor(e, 2, ulps=100.0, row_nominal=np.array([4.0, 1.0]))
    assert scaled.tolist() == [(tiny + 100.0 * eps * 4.0) / 1e-6,
                               (tiny + 100.0 * eps * 4.0) / 0.5, tiny / 1e-3]
