"""conformance/run/simulate_fmu.py without running an FMU: the rules and options a simulation
runs with, its start values and DefaultExperiment, and how its trajectories are read back from
the report (the simulations themselves are in tests/simulate)."""
from __future__ import annotations

import pytest

from conformance.report.findings import FmuReport, evidence
from conformance.run import simulate_fmu as sim
from conformance.run.engine import EngineOptions
from tests.simkit import sim_settings


def test_the_simulation_options_and_the_time_limits_follow_the_settings():
    settings = sim_settings(mode="dae", output_times=[0.5, 1.0], wall_seconds=10.0,
                            start_values=[("p", 2.0)])
    catalogue = sim.simulation_catalogue(settings)
    failed = catalogue["simulation-failed"].option_values
    assert failed["output_times"] == (0.5, 1.0) and failed["published_series"] == 0
    assert failed["start_values"] == (("p", 2.0),)
    assert all(failed[k] == v for k, v in settings.as_options().items()
               if k not in ("output_times", "start_values", "published_series"))
    assert failed["mode"] == "dae"
    timed = catalogue["binary-timed-out"].option_values
    assert (timed["probe_seconds"], timed["fmu_seconds"]) == (2 * 10.0 + 30.0, 2 * 10.0 + 60.0)
    both = sim.simulation_catalogue(sim_settings(mode="both"), time_limit=5.0)
    timed = both["binary-timed-out"].option_values
    assert (timed["probe_seconds"], timed["fmu_seconds"]) == (40.0, 3 * 5.0 + 60.0)
    assert catalogue["DAE740"] == both["DAE740"]


class _Model:
    def __init__(self, variables=(), experiment=None):
        self.variables = list(variables)
        self.default_experiment = experiment


class _Var:
    def __init__(self, name, causality="parameter", type="Float64", dimensions=()):
        self.name, self.causality, self.type, self.dimensions = name, causality, type, dimensions


class _Experiment:
    def __init__(self, start, stop, tolerance):
        self.start_time, self.stop_time, self.tolerance = start, stop, tolerance


def test_the_default_experiment_keeps_its_finite_numbers():
    assert sim.default_experiment(None) == {}
    assert sim.default_experiment(_Model()) == {}
    assert sim.default_experiment(_Model(experiment=_Experiment(0, 10.5, None))) == {
        "startTime": 0.0, "stopTime": 10.5}
    assert sim.default_experiment(_Model(experiment=_Experiment(float("nan"), 2, 1e-6))) == {
        "stopTime": 2.0, "tolerance": 1e-6}


def test_start_values_are_scalar_float64_inputs_and_parameters():
    model = _Model([_Var("p"), _Var("u", "input"), _Var("x", "local"), _Var("n", type="Int32"),
                    _Var("a", dimensions=(3,))])
    assert sim.start_values(model, []) == ()
    assert sim.start_values(model, ["p=2", " u = -1e3"]) == (("p", 2.0), ("u", -1000.0))
    for item, says in (("p", "--start-value takes NAME=VALUE, not 'p'"),
                       ("p=x", "--start-value p: not a number: 'x'"),
                       ("q=1", "--start-value: the FMU has no variable 'q'"),
                       ("x=1", "--start-value x: only scalar Float64 inputs and parameters can "
                               "be given (it is a Float64 local)"),
                       ("n=1", "(it is a Int32 parameter)"), ("a=1", "(it is a Float64 parameter)")):
        with pytest.raises(ValueError) as caught:
            sim.start_values(model, [item])
        assert says in str(caught.value)
    with pytest.raises(ValueError, match="no variable 'p'"):
        sim.start_values(None, ["p=1"])


def _run(monkeypatch, simulation, mode="both"):
    calls = []

    def check(path, *, options, catalogue, display_path):
        calls.append((path, options, catalogue, display_path))
        info = evidence(simulation=simulation) if simulation is not None else ()
        return FmuReport(display_path, None, (), rules_skipped=(("DAE805", "a reason"),
                                                                ("DAE701", "other")),
                         info=info)

    monkeypatch.setattr(sim, "check_fmu", check)
    return sim.simulate_fmu("m.fmu", sim_settings(mode=mode)), calls


def _info(mode: str, **extra):
    return {"mode": mode, "times": [0.0, 1.0], "series": {"x": [1.0, 2.0]}, **extra}


def test_a_simulation_reads_its_trajectories_back_from_the_report(monkeypatch):
    result, calls = _run(monkeypatch, _info("dae", ode=_info("ode"), comparison={"ok": True}))
    ((path, options, catalogue, shown),) = calls
    assert str(path) == "m.fmu" and shown == "m.fmu"
    assert options == EngineOptions(select=("DAE0", "DAE70", "DAE801", "DAE802", "DAE803",
                                            "DAE804", "DAE805"), probes_only=True)
    assert result.catalogue is catalogue and result.report.path == "m.fmu"
    assert [(t.mode, t.times) for t in result.trajectories] == [("dae", [0.0, 1.0]),
                                                                ("ode", [0.0, 1.0])]
    assert result.comparison == {"ok": True}
    assert result.skipped() == ["a reason"]


def test_a_simulation_without_a_run_has_no_trajectories(monkeypatch):
    for simulation in (None, {"times": None}, {"status": "not run"}):
        result, _ = _run(monkeypatch, simulation, mode="ode")
        assert result.trajectories == [] and result.comparison is None
    result, calls = _run(monkeypatch, _info("dae", ode="none", comparison=[1]), mode="dae")
    assert [t.mode for t in result.trajectories] == ["dae"] and result.comparison is None
    assert calls[0][1].select == ("DAE0", "DAE70", "DAE801", "DAE802", "DAE803", "DAE804")
