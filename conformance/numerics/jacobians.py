"""Jacobians of the integrated systems: dense arrays when small, sparse when large.

A system's ``partials(t, y)`` returns an ndarray of shape (n, n) or, above the size the
settings allow for dense work (``dense_up_to``), a scipy.sparse CSC matrix holding the declared
entries only, so that nothing of size n x n is formed for a model of 10,000 variables. The
integrators and the consistent initialisation do a handful of things with it, each here for
both kinds: read a block, weigh its rows, solve with it (dense LU, or SuperLU), check that it is
finite, and hand it to SUNDIALS, whose sparse linear solver (SuperLU_MT) takes the entries in
the compressed-column order of a pattern fixed when the solver is made
(:class:`SparseTemplate`). The dense paths are the arithmetic they always were.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .intsets import unique_ints


def is_sparse(jac: Any) -> bool:
    """Whether ``jac`` is a scipy.sparse matrix (an ndarray otherwise)."""
    return hasattr(jac, "tocsc")


def finite(jac: Any) -> bool:
    """Every stored entry is finite."""
    return bool(np.all(np.isfinite(jac.data if is_sparse(jac) else jac)))


def weighted_row_sums(jac: Any, weights: np.ndarray) -> np.ndarray:
    """``sum_j |jac_ij| * weights_j`` per row, shape (rows,)."""
    if is_sparse(jac):
        return np.asarray(abs(jac) @ np.asarray(weights, dtype=float), dtype=float).ravel()
    return np.abs(jac * np.asarray(weights, dtype=float)[None, :]).sum(axis=1)


def solve(a: Any, b: np.ndarray) -> np.ndarray:
    """``a^-1 b`` for a square ``a``; numpy's LinAlgError when ``a`` is singular (a zero pivot
    of SuperLU for a sparse one)."""
    if not is_sparse(a):
        return np.linalg.solve(a, b)
    from scipy.sparse.linalg import splu  # scipy: only for a sparse Jacobian

    try:
        return splu(a.tocsc(), permc_spec="COLAMD").solve(np.asarray(b, dtype=float))
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(exc)) from None


def identity(n: int, *, sparse: bool) -> Any:
    """The identity of size n, sparse (CSC) or not (a stand-in after a failure)."""
    if sparse:
        import scipy.sparse as sp  # scipy: only for a sparse Jacobian

        return sp.identity(n, format="csc")
    return np.eye(n)


class SparseTemplate:
    """The fixed compressed-column pattern SUNDIALS' sparse solver is made with: the system's
    declared entries (``rows``, ``cols``) and the whole diagonal (where ``cj`` or the identity
    goes), with 32-bit indices as SUNDIALS' ``sunindextype`` of scikit-sundae is.

    :meth:`fill` writes a sparse Jacobian into the solver's data array (length ``nnz``, CSC
    order); an entry outside the pattern cannot be given to the solver and is left out.
    """

    def __init__(self, n: int, rows: np.ndarray, cols: np.ndarray):
        import scipy.sparse as sp  # scipy: only for a sparse Jacobian

        diagonal = np.arange(n)
        r = np.concatenate([np.asarray(rows, dtype=np.int64), diagonal])
        c = np.concatenate([np.asarray(cols, dtype=np.int64), diagonal])
        keys = unique_ints(c * n + r)           # column-major: the CSC order
        self.n, self.keys = n, keys
        indices = (keys % n).astype(np.int32)
        indptr = np.searchsorted(keys // n, np.arange(n + 1)).astype(np.int32)
        self.pattern = sp.csc_matrix((np.ones(keys.size), indices, indptr), shape=(n, n))
        self.nnz = int(keys.size)
        self.diagonal = np.searchsorted(keys, diagonal * n + diagonal)

    def fill(self, jac: Any, out: np.ndarray, *, diagonal_shift: np.ndarray | None = None
             ) -> None:
        """``out[:] = jac`` in the template's order, then ``diagonal_shift`` added to the
        diagonal (``-cj`` on the differential rows of IDA's iteration matrix)."""
        coo = jac.tocoo()
        keys = coo.col.astype(np.int64) * self.n + coo.row
        at = np.searchsorted(self.keys, keys)
        inside = at < self.keys.size
        inside[inside] = self.keys[at[inside]] == keys[inside]
        out[:] = 0.0
        np.add.at(out, at[inside], coo.data[inside])
        if diagonal_shift is not None:
            out[self.diagonal] += diagonal_shift
