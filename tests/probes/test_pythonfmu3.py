"""FMUs exported by PythonFMU3 (issue 21.2): FMI 3 FMUs of another exporter stay at 0
errors and 0 warnings with the ODE-mode probes on, but for one defect of PythonFMU3 0.3.4 itself
(issue 20): its fmi3UpdateDiscreteStates never writes discreteStatesNeedUpdate and
nominalsOfContinuousStatesChanged (its Python result class names the first
discreteStateNeedsUpdate), so an importer that presets discreteStatesNeedUpdate = true and loops
while it is true, as the Reference FMUs' import examples do, never leaves Event Mode:
event-update-invalid on the Model Exchange ones. They are probed in ODE mode, the
Co-Simulation-only one is not and the report says why. And the probes see what these binaries
hold: an XML start edited after the export is start-value-not-applied, whatever the type.
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from conformance.report.findings import Severity
from conformance.run.engine import EngineOptions, check_fmu
from tests.fixtures import PYTHONFMU3_MODELS, build_pythonfmu3

NAMES = sorted(PYTHONFMU3_MODELS)


@pytest.mark.parametrize("name", NAMES)
def test_pythonfmu3_fmu_is_clean_with_the_probes_on(name):
    report = check_fmu(build_pythonfmu3(name), options=EngineOptions(probes=True))
    me = "Model Exchange" in PYTHONFMU3_MODELS[name]
    bad = [(f.name, dict(f.evidence).get("unwritten")) for f in report.findings
           if f.severity >= Severity.WARNING]
    unwritten = ("discreteStatesNeedUpdate", "nominalsOfContinuousStatesChanged")
    assert bad == ([("event-update-invalid", unwritten)] if me else [])   # ODE mode only
    assert {f.code for f in report.findings} == {"DAE091", *(["DAE734"] if me else [])}
    info = dict(report.info)
    if me:
        assert dict(info["modes"])["ODE mode"] == "probed"
        assert {"DAE713", "DAE742", "DAE744", "DAE750", "DAE723"} <= set(report.rules_run)
        assert report.binary_not_checked is None
    else:
        assert "not Model Exchange" in (report.binary_not_checked or "")


def _edited(source: Path, target: Path, old: str, new: str) -> Path:
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                assert text.count(old) == 1, old
                data = text.replace(old, new).encode()
            zout.writestr(item, data)
    return target


@pytest.mark.parametrize("old, new, variable", [
    ('name="h" valueReference="1" causality="output" variability="continuous" '
     'initial="exact" start="1"', 'name="h" valueReference="1" causality="output" '
     'variability="continuous" initial="exact" start="1.5"', "h"),
    ('start="20"', 'start="21"', "max_bounces"),
    ('start="true"', 'start="false"', "damped"),
    ('<Start value="ball"/>', '<Start value="balloon"/>', "label"),
])
def test_an_xml_start_the_binary_does_not_hold_is_found(tmp_path, old, new, variable):
    fmu = _edited(build_pythonfmu3("PyBouncingBall"), tmp_path / "edited.fmu", old, new)
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    bad = [(f.name, f.subject) for f in report.findings if f.severity >= Severity.WARNING
           and f.name != "event-update-invalid"]      # PythonFMU3's own, see the docstring
    assert bad == [("start-value-not-applied", variable)]
