"""State shared between instances, a family (issue 20, point 3), and the first cause.

``-D DEFECT_SHARED=<what> -D DEFECT_SHARED_BY=<who>`` (scenes/common/fmi3_framework.c) keeps in a
C global what each instance should keep for itself: the results of the last evaluation, the
partial derivatives cached per point, the DAE switch or the inputs; written by the process's
first instance, its second, or every instance (one copy for all). Whatever is shifted and
whoever writes it, the verdict is ``instances-not-independent`` (DAE762), found by the survey
that compares the process's instances with instances alone (each in a copy of the binary of its
own), and none of the findings it explains: the derivative, mode, value and simulation findings
that vanish with every instance alone are folded into DAE762's evidence
(``conformance.probes.machinery.stage``, ``runner.fold_consequences``).

Two members differ, and the tests say why: a global written only by the process's second
instance (lsdae's ODE-mode instance) that holds the switch is never written, since that
instance never sets the switch (the FMU computes right for this importer: nothing to report);
and one copy of the inputs for every instance makes fmi3Reset of an instance alone keep its
inputs (reset-incomplete is then a fault of its own, which the re-run alone confirms).
"""
from __future__ import annotations

import pytest

from conformance.probes.machinery.runner import ProbeOutcome, fold_consequences
from conformance.report.catalogue import default_catalogue
from conformance.report.findings import FmuReport, Violation, evidence, thaw
from conformance.run.engine import EngineOptions
from tests.checkkit import checked
from tests.fixtures import build_scene
from tests.reportkit import errors_and_warnings

WHAT = ("SHARED_VALUES", "SHARED_DERIVATIVES", "SHARED_MODE", "SHARED_INPUTS")
BY = ("1", "2", "SHARED_EVERY")
# every probe rule but the path run of DAE760/DAE761 (it judges nothing here and costs most)
SELECT = ("DAE70", "DAE71", "DAE72", "DAE73", "DAE74", "DAE75", "DAE762", "DAE80")
EXPLAINED = set(default_catalogue()["DAE762"].option_values["explains"].split())
# what the survey names as compared, by what the global holds
COMPARED = {"SHARED_VALUES": {"values"}, "SHARED_DERIVATIVES": {"derivatives"},
            "SHARED_MODE": {"mode", "values"}, "SHARED_INPUTS": {"inputs", "values"}}
OWN = {("SHARED_INPUTS", "SHARED_EVERY"): {"DAE712"}}   # faults of an instance alone too
UNREACHED = {("SHARED_MODE", "2")}                     # the writer never writes (docstring)


def _check(*defines: str, scene: str = "SimpleDAE", **options) -> FmuReport:
    """The report, once per session for each question (the consequence tests ask some of the
    family test's again)."""
    return checked(build_scene(scene, defines=list(defines)),
                   options=EngineOptions(**{"select": SELECT, **options}))


def _detail(report: FmuReport) -> str:
    return "\n".join(f"{f.code}: {f.message}" for f in report.findings)


@pytest.mark.parametrize("by", BY)
@pytest.mark.parametrize("what", WHAT)
def test_a_shared_global_is_instances_not_independent_and_nothing_else(what, by):
    report = _check(f"DEFECT_SHARED={what}", f"DEFECT_SHARED_BY={by}")
    found = errors_and_warnings(report)
    if (what, by) in UNREACHED:
        assert found == {}, _detail(report)
        return
    assert set(found) == {"DAE762"} | OWN.get((what, by), set()), _detail(report)
    ev = thaw(found["DAE762"][0].evidence)
    compared = {c["compared"].split(" ")[0] for c in ev["comparisons"]}
    assert compared & COMPARED[what], ev["comparisons"]
    for folded in ev.get("consequences", []):
        assert folded["rule"] in EXPLAINED


@pytest.mark.parametrize("what, by", [("SHARED_VALUES", "1"), ("SHARED_MODE", "SHARED_EVERY"),
                                      ("SHARED_DERIVATIVES", "1")])
def test_the_consequences_are_folded_into_the_first_cause(what, by):
    # these members trip derivative, mode or simulation rules on the process's instances
    # (DAE740, DAE747, DAE752, ...); with every instance alone those findings vanish
    report = _check(f"DEFECT_SHARED={what}", f"DEFECT_SHARED_BY={by}")
    finding = errors_and_warnings(report)["DAE762"][0]
    folded = thaw(finding.evidence)["consequences"]
    assert folded and {c["rule"] for c in folded} <= EXPLAINED
    assert not {c["rule"] for c in folded} & {f.code for f in report.findings}


@pytest.mark.parametrize("what, by", [("SHARED_VALUES", "1"), ("SHARED_MODE", "SHARED_EVERY")])
def test_without_the_first_cause_the_findings_are_their_own(what, by):
    # DAE762 not selected: nothing explains them, so the rules report what they measured
    report = _check(f"DEFECT_SHARED={what}", f"DEFECT_SHARED_BY={by}",
                    select=tuple(s for s in SELECT if s != "DAE762"))
    found = errors_and_warnings(report)
    assert "DAE762" not in found
    assert set(found) & EXPLAINED, _detail(report)


def test_a_fault_of_its_own_beside_shared_state_stays_its_own():
    # the wrong sign of d der(x1)/d x1 is wrong in an instance alone too: DAE740 reports it
    report = _check("DEFECT_SHARED=SHARED_MODE", "DEFECT_SHARED_BY=SHARED_EVERY",
                    "DEFECT_WRONG_JACOBIAN")
    found = errors_and_warnings(report)
    assert {"DAE762", "DAE740"} <= set(found), _detail(report)
    assert "DAE747" not in found


@pytest.mark.parametrize("scene", ["HelloWorldDAE", "Robertson", "EventDAE"])
def test_independent_instances_are_not_flagged(scene):
    report = _check(scene=scene)
    assert "DAE762" in report.rules_run
    assert errors_and_warnings(report) == {}, _detail(report)


def _outcome(codes: list[str]) -> ProbeOutcome:
    outcome = ProbeOutcome()
    outcome.violations = [(c, Violation(f"{c} found", evidence=evidence(k=1))) for c in codes]
    outcome.consequences = [("DAE740", Violation("d wrong", subject="d(y1)/d(x1)")),
                            ("DAE747", Violation("modes differ"))]
    return outcome


def test_fold_puts_the_consequences_into_the_first_cause():
    outcome = _outcome(["DAE713", "DAE762"])
    fold_consequences(outcome)
    assert [c for c, _ in outcome.violations] == ["DAE713", "DAE762"]
    ev = thaw(outcome.violations[1][1].evidence)
    assert ev["k"] == 1
    assert [(c["rule"], c["subject"]) for c in ev["consequences"]] == [
        ("DAE740", "d(y1)/d(x1)"), ("DAE747", None)]


def test_fold_without_the_first_cause_restores_the_findings():
    outcome = _outcome(["DAE713"])
    fold_consequences(outcome)
    assert [c for c, _ in outcome.violations] == ["DAE713", "DAE740", "DAE747"]
    assert outcome.consequences == []
