"""invariant-drift (DAE806, issue 21.5): what a manifest's <Invariant> promises, probed along
the simulation runs of both modes; the element itself is invariant-rejected-by-importers.

MassSpringDAE conserves its energy: with <Invariant> on the energy nothing drifts (the clean
twin of the DAE806 defect variant); with DEFECT_ENERGY_DRIFT it drifts in DAE mode and in ODE
mode alike (one finding, the ODE mode's folded into it); an <Invariant> on a variable that is
not constant (the position) drifts on the correct model too, in both modes.
"""
from __future__ import annotations

from conformance.report.findings import Severity
from conformance.run.engine import EngineOptions, check_fmu
from tests.checkkit import checked
from tests.fixtures import ENERGY_INVARIANT, variant

POSITION_INVARIANT = (ENERGY_INVARIANT[0],
                      ENERGY_INVARIANT[1].replace('valueReference="8"', 'valueReference="2"'))


def _findings(report):
    return sorted((f.name, f.subject, f.evidence_dict().get("mode")) for f in report.findings
                  if f.severity >= Severity.WARNING or f.name == "invariant-drift")


def test_a_conserved_invariant_does_not_drift_in_either_mode():
    report = check_fmu(variant("MassSpringDAE", manifest_edits=(ENERGY_INVARIANT,)),
                       options=EngineOptions(probes=True))
    assert _findings(report) == [("invariant-rejected-by-importers", "8", None)]
    assert "DAE806" in report.rules_run


def test_a_drifting_invariant_is_one_finding_that_names_both_modes():
    report = checked(variant("MassSpringDAE", defines=["DEFECT_ENERGY_DRIFT"],
                             manifest_edits=(ENERGY_INVARIANT,)),
                       options=EngineOptions(probes=True))
    drift = [f for f in report.findings if f.name == "invariant-drift"]
    assert [(f.subject, f.evidence_dict()["mode"]) for f in drift] == [("energy", "DAE mode")]
    assert [dict(a)["where"] for a in drift[0].evidence_dict()["also"]] == ["ODE mode trajectory"]
    for f in drift:
        ev = f.evidence_dict()
        assert f.severity == Severity.INFO and ev["drift"] > ev["tolerance"]
        assert f.location.file.endswith("fmi-ls-manifest.xml")


def test_an_invariant_on_a_variable_that_moves_drifts_on_a_correct_model():
    # only invariant-drift is looked at: its simulation runs, no other probe
    report = check_fmu(variant("MassSpringDAE", manifest_edits=(POSITION_INVARIANT,)),
                       options=EngineOptions(probes=True, select=("DAE806",)))
    drift = [f for f in report.findings if f.name == "invariant-drift"]
    assert [(f.subject, f.evidence_dict()["mode"]) for f in drift] == [("p", "DAE mode")]
    assert [dict(a)["where"] for a in drift[0].evidence_dict()["also"]] == ["ODE mode trajectory"]


def test_without_an_invariant_nothing_is_simulated_for_it():
    report = check_fmu(variant("MassSpringDAE", defines=["DEFECT_ENERGY_DRIFT"]),
                       options=EngineOptions(probes=True, select=("DAE806",)))
    assert report.findings == () and "DAE806" in report.rules_run
