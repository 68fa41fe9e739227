"""Integer sets through one sort equal numpy's unique and isin (conformance.numerics.intsets)."""
from __future__ import annotations

import numpy as np
from hypothesis import given, strategies as st
from hypothesis.extra import numpy as hnp

from conformance.numerics.intsets import isin_ints, unique_ints

KEYS = hnp.arrays(np.int64, st.integers(0, 60), elements=st.integers(-50, 50))


@given(KEYS)
def test_unique_ints_is_numpys_unique(values):
    got = unique_ints(values)
    assert got.dtype == values.dtype and np.array_equal(got, np.unique(values))


@given(KEYS, KEYS)
def test_isin_ints_is_numpys_isin(values, members):
    assert np.array_equal(isin_ints(values, members), np.isin(values, members))


def test_other_dtypes_and_mixed_signedness_go_to_numpy():
    floats = np.array([1.5, np.nan, 1.5, -0.0, 0.0])
    assert np.array_equal(unique_ints(floats), np.unique(floats), equal_nan=True)
    unsigned = np.array([1, 2, 3], dtype=np.uint64)
    signed = np.array([-1, 2], dtype=np.int64)
    assert np.array_equal(isin_ints(unsigned, signed), np.isin(unsigned, signed))
    assert np.array_equal(isin_ints(np.arange(4, dtype=np.int32), np.array([3, 9])),
                          [False, False, False, True])


def test_a_single_value_or_a_table_of_values_goes_to_numpy():
    members = np.array([1, 3])
    assert isin_ints(np.int64(3), members) == np.isin(3, members)
    assert isin_ints(np.array(2), members).shape == ()
    table = np.array([[1, 2], [3, 4]])
    assert isin_ints(table, members).tolist() == [[True, False], [True, False]]
