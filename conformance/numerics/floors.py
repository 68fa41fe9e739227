"""Absolute floors for the probes' comparisons: below them a measurement resolves nothing.

The probes scale every tolerance by what the function does: a partial derivative ``J_ij`` is
compared in units of its row's scale ``S_i = sum_j |J_ij| nominal_j`` and of the finite
difference's own error estimate, a value in units of its magnitude and of its rounding noise.
Where the function does not move measurably all of these are zero, and so is the tolerance:
along a diagonally dominant chain the sensitivity of a far variable shrinks by a factor of 4
per link and underflows, the finite differences of its row are exactly 0 with an error
estimate of 0, and an FMU that reports the true value, 3e-321, would "differ" from them.

Two floors close that gap, both far below anything a scaled tolerance allows elsewhere:

* **resolution**: where every finite difference of a row is zero or underflows (below the
  smallest normal double), nothing about the row was resolved below the noise of a value of
  the unknown's own size, ``ulps * eps * nominal_i``; over the known's step ``h_j`` that is a
  derivative of ``ulps * eps * nominal_i / h_j`` (for a value: ``ulps * eps * nominal_i``);
* **underflow**: a derivative whose change over the step, ``J_ij h_j``, is below the smallest
  normal double cannot be measured at all (a value below it is no value): ``TINY / h_j``
  (``TINY``), everywhere.

The helpers return the floors; each rule takes the larger of its scaled tolerance and the floor
and says in its evidence which one applied.
"""
from __future__ import annotations

import numpy as np

EPS = float(np.finfo(np.float64).eps)
TINY = float(np.finfo(np.float64).tiny)   # the smallest normal double, 2.2e-308


def underflowing_rows(rows: np.ndarray, values: np.ndarray, m: int) -> np.ndarray:
    """Rows (bool, shape (m,)) whose ``values`` (per entry, shape (k,), the row of each in
    ``rows``) are all zero or below the smallest normal double; a row with no entry, too.
    A NaN is not small: non-finite values are another rule's finding."""
    resolved = np.zeros(m, dtype=bool)
    values = np.asarray(values, dtype=float)
    resolved[np.asarray(rows)[~(np.abs(values) < TINY)]] = True
    return ~resolved


def derivative_floor(row_nominal: np.ndarray, step: np.ndarray, underflowing: np.ndarray, *,
                     ulps: float) -> np.ndarray:
    """The absolute floor of the comparison of ``d(unknown_i)/d(known_j)``, per entry.

    Parameters
    ----------
    row_nominal : ndarray, shape (k,)
        The nominal value of each entry's unknown (1 when it declares none), its units.
    step : ndarray, shape (k,)
        The finite-difference step of each entry's known, its units (0 or NaN: not perturbed).
    underflowing : ndarray of bool, shape (k,)
        Whether each entry's row is one of :func:`underflowing_rows`.
    ulps : float
        The noise of one function value, in units of eps times its size (the rule's option).

    Returns
    -------
    ndarray, shape (k,)
        In units of the unknown per unit of the known: ``TINY / h_j``, plus
        ``ulps * eps * nominal_i / h_j`` in underflowing rows; 0 where the known was not
        perturbed (no finite difference to compare with).
    """
    step = np.asarray(step, dtype=float)
    usable = np.isfinite(step) & (step > 0)
    h = np.where(usable, step, 1.0)
    resolution = np.where(underflowing, ulps * EPS * np.asarray(row_nominal, dtype=float), 0.0)
    return np.where(usable, (TINY + resolution) / h, 0.0)


def value_floor(nominal: np.ndarray, underflowing: np.ndarray, *, ulps: float) -> np.ndarray:
    """The absolute floor of the comparison of two values of an unknown of ``nominal``:
    ``TINY``, plus ``ulps * eps * nominal`` where its row underflows (shape of ``nominal``)."""
    return TINY + np.where(underflowing, ulps * EPS * np.asarray(nominal, dtype=float), 0.0)
