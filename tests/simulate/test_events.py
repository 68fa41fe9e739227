"""Simulating an FMU through its events (EventDAE: a state event that changes a residual and a
time event; scenes/EventDAE/README.md gives the exact solution): both modes against the exact
solution, ODE mode against ``fmpy simulate`` (its own CVODE and event loop), DAE mode against ODE
mode (ode-dae-trajectory-mismatch stays clean), terminateSimulation, the report and the summary.
The event loop itself is tested on plain Python models in tests/numerics/test_events.py."""
from __future__ import annotations

import argparse
import math

import fmpy
import numpy as np
import pytest

from conformance.report.findings import thaw
from conformance.commands.simulate import add_parser, run, simulate_fmu, summary
from scenes.build import build_scene
from tests.simkit import sim_settings

T1, T2 = math.log(2.0), 0.75   # the state event (x falls to 0.5) and the time event
RTOL = 1e-8


def exact(t: float) -> tuple[float, float]:
    """x(t) and w(t) of EventDAE; at an event, the values after it."""
    if t < T1:
        x = math.exp(-t)
        return x, x
    if t < T2:
        x = 4.0 * math.exp(-3.0 * t)
        return x, 3.0 * x
    x = (4.0 * math.exp(-2.25) + 1.0 / 6.0) * math.exp(-3.0 * (t - T2)) - 1.0 / 6.0
    return x, 3.0 * x + 0.5


@pytest.fixture(scope="module")
def fmu():
    return build_scene("EventDAE")


@pytest.fixture(scope="module")
def both(fmu):
    return simulate_fmu(fmu, sim_settings(mode="both", rtol=RTOL))


def _gaps(traj, reference: np.ndarray, column: int) -> np.ndarray:
    """|value - reference| in units of the run's tolerance rtol |reference| + atol."""
    return (np.abs(traj.values[:, column] - reference)
            / (traj.rtol * np.abs(reference) + traj.atol[column]))


def test_both_modes_stop_at_the_state_and_the_time_event(both):
    assert {f.code for f in both.report.findings} == set()   # DAE801-DAE805 clean
    dae, ode = both.trajectories
    for traj in (dae, ode):
        assert traj.ok and traj.t_end == 1.0, traj.message
        assert (traj.indicators, traj.state_events, traj.time_events) == (1, 1, 1)
        assert traj.event_times == pytest.approx([T1, T2], abs=1e-7)
        assert traj.terminated_at is None


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_each_mode_follows_the_exact_solution_through_the_events(both, mode):
    traj = next(t for t in both.trajectories if t.mode == mode)
    reference = np.array([exact(t) for t in traj.times])
    assert traj.names == ["x", "w"]
    # the global error, a few tolerance units (measured: 3.6 for x, 6.5 for w, both modes);
    # an event moved by dt shifts x by dt times the jump of x'
    assert _gaps(traj, reference[:, 0], 0).max() <= 20
    assert _gaps(traj, reference[:, 1], 1).max() <= 20
    # at t = 0.75 the output is the value after the time event: w jumped by b = 0.5
    at = traj.times.index(0.75)
    assert traj.series("w")[at] == pytest.approx(exact(0.75)[1], abs=1e-6)
    assert traj.series("x")[-1] == pytest.approx(0.11120936559495823, abs=1e-6)
    assert abs(traj.series("x")[-1] - math.exp(-1.0)) > 0.25   # not straight through


def test_dae_mode_agrees_with_ode_mode(both):
    assert both.comparison and max(both.comparison["gaps"].values()) <= 100.0
    dae, ode = both.trajectories
    assert dae.times == ode.times
    assert np.max(np.abs(dae.values - ode.values)) < 1e-6


def test_ode_mode_agrees_with_fmpy_simulate(fmu, both):
    """fmpy records an event twice (before and after it); the last row at a time is the value
    after the event, what lsdae records at an output time that is an event time. The bound is
    the two runs' global errors together: fmpy's is up to 20 tolerance units here (it locates
    the state event 5e-8 early), lsdae's below 7."""
    result = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output=["x", "w"], output_interval=0.01,
                               relative_tolerance=RTOL)
    last = {float(row[0]): (row[1], row[2]) for row in result}   # later rows win
    ode = next(t for t in both.trajectories if t.mode == "ode")
    compared = 0
    for k, t in enumerate(ode.times):
        match = [s for s in last if abs(s - t) < 1e-12]
        if not match:
            continue
        x, w = last[match[0]]
        assert abs(ode.values[k, 0] - x) <= 40 * (RTOL * abs(x) + ode.atol[0]), t
        assert abs(ode.values[k, 1] - w) <= 40 * (RTOL * abs(w) + ode.atol[1]), t
        compared += 1
    assert compared >= 95


def test_the_events_are_in_the_report(both):
    info = thaw(both.report.info)["simulation"]
    assert info["events"]["state"] == 1 and info["events"]["time"] == 1
    assert info["events"]["times"] == pytest.approx([T1, T2], abs=1e-7)
    # the state event moves g = w - k x - b by -2 x = -1 before w is solved again (DAE mode)
    assert info["events"]["residual_jump"] == pytest.approx(1.0, abs=1e-6)
    assert info["ode"]["events"]["indicators"] == 1
    assert info["ode"]["events"]["residual_jump"] == 0.0


def test_scenes_without_events_report_none():
    result = simulate_fmu(build_scene("HelloWorldDAE"), sim_settings(mode="both"))
    info = thaw(result.report.info)["simulation"]
    assert "events" not in info and "events" not in info["ode"]
    assert all(not t.has_events for t in result.trajectories)


def test_terminate_simulation_ends_both_runs_without_a_finding():
    result = simulate_fmu(build_scene("EventDAE", defines=["EVENTDAE_TERMINATE"]),
                          sim_settings(mode="both", rtol=1e-6))
    assert {f.code for f in result.report.findings} == set()
    for traj in result.trajectories:
        assert traj.ok and traj.terminated_at == pytest.approx(T2) and traj.t_end == T2
        assert traj.times[-1] == T2 and (traj.state_events, traj.time_events) == (1, 1)
        assert traj.event["terminate_simulation"] is True


def test_the_summary_counts_the_events_and_a_termination(both, capsys):
    lines = summary(both.trajectories[0]).splitlines()
    assert len(lines) == 3 and "1 state event, 1 time event" in lines[2]
    parser = argparse.ArgumentParser(prog="lsdae")
    add_parser(parser.add_subparsers(dest="command", required=True))
    fmu = build_scene("EventDAE", defines=["EVENTDAE_TERMINATE"])
    assert run(parser.parse_args(["simulate", str(fmu), "--mode", "both"])) == 0
    text = capsys.readouterr().out
    assert text.count("terminateSimulation") == 2 and "reached the stop time" not in text
