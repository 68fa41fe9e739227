"""The corpus FMUs run: their C code does what their modelDescription.xml says.

Driven through fmpy, as an importer would: every start value in the XML reads back with the
typed getter of its type and its element count, Model Exchange and Co-Simulation simulate from
the default experiment, Scheduled Execution runs its partitions, and calls the FMI 3.0 state
machine forbids return an error.
"""
from __future__ import annotations

import ctypes
import math
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3ScheduledExecution, FMU3Slave, fmi3Float64, fmi3ValueReference
from lxml import etree

from tests.scenes.test_corpus import NAMES, SHAPES, corpus_fmu

INTERFACE_CLASS = {"Model Exchange": FMU3Model, "Co-Simulation": FMU3Slave,
                   "Scheduled Execution": FMU3ScheduledExecution}
FMPY_TYPE = {"Model Exchange": "ModelExchange", "Co-Simulation": "CoSimulation"}


def _quiet(*_args):
    pass


@pytest.fixture(scope="module")
def unzipped(tmp_path_factory):
    """name -> (folder of the unzipped FMU, fmpy model description)."""
    out = {}
    for name in NAMES:
        folder = tmp_path_factory.mktemp(name)
        with zipfile.ZipFile(corpus_fmu(name)) as zf:
            zf.extractall(folder)
        out[name] = (folder, fmpy.read_model_description(str(folder)))
    return out


def _instance(unzipped, name, interface):
    folder, md = unzipped[name]
    cls = INTERFACE_CLASS[interface]
    fmu = cls(guid=md.guid, unzipDirectory=str(folder), modelIdentifier=name,
              instanceName=f"{name}-{interface}")
    fmu.instantiate(logMessage=_quiet)
    return fmu, md


def _starts(folder) -> list[tuple[str, int, str, list[str]]]:
    """(type, valueReference, name, start values) of every variable with a start in the XML."""
    root = etree.parse(str(folder / "modelDescription.xml")).getroot()
    variables = root.find("ModelVariables")
    sizes = {int(el.get("valueReference")): el.get("start") for el in variables}
    out = []
    for el in variables:
        starts = [s.get("value") for s in el.findall("Start")]
        if el.get("start") is None and not starts or el.tag == "Clock":
            continue
        count = 1
        for dim in el.findall("Dimension"):
            count *= int(dim.get("start") or sizes[int(dim.get("valueReference"))])
        if not starts:
            starts = el.get("start").split()
        if len(starts) == 1:
            starts = starts * count
        assert len(starts) == count, el.get("name")
        out.append((el.tag, int(el.get("valueReference")), el.get("name"), starts))
    return out


def _expected(type_: str, text: str):
    if type_ in ("Float32", "Float64"):
        return float(text)
    if type_ == "Boolean":
        return text in ("true", "1")
    if type_ == "String":
        return text
    if type_ == "Binary":
        return bytes.fromhex(text)
    return int(text)


@pytest.mark.parametrize("name", NAMES)
def test_every_start_value_reads_back_with_its_type(unzipped, name):
    fmu, _ = _instance(unzipped, name, SHAPES[name][0])
    try:
        for type_, vr, var, starts in _starts(unzipped[name][0]):
            getter = getattr(fmu, "getInt64" if type_ == "Enumeration" else f"get{type_}")
            got = list(getter([vr], nValues=len(starts)))
            want = [_expected(type_, s) for s in starts]
            if type_ == "Float32":
                assert got == pytest.approx(want, rel=1e-7), var
            else:
                assert got == want, var
    finally:
        fmu.freeInstance()


@pytest.mark.parametrize("name, interface", [(n, i) for n in NAMES for i in SHAPES[n]
                                             if i in FMPY_TYPE])
def test_simulates_from_its_default_experiment(unzipped, name, interface):
    folder, md = unzipped[name]
    result = fmpy.simulate_fmu(str(folder), fmi_type=FMPY_TYPE[interface], logger=_quiet)
    assert result["time"][0] == pytest.approx(float(md.defaultExperiment.startTime or 0.0))
    assert result["time"][-1] == pytest.approx(float(md.defaultExperiment.stopTime))
    for field in result.dtype.names:
        assert np.all(np.isfinite(result[field].astype(float))), field


def test_start_time_model_steps_one_second_after_its_start(unzipped):
    folder, _ = unzipped["StartTime"]
    for interface in ("ModelExchange", "CoSimulation"):
        result = fmpy.simulate_fmu(str(folder), fmi_type=interface, output=["stepped", "y"],
                                   logger=_quiet)
        assert result["time"][0] == 10.0
        stepped = result["time"][result["stepped"].astype(bool)]
        assert stepped.min() == pytest.approx(11.0, abs=0.02), interface


def test_bouncing_ball_bounces_and_samples(unzipped):
    folder, _ = unzipped["ModelExchangeEvents"]
    result = fmpy.simulate_fmu(str(folder), output=["h", "sampled", "bounces"], logger=_quiet)
    assert result["bounces"][-1] >= 3
    assert result["h"].min() > -1e-3
    # sampled holds h of the last sample instant, a multiple of period = 0.25 s
    row = np.searchsorted(result["time"], 0.3)
    assert result["sampled"][row] == pytest.approx(1 - 9.81 / 2 * 0.25 ** 2, rel=1e-3)


def test_scheduled_execution_runs_its_partitions(unzipped):
    fmu, _ = _instance(unzipped, "ScheduledExecutionOnly", "Scheduled Execution")
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setFloat64([3], [1.0])                       # u, initial exact: settable here
        fmu.exitInitializationMode()
        intervals, qualifiers = (fmi3Float64 * 2)(), (ctypes.c_int * 2)()
        fmu.getIntervalDecimal((fmi3ValueReference * 2)(1, 2), intervals, qualifiers)
        assert list(intervals) == [0.01, 0.1]
        for k in range(100):
            fmu.activateModelPartition(1, k * 0.01)
            if k % 10 == 0:
                fmu.activateModelPartition(2, k * 0.01)
        assert fmu.getFloat64([7])[0] == pytest.approx(1 - 0.8 ** 100)
        assert fmu.getInt32([8])[0] == 10
        with pytest.raises(FMICallException):
            fmu.activateModelPartition(3, 1.0)           # u is not a Clock
        fmu.terminate()
    finally:
        fmu.freeInstance()


def test_structural_parameters_resize_only_in_configuration_mode(unzipped):
    fmu, _ = _instance(unzipped, "StructuralParameters", "Model Exchange")
    try:
        with pytest.raises(FMICallException):
            fmu.setUInt64([1], [5])                      # n outside Configuration Mode
        fmu.enterConfigurationMode()
        with pytest.raises(FMICallException):
            fmu.setUInt64([1], [9])                      # above max="8"
        fmu.setUInt64([1], [5])
        fmu.setBoolean([2], [True])                      # useOffset
        fmu.exitConfigurationMode()
        fmu.enterInitializationMode()
        y = list(fmu.getFloat64([8], nValues=5))
        assert y == pytest.approx([0.5 * 1 + 0.1] * 5)
        fmu.exitInitializationMode()
        fmu.enterConfigurationMode()                     # Reconfiguration: gainScale is tunable
        with pytest.raises(FMICallException):
            fmu.setUInt64([1], [2])                      # n is fixed
        fmu.setFloat64([3], [2.0])
        fmu.exitConfigurationMode()
        assert list(fmu.getFloat64([8], nValues=5)) == pytest.approx([2 * 0.5 + 0.1] * 5)
    finally:
        fmu.freeInstance()


def test_types_and_arrays_outputs_and_clock(unzipped):
    fmu, _ = _instance(unzipped, "TypesAndArrays", "Model Exchange")
    try:
        with pytest.raises(FMICallException):
            fmu.setFloat64([5], [0.0, 0.0, 0.0])          # y is calculated
        with pytest.raises(FMICallException):
            fmu.getFloat64([7])                           # i8 is an Int8
        fmu.setString([18], ["four"])
        fmu.setBinary([20], [b"\x01\x02"])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        assert list(fmu.getFloat64([5], nValues=3)) == pytest.approx([1.5, 3.0, 4.5])
        assert fmu.getInt64([15])[0] == -8 + 8 - 16 + 16 - 32 + 32 - 64 + 64 + 10 + 20
        assert fmu.getUInt32([19])[0] == 4 and fmu.getUInt64([21])[0] == 2
        assert not fmu.getBoolean([17])[0]
        assert fmu.getString([23])[0] == "mode 2"
        for _ in range(3):
            fmu.setClock([25], [True])
            fmu.updateDiscreteStates()
        assert fmu.getInt32([26])[0] == 3
    finally:
        fmu.freeInstance()


def test_co_simulation_only_refuses_model_exchange(unzipped):
    folder, md = unzipped["CoSimulationOnly"]
    with pytest.raises(Exception, match="instantiate"):  # fmpy raises a bare Exception
        FMU3Model(guid=md.guid, unzipDirectory=str(folder), modelIdentifier="CoSimulationOnly",
                  instanceName="me").instantiate(logMessage=_quiet)


def test_a_reset_instance_starts_again(unzipped):
    fmu, _ = _instance(unzipped, "CoSimulationOnly", "Co-Simulation")
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.5)
        moved = fmu.getFloat64([8])[0]
        fmu.reset()
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        assert fmu.getFloat64([8])[0] == 1.0 and not math.isclose(moved, 1.0)
    finally:
        fmu.freeInstance()
