"""Consistent initialisation on one-unknown systems worked by hand: the exact summary it reports,
the Newton damping measured in scaled residuals, and the Stop it raises (status, time, details)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from conformance.numerics import settings as st
from conformance.numerics.consistent import consistent_start
from conformance.numerics.limits import Stop


class _Square:
    """x' = 0, 0 = c (w^2 - 4): w = 2 from w > 0; dg/dw = 2 c w, so S = |2 c w| (nominal 1)."""

    nx, nw = 1, 1
    names = ("x", "w")
    nominal = np.ones(2)
    jacobian_source = "test"
    fmi_calls = 0

    def __init__(self, c: float = 1.0, *, nan: bool = False):
        self.c, self.nan = c, nan

    def evaluate(self, t, y):
        g = math.nan if self.nan else self.c * (y[1] ** 2 - 4.0)
        return np.array([0.0, g])

    def partials(self, t, y):
        return np.array([[0.0, 0.0], [0.0, 2.0 * self.c * y[1]]])


class _StatesOnly:
    nx, nw = 1, 0
    names = ("x",)
    nominal = np.ones(1)
    jacobian_source = "test"
    fmi_calls = 0

    def evaluate(self, t, y):
        return np.array([-y[0]])

    def partials(self, t, y):
        return np.array([[-1.0]])


def test_without_algebraic_variables_the_start_is_consistent_as_given():
    y, info = consistent_start(_StatesOnly(), 0.0, np.array([3.0]), np.ones(1), 1e-6)
    assert y.tolist() == [3.0]
    nothing = {"max_abs": 0.0, "max_scaled": 0.0}
    assert info == {"residual_before": nothing, "iterations": 0, "residual_after": nothing,
                    "converged": True}


def test_a_consistent_start_takes_no_newton_step():
    y, info = consistent_start(_Square(), 0.0, np.array([1.0, 2.0]), np.full(2, 1e-6), 1e-6)
    assert y.tolist() == [1.0, 2.0]
    zero = {"max_abs": 0.0, "max_scaled": 0.0}
    assert info == {"residual_before": zero, "iterations": 0, "residual_after": zero,
                    "converged": True}


def test_the_newton_damping_compares_residuals_divided_by_their_sensitivity():
    # from w = 1: g = -3, S = 2; the full step w = 2.5 leaves g = 2.25, 2.25/2 < 3/2: taken
    y, info = consistent_start(_Square(), 0.0, np.array([1.0, 1.0]), np.full(2, 1e-6), 1e-6)
    assert y[0] == 1.0 and y[1] == pytest.approx(2.0, abs=1e-12)
    assert info["converged"] is True
    assert info["residual_before"] == {"max_abs": 3.0, "max_scaled": 1.5}
    assert info["residual_after"]["max_abs"] <= 1e-12
    assert 2 <= info["iterations"] <= 8


def test_residuals_that_are_not_finite_at_the_start_stop_at_t0():
    with pytest.raises(Stop) as stop:
        consistent_start(_Square(nan=True), 0.25, np.array([1.0, 1.0]), np.full(2, 1e-6), 1e-6)
    assert stop.value.status == st.INIT and stop.value.t == 0.25
    assert stop.value.details == {"residual_before": {"max_abs": None, "max_scaled": None},
                                  "iterations": 0}


def test_a_singular_dg_dw_at_the_start_stops_as_singular():
    with pytest.raises(Stop) as stop:
        consistent_start(_Square(), 0.5, np.array([1.0, 0.0]), np.full(2, 1e-6), 1e-6)
    assert stop.value.status == st.SINGULAR and stop.value.t == 0.5
    assert stop.value.message == ("dg/dw is singular at the initial point: Newton cannot "
                                  "correct the algebraic variables")
    assert stop.value.details["iterations"] == 0
