"""The simulation verdicts tag their sub-checks (catalogue parts), judged in-process on
hand-made trajectories: no FMU, no worker."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from conformance.numerics import settings as st
from conformance.numerics.dae import STALLED_SINGULAR
from conformance.numerics.settings import Trajectory
from conformance.probes.instruments.api import ProbeContext, ProbeSkipped
from conformance.probes.simulation import verdicts as V
from conformance.report.catalogue import default_catalogue

OPTIONS = {r.code: r.option_values for r in default_catalogue()}


def _traj(mode: str, values, *, times=None, **kw) -> Trajectory:
    values = np.asarray(values, dtype=float).reshape(-1, 1)
    times = list(times if times is not None else np.linspace(0.0, 1.0, len(values)))
    return Trajectory(mode=mode, names=["x"], kinds=["state"], times=times, values=values,
                      t_end=times[-1], stop_time=1.0, rtol=1e-6, atol=[1e-8], steps=10, **kw)


def _ctx(dae: Trajectory, ode: Trajectory | None = None) -> ProbeContext:
    layout = SimpleNamespace(enable_status="ok", algebraic=[], states=[], name=str)
    facts = {"layout": layout, "simulation.dae": dae,
             "simulation.ode": ode if ode is not None else ProbeSkipped("no ODE mode")}
    return ProbeContext(model=None, manifest=None, draft="alpha1", seed=0,  # type: ignore
                        rng=np.random.default_rng(0), points=[], dae=None, ode=None,
                        new_instance=lambda mode: None, facts=facts)


def test_no_consistent_start_and_restart_after_event_are_parts_of_simulation_failed():
    init = _traj("dae", [1.0], status=st.INIT, message="Newton's method did not ...")
    (v,) = V.simulation_failed(_ctx(init), **OPTIONS["DAE801"])
    assert v.part == "no-consistent-start"
    restart = _traj("dae", [1.0, 1.0], status=st.SOLVER, message="no consistent algebraic "
                    "variables after the event at t = 0.5: ...",
                    event={"t": 0.5, "after_event": True})
    (v,) = V.simulation_failed(_ctx(restart), **OPTIONS["DAE801"])
    assert v.part == "restart-after-event"
    solver = _traj("dae", [1.0, 1.0], status=st.SOLVER, message="IDA stopped",
                   event={"t": 0.5})
    (v,) = V.simulation_failed(_ctx(solver), **OPTIONS["DAE801"])
    assert v.part is None


def test_a_stalled_run_blamed_on_dgdw_is_its_part():
    event = {"t": 0.5, "condition": 1e9, "threshold": 1e8, "involved": []}
    stalled = _traj("dae", [1.0, 1.0], status=st.SINGULAR, message=STALLED_SINGULAR,
                    event=event, init={"condition": 1.0})
    (v,) = V.singular_along_trajectory(_ctx(stalled))
    assert v.part == "stalled-run-blamed"
    stopped = _traj("dae", [1.0, 1.0], status=st.SINGULAR, message="dg/dw became singular",
                    event=dict(event, condition=1e13, threshold=1e12), init={"condition": 1.0})
    (v,) = V.singular_along_trajectory(_ctx(stopped))
    assert v.part is None


def _mismatch(dae: Trajectory, ode: Trajectory):
    options = dict(OPTIONS["DAE805"], confirm_levels=0)   # no confirmation runs
    return list(V.ode_dae_trajectory_mismatch(_ctx(dae, ode), **options))


def test_a_gap_at_the_initial_point_is_its_part():
    """Other states at the start: the initialisations differ (alpha.1 leaves DAE mode's open)."""
    (v,) = _mismatch(_traj("dae", [1.0, 1.0, 1.0]), _traj("ode", [1.1, 1.1, 1.1]))
    assert v.part == "initial-gap"


def test_the_same_states_and_other_algebraic_values_at_the_start_are_the_rules_own_case():
    """The modes contradict each other at one point: the rule's own verdict (an error)."""
    def both(mode: str, w: float) -> Trajectory:
        values = np.array([[1.0, w], [1.0, w], [1.0, w]])
        return Trajectory(mode=mode, names=["x", "w"], kinds=["state", "algebraic"],
                          times=[0.0, 0.5, 1.0], values=values, t_end=1.0, stop_time=1.0,
                          rtol=1e-6, atol=[1e-8, 1e-8], steps=10)
    (v,) = _mismatch(both("dae", 2.0), both("ode", 2.5))
    assert v.part is None


def test_a_gap_born_after_an_event_is_its_part_and_one_before_is_not():
    dae, ode = [1.0, 1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.1, 1.1]
    (v,) = _mismatch(_traj("dae", dae, event_times=[0.6], state_events=1),
                     _traj("ode", ode, event_times=[0.6], state_events=1))
    assert v.part == "after-events"
    (v,) = _mismatch(_traj("dae", dae, event_times=[0.8], state_events=1),
                     _traj("ode", ode, event_times=[0.8], state_events=1))
    assert v.part is None                                  # born at 0.75, before the event
    (v,) = _mismatch(_traj("dae", dae), _traj("ode", ode))
    assert v.part is None                                  # no event at all
