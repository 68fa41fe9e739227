"""IDA and CVODE drivers on pure-Python systems: accuracy, consistent start, our limits, and
failed evaluations. Fast (no binary); the FMU path is tests/simulate/test_fmu_simulation.py."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from conformance.numerics import settings as st
from conformance.numerics.consistent import consistent_start
from conformance.numerics.dae import integrate_dae
from conformance.numerics.limits import Budget, EvaluationFailed
from conformance.numerics.ode import integrate_ode
from tests.simkit import sim_settings
from tests.numerics.systems import (
    ROBERTSON_REFERENCE,
    VAN_DER_POL_IMPASSE,
    Decay,
    HelloWorld,
    RelayOde,
    Robertson,
    VanDerPol,
    discard_when,
    hello_start,
)

TIMES = tuple(ROBERTSON_REFERENCE)


def _errors(traj, rtol: float) -> np.ndarray:
    """|y - reference| in units of the requested tolerance rtol*|ref| + atol_i, per time."""
    out = []
    for t, ref in ROBERTSON_REFERENCE.items():
        row = traj.values[traj.times.index(t)]
        ref = np.array(ref)
        out.append(np.abs(row - ref) / (rtol * np.abs(ref) + np.array(traj.atol)))
    return np.array(out)


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_robertson_to_4e10_matches_the_reference(rtol):
    traj = integrate_dae(Robertson(), sim_settings(rtol=rtol, output_times=TIMES), t0=0.0,
                         y0=np.array([1.0, 0.0, 0.0]), stop=4e10)
    assert traj.ok, traj.message
    # IDA controls the local error; the global error is a small multiple of the tolerance
    assert _errors(traj, rtol).max() <= 2.0


def test_absolute_tolerances_follow_the_nominal_values():
    traj = integrate_dae(Robertson(), sim_settings(rtol=1e-6, atol_factor=0.5), t0=0.0,
                         y0=np.array([1.0, 0.0, 0.0]), stop=1.0)
    assert traj.atol == pytest.approx([0.5e-6, 0.5e-11, 0.5e-6])


def test_inconsistent_start_is_corrected_and_reported():
    system = HelloWorld()
    atol = np.full(3, 1e-6)
    y, info = consistent_start(system, 0.0, np.array([1.0, 0.0, 0.0]), atol, 1e-6)
    assert np.allclose(y, hello_start(), atol=1e-12)
    assert info["residual_before"]["max_abs"] == pytest.approx(2.0)
    assert info["residual_after"]["max_abs"] <= 1e-14
    assert info["converged"] and info["iterations"] >= 1
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=np.array([1.0, 0.0, 0.0]), stop=1.0)
    assert traj.ok and traj.init["residual_before"]["max_abs"] == pytest.approx(2.0)
    assert traj.values[-1, 0] == pytest.approx(np.exp(1.4), rel=1e-4)


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_van_der_pol_impasse_stops_with_the_time(rtol):
    traj = integrate_dae(VanDerPol(), sim_settings(rtol=rtol), t0=0.0,
                         y0=np.array([2.0, -2.0 / 3.0]), stop=2.0)
    assert traj.status == st.SINGULAR
    assert abs(traj.event["t"] - VAN_DER_POL_IMPASSE) < 1e-3
    # stopped by the watch inside the Jacobian (max_condition) or, having stalled, by the look
    # at where it stopped (stalled_condition): the evidence names the threshold that applied
    settings = sim_settings()
    watched = traj.message == "dg/dw became singular"
    assert traj.event["threshold"] == (settings.max_condition if watched
                                       else settings.stalled_condition)
    assert traj.event["involved"] == ["y2"]
    assert traj.wall_s < 5
    assert traj.t_end < VAN_DER_POL_IMPASSE


class _DiscardBelowZero(Robertson):
    """fmi3Discard where y2 < 0 (a sqrt(y2) in a real model): the solution stays positive, but
    steps that overshoot do not; IDA cuts them and goes on."""

    def evaluate(self, t, y):
        if y[1] < 0:
            raise EvaluationFailed("fmi3GetFloat64", "fmi3Discard", recoverable=True)
        return super().evaluate(t, y)


def test_discard_avoided_by_smaller_steps_is_recovered():
    traj = integrate_dae(_DiscardBelowZero(), sim_settings(rtol=1e-4), t0=0.0,
                         y0=np.array([1.0, 0.0, 0.0]), stop=4e10)
    assert traj.ok and traj.recovered > 0


def test_discard_that_smaller_steps_do_not_get_past_is_an_fmu_failure():
    system = HelloWorld(fail=discard_when(lambda t, y: t > 0.5))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.FMU_FAILED
    assert traj.event["status"] == "fmi3Discard" and 0.49 < traj.t_end <= 0.5
    assert traj.message.startswith("fmi3GetContinuousStateDerivatives returned fmi3Discard at "
                                   "the points IDA tried near t = 0.5")
    assert traj.event["last_step_t"] == traj.t_end


def test_values_that_are_not_finite_are_blamed_as_such():
    system = HelloWorld(extra=lambda t, y: np.array([np.nan if t > 0.5 else 0.0, 0.0, 0.0]))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.FMU_FAILED
    assert (traj.event["call"], traj.event["status"]) == ("non-finite values", "NaN or Inf")


def test_fmi3_error_ends_the_run_at_once():
    system = HelloWorld(fail=discard_when(lambda t, y: t > 0.5, recoverable=False))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.FMU_FAILED and traj.event["status"] == "fmi3Error"
    assert traj.times[-1] <= 0.5


def _error_with_log(t, y):
    if t > 0.5:
        raise EvaluationFailed("fmi3GetContinuousStateDerivatives", "fmi3Error",
                               [f"line {k}" for k in range(7)], recoverable=False)


def test_fmi3_error_keeps_the_first_five_lines_of_the_log():
    traj = integrate_dae(HelloWorld(fail=_error_with_log), sim_settings(), t0=0.0,
                         y0=hello_start(), stop=1.0)
    assert traj.status == st.FMU_FAILED
    assert traj.message == "fmi3GetContinuousStateDerivatives returned fmi3Error"
    assert traj.event["t"] > 0.5 and traj.event["last_step_t"] == traj.t_end
    assert {k: v for k, v in traj.event.items() if k not in ("t", "last_step_t")} == {
        "call": "fmi3GetContinuousStateDerivatives", "status": "fmi3Error",
        "log": ["line 0", "line 1", "line 2", "line 3", "line 4"]}


class _PartialsDiscarded(HelloWorld):
    """Every other Jacobian IDA asks for cannot be evaluated (fmi3Discard) or is not finite:
    the last good one stands in (the first three calls are the initialisation's)."""

    def __init__(self, failure: str):
        super().__init__()
        self.failure, self.partial_calls = failure, 0

    def partials(self, t, y):
        self.partial_calls += 1
        if self.partial_calls > 3 and self.partial_calls % 2 == 0:
            if self.failure == "nan":
                return np.full((3, 3), np.nan)
            raise EvaluationFailed("fmi3GetDirectionalDerivative", "fmi3Discard",
                                   recoverable=True)
        return super().partials(t, y)


@pytest.mark.parametrize("failure", ["discard", "nan"])
def test_a_jacobian_that_fails_is_replaced_by_the_last_good_one(failure):
    system = _PartialsDiscarded(failure)
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.ok, traj.message
    assert traj.values[-1, 0] == pytest.approx(np.exp(1.4), rel=1e-4)
    assert system.partial_calls >= 5 and traj.recovered == 0


class _SquareResidual:
    """x' = -x, 0 = w^2 from w = 0: consistent, but dg/dw = 0 and g depends on nothing."""

    nx, nw = 1, 1
    names = ("x", "w")
    nominal = np.ones(2)
    jacobian_source = "exact"
    fmi_calls = 0

    def evaluate(self, t, y):
        return np.array([-y[0], y[1] ** 2])

    def partials(self, t, y):
        return np.array([[-1.0, 0.0], [0.0, 2 * y[1]]])


def test_an_infinite_condition_at_the_start_is_written_as_text():
    traj = integrate_dae(_SquareResidual(), sim_settings(), t0=0.0, y0=np.array([1.0, 0.0]),
                         stop=1.0)
    assert traj.status == st.SINGULAR and traj.init["condition"] == "inf"
    assert traj.event["condition"] == "inf" and traj.event["t"] == 0.0


def test_a_jump_in_g_stalls_the_solver_which_is_a_solver_failure():
    system = HelloWorld(extra=lambda t, y: np.array([0.0, 1.0 if t > 0.5 else 0.0, 0.0]))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.SOLVER and traj.event["limit"] == "stall_steps"
    assert traj.t_end == pytest.approx(0.5)


def test_step_budget():
    fast = HelloWorld(extra=lambda t, y: np.array([1e5 * np.cos(1e5 * t), 0.0, 0.0]))
    traj = integrate_dae(fast, sim_settings(max_steps=500), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.BUDGET and traj.steps == 500 and traj.event["limit"] == "max_steps"
    assert traj.event["last_step_t"] == traj.t_end > 0.0
    # dg/dw is constant: its condition is the same at every point, first seen at the start
    assert traj.max_condition_t == 0.0 and traj.max_condition > 1.0


def test_step_budget_in_ode_mode():
    fast = Decay(fail=lambda t, x: None)
    fast.evaluate = lambda t, x: -x + 1e5 * np.cos(1e5 * t)
    traj = integrate_ode(fast, sim_settings(max_steps=300), t0=0.0, x0=np.array([1.0]),
                         stop=1.0)
    assert traj.status == st.BUDGET and traj.steps == 300
    assert traj.event["last_step_t"] == traj.t_end > 0.0 and None not in traj.event


def test_wall_clock_safety_net_is_checked_inside_the_callbacks_and_is_no_budget():
    # the safety net ends the run as "time-budget", never as the step budget's "budget": no
    # rule may judge a run the machine's speed ended
    slow = HelloWorld()
    traj = integrate_dae(slow, sim_settings(wall_seconds=0.0), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.TIME_BUDGET and traj.event["limit"] == "wall_seconds"
    assert slow.calls <= 3  # the initialisation's evaluations, then the first callback stops


def test_outputs_land_on_the_requested_times_and_the_run_counts_its_work():
    settings = sim_settings(output_times=(0.1, 0.25, 1.0))
    traj = integrate_dae(HelloWorld(), settings, t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.times == [0.0, 0.1, 0.25, 1.0]
    assert traj.values[:, 0] == pytest.approx(np.exp(1.4 * np.array(traj.times)), rel=1e-4)
    assert traj.steps > 0 and traj.function_calls > traj.steps and traj.jacobian_calls > 0
    assert traj.kinds == ["state", "algebraic", "algebraic"]


def test_ode_mode_with_cvode():
    traj = integrate_ode(Decay(), sim_settings(rtol=1e-8), t0=0.0, x0=np.array([1.0]), stop=2.0)
    assert traj.ok and traj.jacobian == "exact"
    assert traj.values[:, 0] == pytest.approx(np.exp(-np.array(traj.times)), rel=1e-6)
    assert traj.names == ["x", "w"] and traj.values[:, 1] == pytest.approx(2 * traj.values[:, 0])


def test_ode_mode_wall_clock_safety_net_stops_in_the_right_hand_side_at_its_time():
    traj = integrate_ode(Decay(), sim_settings(wall_seconds=0.0), t0=0.0, x0=np.array([1.0]),
                         stop=2.0)
    assert traj.status == st.TIME_BUDGET
    assert traj.event == {"t": 0.0, "limit": "wall_seconds", "value": 0.0}


class _LateInTheEventsCallback(Budget):
    """A wall clock that has run out whenever the events callback asks it, and only then: the
    safety net must end the run there, at the callback's time."""

    def __init__(self, **limits):
        super().__init__(clock=self._clock, **limits)

    def _clock(self) -> float:
        frame = sys._getframe(1)
        while frame is not None:   # asked from inside the events callback (at any depth)?
            if frame.f_code.co_name == "events":
                return 1e9
            frame = frame.f_back
        return 0.0


def test_ode_mode_wall_clock_safety_net_is_checked_in_the_events_callback(monkeypatch):
    from conformance.numerics import ode

    monkeypatch.setattr(ode, "Budget", _LateInTheEventsCallback)
    system = RelayOde()
    traj = integrate_ode(system, sim_settings(), t0=0.0, x0=np.array([0.0]), stop=2.0,
                         start_update=system.start_update())
    assert traj.status == st.TIME_BUDGET
    assert traj.event["limit"] == "wall_seconds" and traj.event["t"] == 0.0


class _NoAlgebraicValues(Decay):
    def algebraic_values(self, t, x):
        raise EvaluationFailed("fmi3GetFloat64", "fmi3Error", recoverable=False)


def test_ode_mode_failure_at_the_initial_point_is_an_fmu_failure_there():
    traj = integrate_ode(_NoAlgebraicValues(), sim_settings(), t0=0.5, x0=np.array([1.0]),
                         stop=2.0)
    assert traj.status == st.FMU_FAILED and traj.message == "fmi3GetFloat64 returned fmi3Error"
    assert traj.event == {"t": 0.5, "call": "fmi3GetFloat64", "status": "fmi3Error"}


def test_ode_mode_discard_not_recovered():
    system = Decay(fail=discard_when(lambda t, x: t > 1.0))
    traj = integrate_ode(system, sim_settings(), t0=0.0, x0=np.array([1.0]), stop=2.0)
    assert traj.status == st.FMU_FAILED and traj.t_end <= 1.0


def test_the_initial_slope_keeps_the_constraint_differentiated():
    """IDA starts from y'(t0): x' = f, and w' from d/dt g = g_x x' + g_w w' = 0. The reduced Van
    der Pol oscillator at y1 = 2 (y2 = -2/3 solves g): x' = y2 = -2/3, and w' = -10/27."""
    from conformance.numerics.dae import _initial_slope
    system = VanDerPol()
    y = np.array([2.0, -2.0 / 3.0])
    yp = _initial_slope(system, 0.0, y)
    assert yp == pytest.approx([-2.0 / 3.0, -10.0 / 27.0], rel=1e-12)
    jac = system.partials(0.0, y)
    assert jac[1] @ yp == pytest.approx(0.0, abs=1e-12)


def test_an_initial_slope_the_system_cannot_give_is_zero():
    """A derivative that is not finite at t0 starts IDA from a slope of zero there."""
    from conformance.numerics.dae import _initial_slope

    class NotFinite(VanDerPol):
        def evaluate(self, t, y):
            return np.array([np.nan, super().evaluate(t, y)[1]])

    yp = _initial_slope(NotFinite(), 0.0, np.array([2.0, -2.0 / 3.0]))
    assert list(yp) == [0.0, 0.0]
