"""Finite differences: step sizes, the order of each method, and that the error estimate bounds
the real error (the promise the probes rely on to report only clear mismatches)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conformance.numerics import numdiff
from conformance.numerics.numdiff import EPS


def along(fun, x0):
    """fun(x) as a function of the shift delta."""
    return lambda delta: np.atleast_1d(fun(x0 + delta))


def test_relative_steps_follow_the_references():
    assert numdiff.relative_step("forward") == pytest.approx(EPS ** 0.5)
    assert numdiff.relative_step("central") == pytest.approx(EPS ** (1 / 3))
    assert numdiff.relative_step("extrapolated") == pytest.approx(EPS ** 0.2)
    with pytest.raises(ValueError):
        numdiff.relative_step("backward")


def test_step_scales_with_the_larger_of_value_and_nominal():
    x = np.array([0.0, 0.0, 1e3, -2.0])
    nominal = np.array([1.0, 1e-5, 1.0, 1.0])
    h = numdiff.step_sizes(x, nominal, method="central")
    rel = numdiff.relative_step("central")
    np.testing.assert_allclose(h, rel * np.array([1.0, 1e-5, 1e3, 2.0]), rtol=1e-9)
    assert np.all((x + h) - x == h), "steps are exactly representable"


def test_step_shrinks_to_fit_the_bounds():
    x = np.array([0.5, 0.5])
    h = numdiff.step_sizes(x, np.ones(2), method="central", upper=np.array([0.5 + 1e-7, np.inf]))
    assert 2 * h[0] <= 1e-7 * (1 + 1e-9)
    assert h[1] == pytest.approx(numdiff.relative_step("central") * 1.0, rel=1e-9)


def test_central_is_exact_for_a_quadratic():
    fun = along(lambda x: 3 * x**2 - 2 * x + 1, np.array([0.7]))
    d = numdiff.difference(fun, np.array([1e-3]), method="central")
    assert d.value[0] == pytest.approx((6 * 0.7 - 2) * 1e-3, rel=1e-10)
    assert d.truncation[0] < 1e-15
    assert d.calls == 4 and d.rounding == 1.0


def test_exact_zero_when_the_function_does_not_move():
    fun = lambda delta: np.array([np.sin(1.0 + delta[0]), 2.0])  # noqa: E731
    d = numdiff.difference(fun, np.array([1e-4, 0.0]), method="central")
    assert d.exact_zero.tolist() == [False, True]
    d = numdiff.difference(lambda delta: np.array([np.cos(delta[1])]), np.array([1e-4, 0.0]),
                           method="forward")
    assert d.exact_zero.tolist() == [True] and d.calls == 3


@pytest.mark.parametrize("method,order", [("forward", 1), ("central", 2), ("extrapolated", 4)])
def test_truncation_error_has_the_order_of_the_method(method, order):
    x0 = np.array([0.3])
    exact = np.exp(0.3)
    errors = []
    for h in (1e-2, 5e-3):
        d = numdiff.difference(along(np.exp, x0), np.array([h]), method=method)
        errors.append(abs(d.value[0] / h - exact))
    assert errors[0] / errors[1] == pytest.approx(2 ** order, rel=0.15)


@pytest.mark.parametrize("method", numdiff.METHODS)
def test_estimate_bounds_the_error_at_the_chosen_step(method):
    for x in (0.1, 1.0, 7.0, -3.0):
        x0 = np.array([x])
        h = numdiff.step_sizes(x0, np.ones(1), method=method)
        fun = along(lambda v: np.exp(np.sin(v)) * v, x0)
        d = numdiff.difference(fun, h, method=method)
        exact = (np.cos(x) * x + 1) * np.exp(np.sin(x))
        f0 = fun(np.zeros(1))
        noise = numdiff.noise_level(f0, np.abs(x * exact))
        err = abs(d.value[0] / h[0] - exact)
        assert err <= 10 * d.error(noise)[0] / h[0] + 1e-15, (method, x, err)


@settings(max_examples=200, deadline=None)
@given(a=st.floats(-5, 5), b=st.floats(-3, 3), c=st.floats(0.1, 3), x=st.floats(-2, 2),
       method=st.sampled_from(numdiff.METHODS))
def test_estimate_bounds_the_error_for_smooth_functions(a, b, c, x, method):
    """The bound (truncation estimate plus rounding for 100 ulps), times the rules' margin of
    10, is never below the real error of a smooth function."""
    def f(v):
        return a * np.sin(c * v + b) + np.exp(0.5 * v) * c

    def df(v):
        return a * c * np.cos(c * v + b) + 0.5 * np.exp(0.5 * v) * c

    x0 = np.array([x])
    h = numdiff.step_sizes(x0, np.ones(1), method=method)
    d = numdiff.difference(along(f, x0), h, method=method)
    terms = np.abs(x * df(x)) + abs(a) + np.exp(0.5 * x) * c
    bound = 10 * d.error(numdiff.noise_level(np.atleast_1d(f(x)), np.atleast_1d(terms)))[0]
    assert abs(d.value[0] - df(x) * h[0]) <= bound + 1e-300


def test_stiff_scales_do_not_fool_the_estimate():
    """Robertson's der(y2) near y2 = 1e-5 (nominal 1e-5): terms of 1e4 and 3e7 cancel."""
    y1, y3 = 0.9, 0.1

    def f(y2):
        return 0.04 * y1 - 1e4 * y2 * y3 - 3e7 * y2**2

    x0 = np.array([2e-5])
    h = numdiff.step_sizes(x0, np.array([1e-5]), method="central")
    d = numdiff.difference(along(f, x0), h, method="central")
    exact = -1e4 * y3 - 6e7 * 2e-5
    terms = 0.04 * y1 + 1e4 * 2e-5 * y3 + 3e7 * 4e-10
    bound = d.error(numdiff.noise_level(np.atleast_1d(f(2e-5)), np.atleast_1d(terms)))[0]
    assert abs(d.value[0] - exact * h[0]) <= 10 * bound
    assert abs(d.value[0] / h[0] - exact) < 1e-6 * abs(exact)


def test_noise_level():
    out = numdiff.noise_level(np.array([1.0, -2.0]), np.array([0.0, 3.0]), ulps=10)
    np.testing.assert_allclose(out, 10 * EPS * np.array([1.0, 5.0]))


@pytest.mark.parametrize("method, value, truncation, calls", [
    # f(s) = s^5 along d = 1: D(k) = (f(k) - f(-k)) / 2k = k^4, so D(1) = 1, D(2) = 16; the
    # error estimate |D(2) - D(1)| / 3 = 5 bounds the true error 1 of D(1)
    ("central", 1.0, 5.0, 4),
    # R(k) = (4 D(k) - D(2k)) / 3: R(1) = -4, R(2) = -64, the estimate |R(2) - R(1)| / 15 = 4
    # is the true error of R(1) exactly (R(k) = f'(0) + c k^4 for a quintic)
    ("extrapolated", -4.0, 4.0, 6),
])
def test_the_error_estimate_of_each_method_on_a_quintic(method, value, truncation, calls):
    """The estimates and their truncation bounds, by hand: f'(0) = 0, so the value is its own
    error; the extrapolated one's estimate is exact (Richardson's c k^4 term)."""
    fun = {"central": numdiff._central, "extrapolated": numdiff._extrapolated}[method]
    found = fun(lambda step: np.asarray(step, dtype=float) ** 5, np.array([1.0]))
    assert found.value == pytest.approx([value], rel=1e-12)
    assert found.truncation == pytest.approx([truncation], rel=1e-12)
    assert found.calls == calls
