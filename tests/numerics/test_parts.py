"""The small parts: settings, the condition measure, the budget, the comparison, the CSV."""
from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest

from conformance.numerics import settings as st
from conformance.numerics.compare import compare
from conformance.numerics.limits import Budget, Stop, scaled_condition
from conformance.simulate.output import to_csv
from conformance.numerics.settings import Settings, Trajectory, parse_times
from tests.simkit import sim_settings

DENSE = sim_settings().dense_up_to


def _traj(mode: str, names, values, *, times=(0.0, 0.5, 1.0), rtol=1e-6, atol=None):
    values = np.array(values, dtype=float)
    return Trajectory(mode=mode, names=list(names), kinds=["state"] * len(names),
                      times=list(times), values=values, rtol=rtol,
                      atol=list(atol or [rtol] * len(names)))


# ---------------------------------------------------------------------------------- settings

def test_settings_from_catalogue_options_ignore_other_keys():
    defaults = sim_settings().as_options()
    s = Settings.from_options({**defaults, "rtol": 1e-4, "output_times": [1, 2], "factor": 100.0})
    assert s.rtol == 1e-4 and s.output_times == (1.0, 2.0)
    with pytest.raises(ValueError):
        Settings.from_options({**defaults, "mode": "sideways"})


def test_stop_time_explicit_then_default_experiment_then_horizon():
    assert sim_settings(stop_time=5.0).stop(0.0, 40.0) == 5.0
    assert sim_settings().stop(0.0, 40.0) == 40.0
    assert sim_settings(horizon=2.0).stop(1.0, None) == 3.0
    assert sim_settings().stop(1.0, 0.5) == 2.0  # a DefaultExperiment stop before the start


def test_output_times_grid_or_explicit():
    assert sim_settings(output_points=5).times(0.0, 1.0) == pytest.approx([0, .25, .5, .75, 1])
    explicit = sim_settings(output_times=(40.0, 0.4, 4e5, 0.4)).times(0.0, 100.0)
    assert list(explicit) == [0.0, 0.4, 40.0]  # the start first, sorted, within the stop


def test_parse_times():
    assert parse_times("0.4, 40,4e5") == (0.4, 40.0, 4e5)
    for bad in ("", "a,b", "1,nan"):
        with pytest.raises(ValueError):
            parse_times(bad)


def test_trajectory_round_trips_through_the_report_info():
    traj = _traj("dae", ["x", "w"], [[1, 2], [3, math.nan], [5, 6]])
    traj.event = {"t": 0.5}
    info = traj.to_info(timing=False)
    assert "wall_s" not in info and info["series"]["w"] == [2.0, None, 6.0]
    back = Trajectory.from_info(info)
    assert back.names == ["x", "w"] and back.times == traj.times
    assert np.array_equal(back.values, traj.values, equal_nan=True)
    assert back.event == {"t": 0.5} and "wall_s" in traj.to_info()


def test_published_series_are_thinned_evenly():
    traj = _traj("dae", ["x"], [[v] for v in range(11)], times=[float(t) for t in range(11)])
    info = traj.to_info(limit=3)
    assert info["times"] == [0.0, 5.0, 10.0] and info["series"]["x"] == [0.0, 5.0, 10.0]


# ------------------------------------------------------------------------ condition, budget

def test_scaled_condition_of_a_scalar_dg_dw_sees_it_vanish():
    # rows [f; g], columns [x; w]: g = (1 - y1^2) y2 - y1 near y1 = 1
    eps = 1e-6
    jac = np.array([[0.0, 1.0], [-1.0 / eps, 2 * eps]])
    cond, direction = scaled_condition(jac, 1, np.ones(2), dense_up_to=DENSE)
    assert cond == pytest.approx((1 / eps + 2 * eps) / (2 * eps))
    assert abs(direction[0]) == pytest.approx(1.0)


def test_scaled_condition_follows_nominal_values_and_detects_zero_rows():
    jac = np.array([[0, 0, 0], [1, 1, 0], [0, 0, 1e-6]], dtype=float)
    good, _ = scaled_condition(jac, 1, np.array([1.0, 1.0, 1e6]), dense_up_to=DENSE)
    assert good == pytest.approx(2.0)  # w2 = 1e-6 * nominal 1e6: as well-conditioned as w1
    dead, _ = scaled_condition(np.array([[0.0, 1.0], [0.0, 0.0]]), 1, np.ones(2),
                               dense_up_to=DENSE)
    assert dead == math.inf


def test_scaled_condition_weighs_a_residual_by_its_columns_nominal_values():
    """g = x + 1e-6 w with w's nominal 1e6: w moves g by as much as x does (1 each, per
    nominal), so G = (1e-6 * 1e6) / (1 + 1e-6 * 1e6) = 1/2 and the condition is 2; dividing by
    the nominal instead would make w look 1e12 times weaker."""
    jac = np.array([[0.0, 0.0], [1.0, 1e-6]])
    cond, _ = scaled_condition(jac, 1, np.array([1.0, 1e6]), dense_up_to=DENSE)
    assert cond == pytest.approx(2.0)


def test_budget_detects_a_stall_and_counts_steps():
    budget = Budget(max_steps=100, wall_seconds=10.0, stall_steps=3, clock=lambda: 0.0)
    budget.progress(1.0, 1)
    budget.progress(1.0 + 1e-14, 2)
    budget.progress(1.0 + 2e-14, 3)
    with pytest.raises(Stop) as stalled:
        budget.progress(1.0 + 3e-14, 4)
    assert stalled.value.status == st.SOLVER and stalled.value.details["stalled_since"] == 1.0
    with pytest.raises(Stop) as steps:
        budget.check_step(2.0, 100)
    assert steps.value.status == st.BUDGET and steps.value.details["limit"] == "max_steps"


def test_budget_wall_clock():
    now = {"t": 0.0}
    budget = Budget(max_steps=10, wall_seconds=1.0, stall_steps=3, clock=lambda: now["t"])
    budget.check_clock(0.0)
    now["t"] = 1.5
    with pytest.raises(Stop) as late:
        budget.check_clock(0.3)
    assert late.value.details["limit"] == "wall_seconds" and late.value.t == 0.3


# ------------------------------------------------------------------------------- comparison

def test_gaps_are_in_tolerance_units_over_common_times_and_names():
    dae = _traj("dae", ["x", "z"], [[1, 1], [2, 2], [3, 3]], atol=[1e-6, 1e-6])
    ode = _traj("ode", ["x", "q"], [[1, 0], [2 + 4e-6, 0]], times=(0.0, 0.5))
    found = compare(dae, ode)
    assert found.compared_times == 2 and found.variables == ["x"]
    assert found.left_out == ["z", "q"]
    assert found.gaps["x"] == pytest.approx(4e-6 / (1e-6 * (2 + 4e-6) + 1e-6))
    assert found.worst["variable"] == "x" and found.worst["t"] == 0.5


def test_unreadable_values_are_left_out_and_nothing_in_common_is_none():
    dae = _traj("dae", ["x", "w"], [[1, 1], [2, 2], [3, 3]])
    ode = _traj("ode", ["x", "w"], [[1, math.nan], [2, math.nan], [3, math.nan]])
    assert compare(dae, ode).left_out == ["w"]
    assert compare(dae, _traj("ode", ["x"], [[1]], times=(7.0,))) is None


# ------------------------------------------------------------------------------------- csv

def test_csv_has_time_then_the_names_of_modeldescription():
    traj = _traj("dae", ["y1", "der(x,2)", "'a b'"], [[1, 2, 3], [0.1, math.nan, 1e-13],
                                                      [4, 5, 6]])
    rows = list(csv.reader(io.StringIO(to_csv(traj))))
    assert rows[0] == ["time", "y1", "der(x,2)", "'a b'"]
    assert rows[2] == ["0.5", "0.1", "", "1e-13"]
    assert float(rows[2][1]) == 0.1 and len(rows) == 4
