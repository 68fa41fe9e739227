"""Pure-Python DAE and ODE systems with exact derivatives, for testing the integrators without
a binary: Robertson, the reduced Van der Pol oscillator, HelloWorldDAE and variants that fail.

Each follows the protocols of conformance/simulate/dae.py (``DaeSystem``) and ode.py
(``OdeSystem``): ``y = [x; w]``, ``evaluate`` gives ``[f; g]``, ``partials`` d[f; g]/d[x; w].
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from conformance.numerics.limits import EvaluationFailed

# Reference solution of Robertson (tight-tolerance solutions, consistent with the Hairer test set)
ROBERTSON_REFERENCE = {
    0.4: (9.851721139e-1, 3.386395379e-5, 1.479402219e-2),
    40.0: (7.158270687e-1, 9.185534765e-6, 2.841637457e-1),
    4e5: (4.938274521e-3, 1.984994088e-8, 9.950617056e-1),
    4e10: (5.208345181e-8, 2.083338179e-13, 9.999999479e-1),
}
VAN_DER_POL_IMPASSE = 1.5 - np.log(2.0)   # t* where dg/dw = 1 - y1^2 vanishes, from y1 = 2


class Robertson:
    """der(y1), der(y2) kinetics; 0 = y1 + y2 + y3 - 1 (y3 algebraic)."""

    nx, nw = 2, 1
    names = ("y1", "y2", "y3")
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, nominal: tuple[float, float, float] = (1.0, 1e-5, 1.0)):
        self.nominal = np.array(nominal)

    def evaluate(self, t, y):
        y1, y2, y3 = y
        return np.array([-0.04 * y1 + 1e4 * y2 * y3, 0.04 * y1 - 1e4 * y2 * y3 - 3e7 * y2**2,
                         y1 + y2 + y3 - 1])

    def partials(self, t, y):
        _, y2, y3 = y
        return np.array([[-0.04, 1e4 * y3, 1e4 * y2],
                         [0.04, -1e4 * y3 - 6e7 * y2, -1e4 * y2],
                         [1.0, 1.0, 1.0]])


class VanDerPol:
    """der(y1) = y2; 0 = (1 - y1^2) y2 - y1: an impasse point at t* from y1 = 2."""

    nx, nw = 1, 1
    names = ("y1", "y2")
    nominal = np.ones(2)
    jacobian_source = "exact"
    fmi_calls = 0

    def evaluate(self, t, y):
        y1, y2 = y
        return np.array([y2, (1 - y1**2) * y2 - y1])

    def partials(self, t, y):
        y1, y2 = y
        return np.array([[0.0, 1.0], [-2 * y1 * y2 - 1, 1 - y1**2]])


class HelloWorld:
    """der(x) = y; 0 = y + 2z - x; 0 = y - 3z - 2x, with an optional extra on [f; g] and a
    hook that may raise (the failure a variant injects)."""

    nx, nw = 1, 2
    names = ("x", "y", "z")
    nominal = np.ones(3)
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, extra: Callable[[float, np.ndarray], np.ndarray] | None = None,
                 fail: Callable[[float, np.ndarray], None] | None = None):
        self.extra, self.fail = extra, fail
        self.calls = 0

    def evaluate(self, t, y):
        self.calls += 1
        if self.fail is not None:
            self.fail(t, y)
        x, w1, w2 = y
        out = np.array([w1, w1 + 2 * w2 - x, w1 - 3 * w2 - 2 * x])
        return out + self.extra(t, y) if self.extra is not None else out

    def partials(self, t, y):
        return np.array([[0.0, 1.0, 0.0], [-1.0, 1.0, 2.0], [-2.0, 1.0, -3.0]])


def hello_start(x: float = 1.0) -> np.ndarray:
    return np.array([x, 1.4 * x, -0.2 * x])


def discard_when(condition: Callable[[float, np.ndarray], bool], *, recoverable: bool = True):
    def fail(t, y):
        if condition(t, y):
            raise EvaluationFailed("fmi3GetContinuousStateDerivatives",
                                   "fmi3Discard" if recoverable else "fmi3Error",
                                   recoverable=recoverable)
    return fail


class Decay:
    """x' = -x as an ODE, with the 'algebraic variable' w = 2x, and a hook that may fail."""

    nx = 1
    names = ("x",)
    algebraic_names = ("w",)
    nominal = np.ones(1)
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, fail: Callable[[float, np.ndarray], None] | None = None):
        self.fail = fail

    def evaluate(self, t, x):
        if self.fail is not None:
            self.fail(t, x)
        return -x

    def partials(self, t, x):
        return -np.eye(1)

    def algebraic_values(self, t, x):
        return 2 * x
