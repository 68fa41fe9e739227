"""Sets of integer keys (value references, entry keys ``row * n + col``) held as sorted arrays.

numpy's ``unique`` and ``isin`` take a hash path for plain integer arrays (numpy 2.x) that costs
about half a second per 300,000 keys on the 2-core machine of ``make bench``, fifty times a sort:
a model of 10,000 variables with 30 nonzeros per row builds such sets a few dozen times per
check. Both functions here give exactly what numpy's would for 1-D integer arrays, through one
sort; any other dtype goes to numpy unchanged.
"""
from __future__ import annotations

import numpy as np


def _integer(a: np.ndarray) -> bool:
    return a.ndim == 1 and a.dtype.kind in "iu"


def unique_ints(values: np.ndarray) -> np.ndarray:
    """The sorted distinct values of ``values`` (``np.unique(values)``)."""
    a = np.asarray(values)
    if not _integer(a):
        return np.unique(a)
    s = np.sort(a)
    if s.size < 2:
        return s
    keep = np.empty(s.size, dtype=bool)
    keep[0] = True
    np.not_equal(s[1:], s[:-1], out=keep[1:])
    return s[keep]


def isin_ints(values: np.ndarray, members: np.ndarray) -> np.ndarray:
    """For each of ``values``, whether it is one of ``members`` (``np.isin(values, members)``)."""
    a, b = np.asarray(values), np.asarray(members)
    if not (_integer(a) and _integer(b)) or (a.dtype != b.dtype and "u" in a.dtype.kind + b.dtype.kind):
        return np.isin(a, b)  # mixed signedness: numpy's own promotion
    table = unique_ints(b)
    if table.size == 0:
        return np.zeros(a.shape, dtype=bool)
    at = np.searchsorted(table, a)
    at[at == table.size] = 0
    return table[at] == a
