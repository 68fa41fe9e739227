"""Finite differences for the derivative probes, with an estimate of their own error.

The probes compare the partial derivatives an FMU reports (fmi3GetDirectionalDerivative,
fmi3GetAdjointDerivative) and the sparsity it declares (``dependencies``) with finite differences
of the function itself. A finite difference is only evidence when its error is known, so every
difference here comes with two numbers, both in the units of the function value:

* the **truncation** error, estimated from the same difference taken with two (or three) step
  sizes, as in Richardson extrapolation: for a central difference ``D(h) = J d + c h^2 + ...`` so
  ``|D(2h) - D(h)| / 3`` estimates the error of ``D(h)``;
* a **rounding factor** ``c``: the rounding error of the difference is at most ``c * rho`` where
  ``rho`` is the noise of one function value (see :func:`noise_level`).

Helpers return measured values and errors; the rules compare them with the tolerances of the
catalogue. Step sizes follow the classical analysis of the balance between truncation and
rounding error (Nocedal & Wright, *Numerical Optimization*, 2nd ed., 2006, §8.1: ``h ~ eps^(1/2)``
for forward and ``h ~ eps^(1/3)`` for central differences; Press et al., *Numerical Recipes*, 3rd
ed., 2007, §5.7: ``h ~ eps^(1/5)`` for a fourth-order, extrapolated difference), scaled per
variable by the larger of its magnitude and its nominal value, the FMI notion of "typical size".

Everything is float64. ``m`` is the number of unknowns (rows), ``n`` the number of knowns.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable

import numpy as np

log = logging.getLogger(__name__)

EPS = float(np.finfo(np.float64).eps)
METHODS = ("forward", "central", "extrapolated")

# Relative step per method, see the module docstring for the references.
_RELATIVE_STEP = {"forward": EPS ** 0.5, "central": EPS ** (1.0 / 3.0),
                  "extrapolated": EPS ** 0.2}
# Multiples of the step each method evaluates (both signs for central and extrapolated).
_LEVELS = {"forward": (1, 2), "central": (1, 2), "extrapolated": (1, 2, 4)}
# Function evaluations per direction (the base value of a forward difference is shared).
CALLS_PER_DIRECTION = {"forward": 2, "central": 4, "extrapolated": 6}
# Default noise of one function value, in units of eps times the magnitude of its terms.
DEFAULT_ULPS = 100.0


@dataclass(frozen=True)
class Difference:
    """A finite-difference estimate of ``J @ d`` along one direction ``d``.

    Attributes
    ----------
    value : ndarray, shape (m,)
        The estimate of ``J @ d``, in the units of the function values.
    truncation : ndarray, shape (m,)
        Estimated truncation error of ``value`` (non-negative, same units).
    rounding : float
        Factor ``c``: the rounding error of ``value`` is at most ``c * rho`` where ``rho`` is the
        noise of one function value (:func:`noise_level`).
    exact_zero : ndarray of bool, shape (m,)
        True where every function value compared was bitwise identical: the function did not
        change at all along ``d`` (the strongest evidence of a structural zero).
    calls : int
        Function evaluations spent.
    """

    value: np.ndarray
    truncation: np.ndarray
    rounding: float
    exact_zero: np.ndarray
    calls: int

    def error(self, noise: np.ndarray | float) -> np.ndarray:
        """Bound on the error of ``value``: truncation plus rounding, shape (m,)."""
        return self.truncation + self.rounding * np.asarray(noise, dtype=float)


def relative_step(method: str) -> float:
    """The relative step of ``method`` (dimensionless), see the module docstring."""
    try:
        return _RELATIVE_STEP[method]
    except KeyError:
        raise ValueError(f"unknown finite-difference method {method!r} (use {METHODS})") from None


def step_sizes(x: np.ndarray, nominal: np.ndarray, *, method: str = "central",
               lower: np.ndarray | None = None, upper: np.ndarray | None = None) -> np.ndarray:
    """Step per known: the relative step times the larger of ``|x|`` and ``|nominal|``.

    Parameters
    ----------
    x : ndarray, shape (n,)
        The point, in the units of each known.
    nominal : ndarray, shape (n,)
        The nominal value of each known (FMI ``nominal``, 1 when not declared), same units.
    method : str
        One of :data:`METHODS`.
    lower, upper : ndarray, shape (n,), optional
        Bounds (``min``/``max``, or the start time for time); a step that would leave them at
        its largest multiple is shrunk to fit, by at most a factor of 1000.

    Returns
    -------
    ndarray, shape (n,)
        Steps, in the units of each known, rounded so that ``x + h`` and ``x`` differ by
        exactly ``h`` in floating point; 0 where a bound leaves no room: that known cannot be
        perturbed both ways at this point.
    """
    x = np.asarray(x, dtype=float)
    scale = np.maximum(np.abs(x), np.abs(np.asarray(nominal, dtype=float)))
    scale = np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)
    h = relative_step(method) * scale
    h = _fit_bounds(x, h, _LEVELS[method][-1], lower, upper)
    return _representable(x, h)


def _fit_bounds(x: np.ndarray, h: np.ndarray, level: int, lower: np.ndarray | None,
                upper: np.ndarray | None) -> np.ndarray:
    """Shrink steps whose largest multiple ``level * h`` would cross a bound."""
    room = np.full_like(h, np.inf)
    if upper is not None:
        room = np.minimum(room, np.asarray(upper, dtype=float) - x)
    if lower is not None:
        room = np.minimum(room, x - np.asarray(lower, dtype=float))
    room = np.where(np.isnan(room), np.inf, room)
    fits = room >= level * h
    usable = room / level >= 1e-3 * h
    return np.where(fits, h, np.where(usable, room / level, 0.0))


def _representable(x: np.ndarray, h: np.ndarray) -> np.ndarray:
    """``(x + h) - x``: the step the function really sees (Numerical Recipes §5.7)."""
    exact = (x + h) - x
    return np.where((exact > 0) | (h == 0), exact, h)


def difference(fun: Callable[[np.ndarray], np.ndarray], direction: np.ndarray, *,
               method: str = "central", f0: np.ndarray | None = None) -> Difference:
    """Estimate ``J @ direction`` by finite differences, with its error.

    Parameters
    ----------
    fun : callable ``fun(delta) -> f``
        The function at the point shifted by ``delta`` (shape (n,), units of the knowns);
        returns the unknowns, shape (m,).
    direction : ndarray, shape (n,)
        The step ``d`` itself (already scaled: it is what the function is shifted by).
    method : str
        ``"forward"`` (``f(d) - f(0)``; error from ``2d``), ``"central"``
        (``(f(d) - f(-d)) / 2``; error from ``2d``) or ``"extrapolated"`` (Richardson on the
        central differences at ``d`` and ``2d``; error from ``4d``).
    f0 : ndarray, shape (m,), optional
        ``fun(0)``, when already known (saves one call of a forward difference).

    Returns
    -------
    Difference
    """
    d = np.asarray(direction, dtype=float)
    if method == "forward":
        return _forward(fun, d, f0)
    if method == "central":
        return _central(fun, d)
    if method == "extrapolated":
        return _extrapolated(fun, d)
    raise ValueError(f"unknown finite-difference method {method!r} (use {METHODS})")


def _forward(fun, d: np.ndarray, f0: np.ndarray | None) -> Difference:
    calls = 2
    if f0 is None:
        f0, calls = np.asarray(fun(np.zeros_like(d)), dtype=float), 3
    f1 = np.asarray(fun(d), dtype=float)
    f2 = np.asarray(fun(2 * d), dtype=float)
    d1, d2 = f1 - f0, (f2 - f0) / 2
    # D(h) = Jd + a, D(2h) = Jd + 2a: the difference is the truncation error of D(h).
    return Difference(d1, np.abs(d2 - d1), 2.0, (f1 == f0) & (f2 == f0), calls)


def _central_pair(fun, d: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(f(kd) - f(-kd)) / (2k)`` and whether the two values were bitwise equal."""
    plus = np.asarray(fun(k * d), dtype=float)
    minus = np.asarray(fun(-k * d), dtype=float)
    return (plus - minus) / (2 * k), plus == minus


def _central(fun, d: np.ndarray) -> Difference:
    d1, z1 = _central_pair(fun, d, 1)
    d2, z2 = _central_pair(fun, d, 2)
    # D(h) = Jd + b, D(2h) = Jd + 4b: |D(2h) - D(h)| / 3 is the truncation error of D(h).
    return Difference(d1, np.abs(d2 - d1) / 3, 1.0, z1 & z2, 4)


def _extrapolated(fun, d: np.ndarray) -> Difference:
    d1, z1 = _central_pair(fun, d, 1)
    d2, z2 = _central_pair(fun, d, 2)
    d4, z4 = _central_pair(fun, d, 4)
    r1, r2 = (4 * d1 - d2) / 3, (4 * d2 - d4) / 3
    # R(h) = Jd + c, R(2h) = Jd + 16c: |R(2h) - R(h)| / 15 is the truncation error of R(h);
    # rounding of R(h): (4 rho + rho / 2) / 3.
    return Difference(r1, np.abs(r2 - r1) / 15, 1.5, z1 & z2 & z4, 6)


def noise_level(f0: np.ndarray, terms: np.ndarray, *, ulps: float = DEFAULT_ULPS) -> np.ndarray:
    """Noise of one function value: ``ulps * eps * (|f| + terms)``, shape (m,).

    ``terms`` is ``sum_j |x_j * J_ij|``, the size of the terms the value is computed from
    (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., 2002, §1.6: relative
    perturbations of the inputs of size ``eps`` change ``f`` by up to ``eps * sum_j |x_j f_j|``).
    It catches cancellation, as in ``1e4*y2*y3 - 3e7*y2^2``, where ``|f|`` alone would not.
    """
    return ulps * EPS * (np.abs(np.asarray(f0, dtype=float)) + np.asarray(terms, dtype=float))
