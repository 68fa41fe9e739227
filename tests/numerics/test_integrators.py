"""IDA and CVODE drivers on pure-Python systems: accuracy, consistent start, our limits, and
failed evaluations. Fast (no binary); the FMU path is tests/simulate/test_fmu_simulation.py."""
from __future__ import annotations

import numpy as np
import pytest

from conformance.numerics import settings as st
from conformance.numerics.consistent import consistent_start
from conformance.numerics.dae import integrate_dae
from conformance.numerics.limits import EvaluationFailed
from conformance.numerics.ode import integrate_ode
from tests.simkit import sim_settings
from tests.numerics.systems import (
    ROBERTSON_REFERENCE,
    VAN_DER_POL_IMPASSE,
    Decay,
    HelloWorld,
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


def test_fmi3_error_ends_the_run_at_once():
    system = HelloWorld(fail=discard_when(lambda t, y: t > 0.5, recoverable=False))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.FMU_FAILED and traj.event["status"] == "fmi3Error"
    assert traj.times[-1] <= 0.5


def test_a_jump_in_g_stalls_the_solver_which_is_a_solver_failure():
    system = HelloWorld(extra=lambda t, y: np.array([0.0, 1.0 if t > 0.5 else 0.0, 0.0]))
    traj = integrate_dae(system, sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.SOLVER and traj.event["limit"] == "stall_steps"
    assert traj.t_end == pytest.approx(0.5)


def test_step_budget():
    fast = HelloWorld(extra=lambda t, y: np.array([1e5 * np.cos(1e5 * t), 0.0, 0.0]))
    traj = integrate_dae(fast, sim_settings(max_steps=500), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.status == st.BUDGET and traj.steps == 500 and traj.event["limit"] == "max_steps"


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
    assert traj.ok
    assert traj.values[:, 0] == pytest.approx(np.exp(-np.array(traj.times)), rel=1e-6)
    assert traj.names == ["x", "w"] and traj.values[:, 1] == pytest.approx(2 * traj.values[:, 0])


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
