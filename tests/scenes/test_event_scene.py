"""EventDAE and the framework's events: indicators, the event hook, time events.

The scene's README.md gives the equations and the analytic solution; here fmpy (ODE mode) is
held against it, and the framework's event support is driven call by call in both modes: the
indicators come from the importer's w in DAE mode and from the solved w in ODE mode, the hook
changes a discrete variable that the residual uses, and a model without events still reports
none.
"""
from __future__ import annotations

import ctypes
import math

import fmpy
import numpy as np
import pytest
from fmpy.fmi3 import FMU3Model

from scenes.build import build_scene

X, DER, W, Y, G, Z, K, B, SWITCH = 1, 2, 3, 4, 5, 6, 7, 8, 9
FMI_ERROR = 3
T1, T2 = math.log(2.0), 0.75


def exact_x(t: float) -> float:
    """x(t) of EventDAE (README.md)."""
    if t < T1:
        return math.exp(-t)
    if t < T2:
        return 4.0 * math.exp(-3.0 * t)
    x2 = 4.0 * math.exp(-2.25)
    return (x2 + 1.0 / 6.0) * math.exp(-3.0 * (t - T2)) - 1.0 / 6.0


@pytest.fixture(scope="module")
def unzipped(tmp_path_factory):
    out = {}
    for name in ("EventDAE", "SimpleDAE"):
        fmu = build_scene(name)
        folder = fmpy.extract(str(fmu), str(tmp_path_factory.mktemp(name)))
        out[name] = (fmu, folder, fmpy.read_model_description(str(fmu)))
    return out


@pytest.fixture
def make(unzipped):
    created = []

    def factory(name="EventDAE", *, dae=False):
        _, folder, md = unzipped[name]
        fmu = FMU3Model(guid=md.guid, unzipDirectory=folder,
                        modelIdentifier=md.modelExchange.modelIdentifier, instanceName=name)
        fmu.instantiate()
        created.append(fmu)
        if dae:
            fmu.enterConfigurationMode()
            fmu.setBoolean([SWITCH if name == "EventDAE" else 13], [True])
            fmu.exitConfigurationMode()
        return fmu

    yield factory
    for fmu in created:
        fmu.freeInstance()


def _indicators(fmu, n=1) -> list[float]:
    buf = (ctypes.c_double * n)()
    fmu.getEventIndicators(buf, n)
    return list(buf)


def _raw(fmu, fname, *args) -> int:
    return fmu._functions[fname](fmu.component, *args)


def test_fmpy_ode_mode_matches_the_analytic_solution_through_both_events(unzipped):
    fmu = str(unzipped["EventDAE"][0])
    result = fmpy.simulate_fmu(fmu, stop_time=1.0, output=["x", "y", "k", "b"],
                               output_interval=0.01, relative_tolerance=1e-8)
    errors = [abs(x - exact_x(t)) for t, x in zip(result["time"], result["x"])]
    assert max(errors) < 1e-5
    assert result["x"][-1] == pytest.approx(0.11120936559495823, abs=1e-5)
    assert result["y"][-1] == pytest.approx(0.8336280967848747, abs=1e-5)
    assert (result["k"][0], result["k"][-1]) == (1.0, 3.0)
    assert (result["b"][0], result["b"][-1]) == (0.0, 0.5)
    switched = result["time"][np.argmax(result["k"] == 3.0)]
    assert switched == pytest.approx(T1, abs=1e-6)
    assert result["time"][np.argmax(result["b"] == 0.5)] == pytest.approx(T2, abs=1e-12)


def test_indicator_counts_and_values_in_every_state_that_allows_them(make):
    fmu = make()
    assert fmu.getNumberOfEventIndicators() == 1
    fmu.enterInitializationMode(startTime=0.0)
    assert _indicators(fmu) == pytest.approx([0.5])                    # x - 0.5 at x = 1
    fmu.exitInitializationMode()
    assert _indicators(fmu) == fmu.getFloat64([Z])                     # Event Mode
    fmu.enterContinuousTimeMode()
    fmu.setContinuousStates((ctypes.c_double * 1)(0.7), 1)
    assert _indicators(fmu) == pytest.approx([0.2], abs=1e-12)         # solved w = 0.7
    assert _indicators(fmu) == fmu.getFloat64([Z])
    assert _raw(fmu, "fmi3GetEventIndicators", (ctypes.c_double * 2)(), 2) == FMI_ERROR
    fmu.terminate()
    assert _indicators(fmu) == fmu.getFloat64([Z])                     # Terminated


def test_dae_mode_indicators_come_from_the_importers_w(make):
    fmu = make(dae=True)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.enterContinuousTimeMode()
    fmu.setContinuousStates((ctypes.c_double * 1)(0.7), 1)
    fmu.setFloat64([W], [0.9])                                         # inconsistent on purpose
    assert _indicators(fmu) == pytest.approx([0.4])                    # (w - b)/k - 0.5
    assert fmu.getFloat64([G]) == pytest.approx([0.2])
    fmu.setFloat64([W], [0.3])
    assert _indicators(fmu) == pytest.approx([-0.2])


def test_state_event_switches_k_and_changes_the_residual_in_dae_mode(make):
    fmu = make(dae=True)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    need, terminate, _, x_changed, time_defined, next_time = fmu.updateDiscreteStates()
    assert (need, terminate, x_changed, time_defined, next_time) == \
        (False, False, False, True, T2)                                # the time event ahead
    fmu.enterContinuousTimeMode()
    fmu.setTime(0.69)
    fmu.setContinuousStates((ctypes.c_double * 1)(0.49), 1)
    fmu.setFloat64([W], [0.49])                                        # consistent, k = 1
    assert fmu.getFloat64([G]) == pytest.approx([0.0])
    assert _indicators(fmu)[0] < 0                                     # the crossing
    fmu.enterEventMode()
    need, *_ = fmu.updateDiscreteStates()
    assert need is True                                                # k changed: iterate
    assert fmu.getFloat64([K, B]) == [3.0, 0.0]
    assert fmu.getFloat64([G]) == pytest.approx([0.49 - 3 * 0.49])     # the residual jumped
    fmu.setFloat64([W], [3 * 0.49])                                    # re-initialise w
    need, *_ = fmu.updateDiscreteStates()
    assert need is False
    assert fmu.getFloat64([G]) == pytest.approx([0.0])
    assert _indicators(fmu) == pytest.approx([0.49 - 1.5])             # far from zero now
    fmu.enterContinuousTimeMode()


def test_time_event_changes_b_and_ode_mode_solves_w_again(make):
    fmu = make()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.updateDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setTime(T2)
    fmu.setContinuousStates((ctypes.c_double * 1)(0.8), 1)
    assert fmu.getFloat64([W]) == pytest.approx([0.8])                 # k = 1, b = 0
    fmu.enterEventMode()
    need, _, _, _, time_defined, _ = fmu.updateDiscreteStates()
    assert (need, time_defined) == (True, False)                       # b changed, no more
    assert fmu.getFloat64([B, W]) == pytest.approx([0.5, 1.3])         # w = k x + b, solved
    need, *_ = fmu.updateDiscreteStates()
    assert need is False


def test_discrete_variables_are_saved_reset_and_not_settable(make):
    fmu = make()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.enterContinuousTimeMode()
    state = fmu.getFMUState()
    fmu.setTime(T2)
    fmu.enterEventMode()
    fmu.updateDiscreteStates()
    assert fmu.getFloat64([B]) == [0.5]
    assert _raw(fmu, "fmi3SetFloat64", (ctypes.c_uint32 * 1)(B), 1,
                (ctypes.c_double * 1)(0.0), 1) == FMI_ERROR
    fmu.setFMUState(state)
    assert fmu.getFloat64([B]) == [0.0]
    fmu.freeFMUState(state)
    fmu.reset()
    assert fmu.getFloat64([K, B]) == [1.0, 0.0]


def test_a_model_without_events_reports_none(make):
    fmu = make("SimpleDAE")
    assert fmu.getNumberOfEventIndicators() == 0
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    assert _raw(fmu, "fmi3GetEventIndicators", (ctypes.c_double * 1)(), 1) == FMI_ERROR
    assert _raw(fmu, "fmi3GetEventIndicators", None, 0) == 0
    need, terminate, nominals, values, time_defined, _ = fmu.updateDiscreteStates()
    assert not any((need, terminate, nominals, values, time_defined))
