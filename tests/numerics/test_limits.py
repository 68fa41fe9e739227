"""The pure helpers of conformance.numerics.limits on hand-made inputs: who is blamed when a
solver gives up (the exact status, message and event), and the scaled condition of a sparse
dg/dw at the edges (a residual that depends on nothing, a row whose total sensitivity is 1)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp

from conformance.numerics import settings as st
from conformance.numerics.limits import blame_solver_failure, scaled_condition
from conformance.numerics.settings import Trajectory


def _traj() -> Trajectory:
    return Trajectory(mode="dae", names=["x"], kinds=["state"], times=[0.0],
                      values=np.zeros((1, 1)))


def _stepper(t: float):
    return SimpleNamespace(t=t, failure=SimpleNamespace(message="the error test failed",
                                                        status=-3))


def test_a_solver_that_gives_up_without_model_failures_is_blamed_with_its_status():
    traj = _traj()
    failures = [(0.25, "fmi3GetFloat64", "fmi3Discard"), (0.5, "fmi3GetFloat64", "fmi3Discard")]
    blame_solver_failure(traj, failures, _stepper(0.5), "IDA")   # none beyond t = 0.5
    assert traj.status == st.SOLVER
    assert traj.message == "IDA stopped at t = 0.5: the error test failed"
    assert traj.event == {"t": 0.5, "solver_status": -3, "solver": "the error test failed"}
    assert type(traj.event["solver_status"]) is int


def test_model_failures_beyond_where_the_solver_stopped_are_the_cause():
    traj = _traj()
    failures = [(0.25, "a", "fmi3Discard"), (0.75, "fmi3GetFloat64", "fmi3Discard"),
                (0.8, "non-finite values", "NaN or Inf")]
    blame_solver_failure(traj, failures, _stepper(0.5), "CVODE")
    assert traj.status == st.FMU_FAILED
    assert traj.message == ("non-finite values returned NaN or Inf at every step CVODE tried "
                            "beyond t = 0.5; reducing the step did not help")
    assert traj.event == {"t": 0.5, "call": "non-finite values", "status": "NaN or Inf",
                          "failed_evaluations": 2, "solver": "the error test failed"}


def test_a_sparse_residual_that_depends_on_nothing_is_infinitely_ill_conditioned():
    jac = sp.csc_array(np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]))
    cond, direction = scaled_condition(jac, 1, np.ones(3), dense_up_to=0)
    assert cond == np.inf and direction.tolist() == [0.0, 0.0]


def test_a_sparse_row_of_total_sensitivity_one_is_well_conditioned():
    # g1 = w1 (S = 1), g2 = 2 w2 (S = 2): G = I, condition 1 in the 1-norm
    jac = sp.csc_array(np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]))
    cond, _ = scaled_condition(jac, 1, np.ones(3), dense_up_to=0)
    assert cond == 1.0
