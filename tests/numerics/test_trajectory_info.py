"""A trajectory's report info (``Trajectory.to_info``/``from_info``): every key exactly, since the
runner and the simulation rules read them back, and ``finite_rows``."""
from __future__ import annotations

import math

import numpy as np

from conformance.numerics.settings import Trajectory, finite_rows


def _full_trajectory() -> Trajectory:
    return Trajectory(
        mode="dae", names=["x", "w", "z"], kinds=["state", "algebraic", "algebraic"],
        times=[0.0, 0.5, 1.0], values=np.array([[1.0, 2.0, 3.0], [4.0, math.nan, 6.0],
                                                [7.0, 8.0, 9.0]]),
        status="singular", message="why", t_start=0.0, t_end=1.0, stop_time=2.0, rtol=1e-6,
        atol=[1e-6, 2e-6, 3e-6], steps=11, function_calls=12, jacobian_calls=13, fmi_calls=14,
        wall_s=0.1234567, jacobian="finite differences", recovered=2, max_condition=1e9,
        max_condition_t=0.75, init={"iterations": 3}, event={"t": 0.5},
        residual_along={"max_abs": 1e-9}, indicators=1, state_events=2, time_events=3,
        event_times=[0.25, 0.5], event_updates=4, terminated_at=None, residual_jump=0.125,
        events_behind=[(0.5, 0.25)], events_behind_count=1)


def test_to_info_writes_every_key_exactly():
    info = _full_trajectory().to_info(series=2)
    assert info == {
        "mode": "dae", "status": "singular", "message": "why", "times": [0.0, 0.5, 1.0],
        "series": {"x": [1.0, 4.0, 7.0], "w": [2.0, None, 8.0]},
        "kinds": {"x": "state", "w": "algebraic"},
        "rtol": 1e-6, "atol": {"x": 1e-6, "w": 2e-6},
        "t_start": 0.0, "t_end": 1.0, "stop_time": 2.0,
        "steps": 11, "function_calls": 12, "jacobian_calls": 13, "fmi_calls": 14,
        "jacobian": "finite differences", "recovered": 2, "max_condition": 1e9,
        "max_condition_t": 0.75, "init": {"iterations": 3}, "event": {"t": 0.5},
        "series_left_out": 1, "residual_along": {"max_abs": 1e-9},
        "events": {"indicators": 1, "state": 2, "time": 3, "times": [0.25, 0.5],
                   "updates": 4, "terminated_at": None, "residual_jump": 0.125,
                   "behind": [[0.5, 0.25]], "behind_count": 1},
        "wall_s": 0.123457,
    }


def test_to_info_writes_nan_as_null_only_in_the_columns_that_hold_one():
    info = _full_trajectory().to_info(timing=False)
    assert info["series"] == {"x": [1.0, 4.0, 7.0], "w": [2.0, None, 8.0], "z": [3.0, 6.0, 9.0]}
    assert "series_left_out" not in info and "wall_s" not in info


def test_from_info_reads_back_every_field():
    traj = _full_trajectory()
    back = Trajectory.from_info(traj.to_info())
    assert back.names == traj.names and back.kinds == traj.kinds and back.atol == traj.atol
    assert np.array_equal(back.values, traj.values, equal_nan=True)
    for name in ("mode", "status", "message", "t_start", "t_end", "stop_time", "rtol", "steps",
                 "function_calls", "jacobian_calls", "fmi_calls", "jacobian", "recovered",
                 "max_condition", "max_condition_t", "init", "event", "residual_along",
                 "indicators", "state_events", "time_events", "event_times", "event_updates",
                 "terminated_at", "residual_jump", "events_behind", "events_behind_count"):
        assert getattr(back, name) == getattr(traj, name), name
    assert back.wall_s == 0.123457


def test_finite_rows_is_one_flag_per_row():
    values = np.array([[1.0, math.nan, 0.0], [1.0, 2.0, math.inf], [1.0, 2.0, 3.0]])
    assert finite_rows(values, [0, 1]).tolist() == [False, True, True]
    assert finite_rows(values, [2]).tolist() == [True, False, True]
    assert finite_rows(values, []).tolist() == [True, True, True]
