"""Events in IDA and CVODE runs on pure-Python systems: state events root-found on the event
indicators, time events, the event iteration, the consistent restart in DAE mode, termination,
and the failures; each against an exact solution. The FMU path is tests/simulate/test_events.py."""
from __future__ import annotations

import numpy as np
import pytest

from conformance.numerics import settings as st
from conformance.numerics.dae import integrate_dae
from conformance.numerics.events import EventLog, event_update
from conformance.numerics.limits import EvaluationFailed, Stop
from conformance.numerics.ode import integrate_ode
from conformance.numerics.settings import Trajectory
from tests.numerics.systems import (
    BouncingBall,
    HelloWorld,
    Relay,
    RelayOde,
    Update,
    hello_start,
    relay_reference,
)
from tests.simkit import sim_settings

STOP = 2.0
X0 = np.array([0.0])
Y0 = np.array([0.0, 2.0 * Relay.UP])   # consistent: w = -k (x - c)


def _dae(system: Relay, **settings):
    return integrate_dae(system, sim_settings(**settings), t0=0.0, y0=Y0, stop=STOP,
                         start_update=system.start_update())


def _ode(system: RelayOde, **settings):
    return integrate_ode(system, sim_settings(**settings), t0=0.0, x0=X0, stop=STOP,
                         start_update=system.start_update())


def _gap(traj, boost_at=Relay.BOOST_AT) -> float:
    """Largest |x - exact| in units of the run's tolerance rtol |x| + atol."""
    x, _, _ = relay_reference(traj.times, stop=STOP, boost_at=boost_at)
    got = traj.values[:, 0]
    return float(np.max(np.abs(got - x) / (traj.rtol * np.abs(x) + traj.atol[0])))


@pytest.mark.parametrize("run", [_dae, _ode], ids=["dae", "ode"])
def test_relay_events_are_found_counted_and_timed_as_the_exact_solution(run):
    system = Relay() if run is _dae else RelayOde()
    traj = run(system, rtol=1e-8)
    assert traj.ok and traj.t_end == STOP, traj.message
    _, _, events = relay_reference([STOP], stop=STOP)
    assert (traj.state_events, traj.time_events) == (7, 1)
    assert traj.event_times == pytest.approx([t for t, _ in events], abs=1e-6)
    assert traj.event_updates == 2 * 8   # each change settles in a second update
    # IDA's and CVODE's global error is some tolerance units before the first event already;
    # an event shifted by dt moves x by dt times the jump in slope (up to 6 here)
    assert _gap(traj) <= 100.0


@pytest.mark.parametrize("run", [_dae, _ode], ids=["dae", "ode"])
def test_the_error_through_the_events_shrinks_with_the_tolerance(run):
    errors = []
    for rtol in (1e-5, 1e-8):
        traj = run(Relay() if run is _dae else RelayOde(), rtol=rtol)
        x, _, _ = relay_reference(traj.times, stop=STOP)
        errors.append(np.max(np.abs(traj.values[:, 0] - x)))
    assert errors[1] < errors[0] / 100


def test_without_the_event_handling_the_run_would_go_straight_through():
    """The reference itself: with events the relay oscillates; ignored, x would rise to 2."""
    traj = _dae(Relay(), rtol=1e-6)
    assert np.max(traj.values[:, 0]) <= Relay.HIGH + 1e-5
    assert np.min(traj.values[traj.times.index(1.0):, 0]) >= Relay.LOW - 1e-5


def test_dae_mode_restarts_from_consistent_algebraic_variables():
    """The residual jumps at every event (c changes): w is solved again, so 0 = g holds at
    every output time, the output at a time event included (the value after it)."""
    boost_at = 1.3     # in a rising phase: w jumps from -k (x - 2) to -k (x - 3)
    system = Relay(boost_at=boost_at)
    traj = integrate_dae(system, sim_settings(rtol=1e-8, output_times=(0.5, 1.0, 1.3, 2.0)),
                         t0=0.0, y0=Y0, stop=STOP, start_update=system.start_update())
    assert traj.ok and traj.times == [0.0, 0.5, 1.0, 1.3, 2.0]
    x, w, _ = relay_reference(traj.times, stop=STOP, boost_at=boost_at)
    assert traj.values[:, 0] == pytest.approx(x, abs=1e-6)
    assert traj.values[:, 1] == pytest.approx(w, abs=1e-5)
    assert traj.values[3, 1] == pytest.approx(-Relay.K * (x[3] - Relay.BOOSTED), abs=1e-5)
    # the residual after a switch, before w was solved again: w + k (x - c) with c moved by 3
    # at the first switch after the boost (from c = 3 to 0)
    assert traj.residual_jump == pytest.approx(Relay.K * Relay.BOOSTED, rel=1e-4)


def test_dae_and_ode_mode_agree_through_the_events():
    dae, ode = _dae(Relay(), rtol=1e-7), _ode(RelayOde(), rtol=1e-7)
    assert dae.times == ode.times and dae.event_times == pytest.approx(ode.event_times, abs=1e-6)
    assert dae.values == pytest.approx(ode.values, abs=1e-5)


def test_each_event_is_enter_updates_leave_in_that_order():
    system = Relay(boost_at=None)
    traj = _dae(system, rtol=1e-6)
    assert traj.state_events == 7 and traj.time_events == 0
    assert system.calls == ["enter", "update", "update", "leave"] * 7


def test_states_changed_at_an_event_are_read_back():
    ball = BouncingBall()
    traj = integrate_ode(ball, sim_settings(rtol=1e-8), t0=0.0, x0=np.array([1.0, 0.0]),
                         stop=1.2)
    assert traj.ok and traj.state_events == 3
    assert traj.event_times == pytest.approx(BouncingBall.bounces(1.2), abs=1e-6)
    assert ball.calls.count("read") == 3
    assert np.all(traj.values[:, 0] >= -1e-6)   # without the bounce h would fall to -6


def test_terminate_simulation_ends_the_run_without_error():
    system = Relay(terminate=1.0)
    traj = integrate_dae(system, sim_settings(output_times=(0.5, 1.0, 1.5)), t0=0.0, y0=Y0,
                         stop=STOP, start_update=system.start_update())
    assert traj.ok and traj.t_end == 1.0 and traj.terminated_at == 1.0
    assert traj.times == [0.0, 0.5, 1.0] and traj.event["terminate_simulation"]
    assert "leave" not in system.calls[-2:]   # the run ends in Event Mode


def test_terminate_in_the_initial_update_ends_the_run_at_the_start():
    system = RelayOde()
    start = Update(False, True, False, False, None)
    traj = integrate_ode(system, sim_settings(), t0=0.0, x0=X0, stop=STOP, start_update=start)
    assert traj.ok and traj.terminated_at == 0.0 and traj.times == [0.0] and traj.steps == 0


class _NeverSettles(RelayOde):
    def update_discrete_states(self):
        self.calls.append("update")
        return Update(True, False, False, False, None)


def test_an_event_iteration_that_never_settles_is_an_fmu_failure():
    traj = _ode(_NeverSettles(boost_at=None))
    assert traj.status == st.FMU_FAILED
    assert traj.event["call"] == "fmi3UpdateDiscreteStates"
    assert traj.t_end == pytest.approx(np.log(2) / 2, abs=1e-5)


class _IndicatorsFail(RelayOde):
    def __init__(self, value=None):
        super().__init__(boost_at=None)
        self.value = value

    def indicators(self, t, x):
        if t > 0.2:
            if self.value is None:
                raise EvaluationFailed("fmi3GetEventIndicators", "fmi3Discard",
                                       recoverable=True)
            return np.array([self.value])
        return super().indicators(t, x)


@pytest.mark.parametrize("value", [None, np.nan])
def test_indicators_that_fail_or_are_not_finite_end_the_run(value):
    traj = _ode(_IndicatorsFail(value))
    assert traj.status == st.FMU_FAILED and traj.event["call"] == "fmi3GetEventIndicators"
    assert 0.2 < traj.event["t"] < 0.5


class _NoConsistentRestart(Relay):
    """After the first event the residual is w^2 + 1: no real algebraic variable solves it."""

    def evaluate(self, t, y):
        out = super().evaluate(t, y)
        if not self.up:
            out[1] = y[1] ** 2 + 1.0
        return out

    def partials(self, t, y):
        jac = super().partials(t, y)
        if not self.up:
            jac[1] = [0.0, 2 * y[1]]
        return jac


def test_no_consistent_algebraic_variables_after_an_event_is_a_solver_failure():
    traj = _dae(_NoConsistentRestart(boost_at=None))
    assert traj.status == st.SOLVER and traj.event["after_event"] is True
    assert traj.event["converged"] is False and traj.state_events == 1
    assert traj.t_end == pytest.approx(np.log(2) / 2, abs=1e-5)


def test_a_run_without_indicators_reports_no_events():
    traj = integrate_dae(HelloWorld(), sim_settings(), t0=0.0, y0=hello_start(), stop=1.0)
    assert traj.ok and not traj.has_events and "events" not in traj.to_info()


def test_the_events_travel_through_the_report():
    traj = _dae(Relay(), rtol=1e-6)
    info = traj.to_info()
    assert info["events"]["state"] == 7 and info["events"]["time"] == 1
    back = Trajectory.from_info(info)
    assert (back.state_events, back.time_events, back.indicators) == (7, 1, 1)
    assert back.event_times == traj.event_times and back.terminated_at is None


def test_event_update_honours_a_next_time_only_ahead():
    system = RelayOde(boost_at=None)
    system.next_time = lambda t: t   # not ahead of the event: no time event
    outcome = event_update(system, 0.5, np.array([0.3]))
    assert outcome.next_time is None and not outcome.terminate


def test_a_failed_call_in_event_mode_stops_the_run_with_the_call():
    class Refuses(RelayOde):
        def enter_event_mode(self, t, y):
            raise EvaluationFailed("fmi3EnterEventMode", "fmi3Error", recoverable=False)

    with pytest.raises(Stop) as stop:
        event_update(Refuses(), 0.5, np.array([0.3]))
    assert stop.value.status == st.FMU_FAILED and stop.value.t == 0.5
    assert stop.value.message == "fmi3EnterEventMode returned fmi3Error at the event at t = 0.5"
    assert stop.value.details == {"call": "fmi3EnterEventMode", "status": "fmi3Error",
                                  "log": []}


@pytest.mark.parametrize("run", [_dae, _ode], ids=["dae", "ode"])
def test_a_time_event_only_the_initial_update_announced_is_handled_at_its_time(run):
    # the boost at t = 0.1 comes before the first state event (t = ln 2 / 2): only the update
    # at the end of initialisation schedules it
    system = (Relay if run is _dae else RelayOde)(boost_at=0.1)
    traj = run(system, rtol=1e-8)
    assert traj.ok, traj.message
    assert traj.time_events == 1 and traj.event_times[0] == pytest.approx(0.1, abs=1e-12)


class _FailsAfterTheEvent(Relay):
    """The residuals cannot be evaluated once the relay has switched down (fmi3Error)."""

    def evaluate(self, t, y):
        if not self.up:
            raise EvaluationFailed("fmi3GetContinuousStateDerivatives", "fmi3Error",
                                   ["first", "second"], recoverable=False)
        return super().evaluate(t, y)


def test_a_failed_call_while_restarting_after_an_event_is_an_fmu_failure_with_the_call():
    traj = _dae(_FailsAfterTheEvent(boost_at=None))
    first_event = np.log(2) / 2
    assert traj.status == st.FMU_FAILED and traj.state_events == 1
    assert traj.event["t"] == pytest.approx(first_event, abs=1e-6)
    assert {k: v for k, v in traj.event.items() if k not in ("t", "last_step_t")} == {
        "call": "fmi3GetContinuousStateDerivatives", "status": "fmi3Error",
        "log": ["first", "second"]}
    assert traj.message.startswith("fmi3GetContinuousStateDerivatives returned fmi3Error "
                                   "after the event at t = ")


def test_event_log_counts_all_and_lists_the_first_times():
    log = EventLog()
    outcome = event_update(RelayOde(boost_at=None), 0.5, np.array([0.3]))
    for k in range(1500):
        log.add("state" if k % 2 else "time", float(k), outcome)
    assert (log.state, log.time, len(log.times)) == (750, 750, 1000)
