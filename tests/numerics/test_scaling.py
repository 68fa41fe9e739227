"""The numerics of large models (issue 22): conditioning without n x n work, tolerance floors,
and the integrators' sparse Jacobians, each against its dense counterpart on the same input."""
from __future__ import annotations

import resource
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from conformance.numerics import floors, jacobians
from conformance.numerics.conditioning import DENSE, SPARSE, conditioning
from conformance.numerics.dae import integrate_dae
from conformance.numerics.limits import scaled_condition
from conformance.numerics.ode import integrate_ode
from tests.simkit import sim_settings


def _tridiagonal(n: int, diagonal: float = 4.0) -> sp.csc_array:
    return sp.diags_array([-np.ones(n - 1), np.full(n, diagonal), -np.ones(n - 1)],
                          offsets=[-1, 0, 1], format="csc")


def _random_sparse(n: int, seed: int) -> sp.csc_array:
    rng = np.random.default_rng(seed)
    a = sp.random_array((n, n), density=4.0 / n, rng=rng, format="csc")
    return (a + sp.diags_array(rng.uniform(0.5, 2.0, n))).tocsc()


# -------------------------------------------------------------------- conditioning

@pytest.mark.parametrize("n, seed", [(30, 0), (60, 1), (120, 2)])
def test_sparse_estimate_lies_within_the_norm_bounds_of_the_dense_svd(n, seed):
    a = _random_sparse(n, seed)
    dense = conditioning(a, dense_up_to=n)
    sparse = conditioning(a, dense_up_to=0)
    assert dense.method == DENSE and sparse.method == SPARSE and sparse.norm == 1
    # kappa_1 and kappa_2 lie within a factor n of each other; 1/||A^-1||_1 within sqrt(n)
    # of sigma_min; the Hager-Higham estimate is a lower bound of ||A^-1||_1
    assert dense.condition / n <= sparse.condition * (1 + 1e-12)
    assert sparse.condition <= n * dense.condition * (1 + 1e-12)
    exact_inverse = np.abs(np.linalg.inv(a.toarray())).sum(axis=0).max()
    assert 1.0 / sparse.smallest <= exact_inverse * (1 + 1e-12)
    assert 1.0 / sparse.smallest >= exact_inverse / 3   # Higham & Tisseur: rarely off by more


def test_the_estimate_is_the_same_every_time():
    a = _random_sparse(200, 7)
    first, second = conditioning(a, dense_up_to=0, seed=3), conditioning(a, dense_up_to=0, seed=3)
    assert first.condition == second.condition
    np.testing.assert_array_equal(first.direction, second.direction)
    state = np.random.get_state()[1].copy()
    conditioning(a, dense_up_to=0)
    np.testing.assert_array_equal(np.random.get_state()[1], state)  # the global RNG is left


@pytest.mark.parametrize("n", [50, 500, 5000])
def test_an_exactly_singular_matrix_and_its_null_direction_at_every_size(n):
    # the last row twice the one before it: singular; the null vector lives at the end
    a = _tridiagonal(n).tolil()
    a[n - 1, :] = 2 * a[n - 2, :].toarray()
    found = conditioning(a.tocsc(), dense_up_to=100)
    assert found.condition == np.inf or found.condition > 1e15
    null = found.direction
    assert np.linalg.norm(a.tocsc() @ null) <= 1e-6 * np.linalg.norm(null)


@pytest.mark.parametrize("n", [1000, 20000])
def test_a_nearly_singular_chain_is_seen_at_every_size(n):
    a = _tridiagonal(n).tolil()
    a[n - 1, :] = a[n - 2, :].toarray()
    a[n - 1, n - 1] += 1e-10
    found = conditioning(a.tocsc(), dense_up_to=200)
    assert 1e9 < found.condition < 1e13
    assert np.argmax(np.abs(found.direction)) >= n - 3


def test_no_dense_work_on_a_large_sparse_matrix():
    # 100,000 x 100,000 dense would be 80 GB; the estimate runs in a process limited to 1 GiB
    code = (
        "import resource; resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))\n"
        "import numpy as np, scipy.sparse as sp\n"
        "from conformance.numerics.conditioning import conditioning\n"
        "n = 100_000\n"
        "a = sp.diags_array([-np.ones(n - 1), np.full(n, 4.0), -np.ones(n - 1)], "
        "offsets=[-1, 0, 1], format='csc')\n"
        "found = conditioning(a, dense_up_to=200)\n"
        "assert 1.5 < found.condition < 6, found\n"
        "print(found.factor_nonzeros)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout) < 10 * 3 * 100_000   # the LU's nonzeros stay O(nnz)


def test_scaled_condition_is_the_same_question_dense_or_sparse():
    rng = np.random.default_rng(5)
    nx, nw = 3, 60
    jac = rng.normal(size=(nx + nw, nx + nw)) * (rng.random((nx + nw, nx + nw)) < 0.1)
    jac[nx:, nx:] += np.diag(rng.uniform(2, 3, nw))
    nominal = rng.uniform(0.5, 2.0, nx + nw)
    dense, _ = scaled_condition(jac, nx, nominal, dense_up_to=1000)
    sparse, _ = scaled_condition(sp.csc_array(jac), nx, nominal, dense_up_to=0)
    assert dense / np.sqrt(nw) <= sparse * (1 + 1e-12) and sparse <= dense * np.sqrt(nw) * 1.001


# ---------------------------------------------------------------------------- floors

def test_a_row_that_underflows_gets_the_resolution_floor_and_others_only_the_tiny_one():
    rows = np.array([0, 0, 1, 1, 2])
    fd = np.array([0.0, 3e-320, 1e-3, 0.0, np.nan])
    under = floors.underflowing_rows(rows, fd, 4)
    assert under.tolist() == [True, False, False, True]   # a row without entries resolves nothing
    step = np.array([1e-6, 1e-6, 1e-6, 0.0, 1e-6])
    floor = floors.derivative_floor(np.ones(5), step, under[rows], ulps=100.0)
    assert floor[0] == pytest.approx(100 * floors.EPS / 1e-6 + floors.TINY / 1e-6)
    assert floor[2] == pytest.approx(floors.TINY / 1e-6) and floor[3] == 0.0
    # a value at the level of the smallest normal double is never a mismatch, anywhere
    assert floors.value_floor(np.array([1.0]), np.array([False]), ulps=100.0)[0] >= 3e-321


def test_the_resolution_floor_scales_with_the_unknowns_nominal():
    under = np.array([True, True])
    floor = floors.derivative_floor(np.array([1.0, 1e-6]), np.array([1e-6, 1e-6]), under,
                                    ulps=100.0)
    assert floor[1] / floor[0] == pytest.approx(1e-6, rel=1e-9)


# ------------------------------------------------------------------ sparse Jacobians

def test_the_sparse_template_fills_the_solvers_array_in_column_order():
    n = 4
    rows, cols = np.array([0, 1, 3, 2]), np.array([1, 0, 2, 3])
    template = jacobians.SparseTemplate(n, rows, cols)
    jac = sp.csc_array((np.array([5.0, 6.0, 7.0, 8.0]), (rows, cols)), shape=(n, n))
    out = np.empty(template.nnz)
    template.fill(jac, out, diagonal_shift=np.array([-1.0, 0.0, 0.0, 0.0]))
    filled = sp.csc_matrix((out, template.pattern.indices, template.pattern.indptr),
                           shape=(n, n)).toarray()
    expected = jac.toarray()
    expected[0, 0] -= 1.0
    np.testing.assert_array_equal(filled, expected)
    assert template.pattern.indices.dtype == np.int32   # SUNDIALS' index type


class _Chain:
    """der(x) = w0 - x; 0 = 4 w_i + sin(w_i) - w_{i-1} - w_{i+1} (w_{-1} = x, w_n = 0): the
    Chain's equations in numpy, dense or sparse partials."""

    nx = 1
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, n: int, sparse: bool):
        self.nw, self.sparse = n, sparse
        self.names = ["x", *(f"w[{i}]" for i in range(n))]
        self.nominal = np.ones(n + 1)
        i = np.arange(n)
        self.rows = np.concatenate([[0, 0], 1 + i, 1 + i, 1 + i[:-1]])
        self.cols = np.concatenate([[0, 1], 1 + i, i, 2 + i[:-1]])
        self.pattern = (self.rows, self.cols)

    def evaluate(self, t, y):
        x, w = y[0], y[1:]
        left = np.concatenate([[x], w[:-1]])
        right = np.concatenate([w[1:], [0.0]])
        return np.concatenate([[w[0] - x], 4 * w + np.sin(w) - left - right])

    def partials(self, t, y):
        w = y[1:]
        values = np.concatenate([[-1.0, 1.0], 4 + np.cos(w), -np.ones(self.nw),
                                 -np.ones(self.nw - 1)])
        jac = sp.csc_array((values, (self.rows, self.cols)), shape=(self.nw + 1,) * 2)
        return jac if self.sparse else jac.toarray()


def test_sparse_and_dense_integration_give_the_same_trajectory():
    n = 300
    y0 = np.zeros(n + 1)
    y0[0] = 1.0
    runs = []
    for sparse in (False, True):   # the safety net out of the way: a loaded machine is slow
        settings = sim_settings(dense_up_to=10 if sparse else 10_000, rtol=1e-8,
                                wall_seconds=300.0)
        runs.append(integrate_dae(_Chain(n, sparse), settings, t0=0.0, y0=y0, stop=1.0))
    assert all(r.ok for r in runs), [r.message for r in runs]
    np.testing.assert_allclose(runs[1].values, runs[0].values, rtol=1e-6, atol=1e-10)
    assert runs[1].init["condition"] == pytest.approx(runs[0].init["condition"], rel=0.5)


def test_a_sparse_integration_of_10000_unknowns_stays_small():
    n = 10_000
    y0 = np.zeros(n + 1)
    y0[0] = 1.0
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    traj = integrate_dae(_Chain(n, True), sim_settings(wall_seconds=300.0), t0=0.0, y0=y0,
                         stop=1.0)
    grown_mib = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    assert traj.ok, traj.message
    assert grown_mib < 200   # a dense iteration matrix alone would be 763 MiB


class _Diffusion:
    """x' = -A x, A tridiagonal (2, -1): an ODE of n states, dense or sparse partials."""

    jacobian_source = "exact"
    fmi_calls = 0
    algebraic_names: list[str] = []

    def __init__(self, n: int, sparse: bool):
        self.nx, self.sparse = n, sparse
        self.names = [f"x[{i}]" for i in range(n)]
        self.nominal = np.ones(n)
        self.a = _tridiagonal(n, 2.0)
        coo = self.a.tocoo()
        self.pattern = (coo.row, coo.col)

    def evaluate(self, t, x):
        return -(self.a @ x)

    def partials(self, t, x):
        return -self.a if self.sparse else -self.a.toarray()

    def algebraic_values(self, t, x):
        return np.zeros(0)


def test_cvode_with_a_sparse_jacobian_matches_the_dense_one():
    n = 400
    x0 = np.sin(np.linspace(0, np.pi, n))
    runs = [integrate_ode(_Diffusion(n, sparse), sim_settings(
        dense_up_to=10 if sparse else 10_000, rtol=1e-8, wall_seconds=300.0), t0=0.0, x0=x0,
        stop=1.0) for sparse in (False, True)]
    assert all(r.ok for r in runs), [r.message for r in runs]
    np.testing.assert_allclose(runs[1].values, runs[0].values, rtol=1e-6, atol=1e-10)
