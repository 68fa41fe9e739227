"""How close a square matrix is to singular, at a cost that grows with its nonzeros.

Up to ``dense_up_to`` rows the matrix is decomposed by a dense SVD: the 2-norm condition
number ``sigma_max / sigma_min`` and the right singular vector of ``sigma_min``, exactly. Above
it nothing of size n x n is formed: a sparse LU (SuperLU through
:func:`scipy.sparse.linalg.splu`, COLAMD column ordering) factors it in memory proportional to
the factors' nonzeros, and the 1-norm of the inverse is *estimated* by the block
Hager-Higham algorithm (:func:`scipy.sparse.linalg.onenormest`; N. J. Higham and F. Tisseur,
SIAM J. Matrix Anal. Appl. 21(4), 2000) on the LU solve seen as a linear operator, a handful of
solves. The condition number is then the 1-norm one, ``||A||_1 ||A^-1||_1``, which lies
within a factor n of the 2-norm one (Golub & Van Loan, *Matrix Computations*, 4th ed., 2013,
§2.3.2), and ``1 / ||A^-1||_1`` stands for the smallest singular value (it lies between
``sigma_min / sqrt(n)`` and ``sigma_min * sqrt(n)``). The direction of near-singularity comes
from a few steps of inverse iteration on ``A^T A`` with the same factors; an exactly singular
matrix (a zero pivot) is shifted by ``sqrt(eps) ||A||_1`` first, which leaves its null vectors
the dominant ones of the inverse.

Helpers return measured values; the caller (a probe rule, the integrator) decides what is
ill-conditioned or singular. The random starts are seeded, so two runs agree.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

EPS = float(np.finfo(np.float64).eps)
INVERSE_ITERATIONS = 3
DENSE, SPARSE = "dense SVD (2-norm)", "sparse LU, Hager-Higham estimate of the 1-norm"


@dataclass(frozen=True)
class Conditioning:
    """What :func:`conditioning` measured.

    Attributes
    ----------
    condition : float
        ``largest / smallest``: the 2-norm condition number (dense) or the estimated 1-norm one
        (sparse); ``inf`` for a matrix that is exactly singular or all zero.
    smallest : float
        ``sigma_min`` (dense) or ``1 / ||A^-1||_1`` (sparse, estimated): the distance to the
        nearest singular matrix in that norm; 0 when exactly singular.
    largest : float
        ``sigma_max`` (dense) or ``||A||_1`` (sparse).
    direction : ndarray, shape (n,)
        Unit vector (2-norm) along which ``A`` is closest to singular: the right singular vector
        of ``sigma_min`` (dense) or its inverse-iteration estimate (sparse).
    norm : int
        2 (dense) or 1 (sparse): the norm of ``condition``, ``smallest`` and ``largest``.
    method : str
        :data:`DENSE` or :data:`SPARSE`, for the evidence.
    factor_nonzeros : int
        Nonzeros of the sparse LU factors (0 for the dense SVD): what the estimate cost in
        memory, against the matrix's own nonzeros.
    """

    condition: float
    smallest: float
    largest: float
    direction: np.ndarray
    norm: int
    method: str
    factor_nonzeros: int = 0


def conditioning(matrix: Any, *, dense_up_to: int, seed: int = 0) -> Conditioning:
    """How close the square ``matrix`` (an ndarray or a scipy.sparse matrix, finite) is to
    singular: a dense SVD when it has at most ``dense_up_to`` rows, else a sparse LU with the
    Hager-Higham estimate of ``||A^-1||_1`` (see the module docstring). ``seed`` seeds the random
    starts of the estimate and of the inverse iteration."""
    n = matrix.shape[0]
    if matrix.shape != (n, n):
        raise ValueError(f"a square matrix is needed, not {matrix.shape}")
    if n == 0:
        return Conditioning(1.0, 1.0, 1.0, np.zeros(0), 2, DENSE)
    if n <= dense_up_to:
        dense = matrix.toarray() if hasattr(matrix, "toarray") else matrix  # sparse or not
        return _dense(np.asarray(dense, dtype=float))
    import scipy.sparse as sp  # scipy: only for a matrix too large for a dense SVD

    return _sparse(sp.csc_array(matrix, dtype=float), seed)


def _dense(a: np.ndarray) -> Conditioning:
    _, sv, vt = np.linalg.svd(a)
    largest, smallest = float(sv[0]), float(sv[-1])
    condition = largest / smallest if smallest > 0 else np.inf
    return Conditioning(condition, smallest, largest, vt[-1], 2, DENSE)


def _sparse(a: Any, seed: int) -> Conditioning:
    from scipy.sparse.linalg import LinearOperator, onenormest, splu  # scipy: sparse only

    n = a.shape[0]
    largest = float(abs(a).sum(axis=0).max()) if a.nnz else 0.0
    rng = np.random.default_rng(seed)
    if largest == 0.0:
        return Conditioning(np.inf, 0.0, 0.0, _unit(rng.standard_normal(n)), 1, SPARSE)
    try:
        lu = splu(a, permc_spec="COLAMD")
    except RuntimeError:  # SuperLU: "Factor is exactly singular" (a zero pivot)
        return _exactly_singular(a, largest, rng)
    nonzeros = int(lu.L.nnz + lu.U.nnz)
    inverse = LinearOperator(
        (n, n), matvec=lu.solve, rmatvec=lambda x: lu.solve(x, trans="T"),
        matmat=lu.solve, rmatmat=lambda x: lu.solve(x, trans="T"), dtype=float)
    with _seeded_legacy_random(seed):  # onenormest draws from numpy's global generator
        inverse_norm = float(onenormest(inverse)) if n > 2 else _exact_norm(inverse, n)
    direction = _inverse_iteration(lu, rng.standard_normal(n))
    if not (np.isfinite(inverse_norm) and inverse_norm > 0):
        return Conditioning(np.inf, 0.0, largest, direction, 1, SPARSE, nonzeros)
    return Conditioning(largest * inverse_norm, 1.0 / inverse_norm, largest, direction, 1,
                        SPARSE, nonzeros)


def _exactly_singular(a: Any, largest: float, rng: np.random.Generator) -> Conditioning:
    """A zero pivot: the null direction from inverse iteration on ``A + shift I``."""
    import scipy.sparse as sp  # scipy: sparse only
    from scipy.sparse.linalg import splu  # scipy: sparse only

    n = a.shape[0]
    direction = _unit(rng.standard_normal(n))
    for sign in (1.0, -1.0, 2.0):  # a shift that is itself an eigenvalue is next to impossible
        shifted = (a + sign * np.sqrt(EPS) * largest * sp.identity(n, format="csc")).tocsc()
        try:
            lu = splu(shifted, permc_spec="COLAMD")
        except RuntimeError:
            continue
        direction = _inverse_iteration(lu, direction)
        nonzeros = int(lu.L.nnz + lu.U.nnz)
        return Conditioning(np.inf, 0.0, largest, direction, 1, SPARSE, nonzeros)
    return Conditioning(np.inf, 0.0, largest, direction, 1, SPARSE)


def _inverse_iteration(lu: Any, start: np.ndarray) -> np.ndarray:
    """A few steps of ``v <- A^-1 A^-T v``: towards the right singular vector of sigma_min."""
    v = _unit(start)
    for _ in range(INVERSE_ITERATIONS):
        with np.errstate(all="ignore"):
            w = lu.solve(lu.solve(v, trans="T"))
        if not np.all(np.isfinite(w)) or not np.any(w):
            break
        v = _unit(w)
    return v


def _exact_norm(op: Any, n: int) -> float:
    """``||op||_1`` of a tiny operator, column by column."""
    return float(max(np.abs(op.matvec(e)).sum() for e in np.eye(n)))


def _unit(v: np.ndarray) -> np.ndarray:
    size = float(np.linalg.norm(v))
    return v / size if size > 0 and np.isfinite(size) else np.zeros_like(v)


@contextlib.contextmanager
def _seeded_legacy_random(seed: int) -> Iterator[None]:
    """numpy's global (legacy) generator seeded for the block, and restored afterwards."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        yield
    finally:
        np.random.set_state(state)
