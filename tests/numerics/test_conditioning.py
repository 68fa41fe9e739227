"""The measured condition of tiny matrices, by hand: the sparse path's exact values (its 1-norm
of ``A^-1`` column by column up to n = 2), its singular and overflowing branches, and n = 0."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from conformance.numerics.conditioning import DENSE, SPARSE, conditioning


def test_an_empty_matrix_is_perfectly_conditioned_by_the_dense_method():
    found = conditioning(np.zeros((0, 0)), dense_up_to=10)
    assert (found.condition, found.smallest, found.largest, found.norm, found.method,
            found.factor_nonzeros) == (1.0, 1.0, 1.0, 2, DENSE, 0)
    assert found.direction.shape == (0,)


def test_a_two_by_two_sparse_matrix_is_measured_exactly_in_the_1_norm():
    # ||A||_1 = max(2 + 1, 4) = 4; A^-1 = [[1/2, 0], [-1/8, 1/4]], ||A^-1||_1 = 5/8
    a = sp.csc_array(np.array([[2.0, 0.0], [1.0, 4.0]]))
    found = conditioning(a, dense_up_to=0)
    assert found.method == SPARSE and found.norm == 1
    assert found.largest == 4.0
    assert found.smallest == 1.0 / 0.625 and found.condition == 4.0 * 0.625
    assert found.factor_nonzeros > 0


def test_a_one_by_one_sparse_matrix():
    found = conditioning(sp.csc_array(np.array([[-5.0]])), dense_up_to=0)
    assert (found.condition, found.smallest, found.largest) == (1.0, 5.0, 5.0)
    assert abs(found.direction[0]) == 1.0


def test_an_exactly_singular_sparse_matrix_has_infinite_condition_and_its_null_direction():
    a = sp.csc_array(np.array([[1.0, 2.0, 0.0], [2.0, 4.0, 0.0], [0.0, 0.0, 1.0]]))
    found = conditioning(a, dense_up_to=0, seed=1)
    assert (found.condition, found.smallest, found.largest, found.norm, found.method) == (
        np.inf, 0.0, 6.0, 1, SPARSE)
    assert found.factor_nonzeros > 0
    # the null vector of A is (2, -1, 0) / sqrt(5)
    assert np.allclose(np.abs(found.direction), np.array([2.0, 1.0, 0.0]) / np.sqrt(5.0),
                       atol=1e-6)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_an_inverse_that_overflows_counts_as_singular_with_the_factors_kept():
    # a pivot of 1e-310 (subnormal, not zero): the LU succeeds, A^-1 overflows to inf
    a = sp.csc_array(np.diag([1.0, 2.0, 1e-310]))
    found = conditioning(a, dense_up_to=0)
    assert (found.condition, found.smallest, found.largest, found.norm, found.method) == (
        np.inf, 0.0, 2.0, 1, SPARSE)
    assert found.factor_nonzeros == 6   # L: unit diagonal (3), U: diagonal (3)


def test_an_all_zero_sparse_matrix():
    found = conditioning(sp.csc_array((3, 3)), dense_up_to=0)
    assert (found.condition, found.smallest, found.largest, found.norm, found.method,
            found.factor_nonzeros) == (np.inf, 0.0, 0.0, 1, SPARSE, 0)
    assert np.isclose(np.linalg.norm(found.direction), 1.0)   # a seeded random unit vector
