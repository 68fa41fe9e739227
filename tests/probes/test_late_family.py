"""Late failures, a family (issue 20, point 3): failures after n FMI calls on one instance.

``-D DEFECT_LATE_ERROR -D DEFECT_LATE_AFTER=<n>`` (scenes/common/fmi3_framework.c) makes every FMI
call in Continuous-Time Mode after the n-th on one instance return fmi3Error;
``-D DEFECT_LATE_CALL=<function>`` restricts it to one FMI function (the failure strikes in
different calls). What finds it depends on n, and the rule docs of evaluation-fails-late (DAE760)
say so:

* n below the calls one fresh instance needs to reach a point at all (about ten): every instance
  fails at once, a fresh one too, so it is no late failure; the point probes report the call
  that fails (evaluation-failed, directional-derivative-mismatch, ...), never a clean report;
* n within the path run's budget (``calls_<level>``) and beyond what the point probes make on one
  instance (at most about 2,000): evaluation-fails-late, naming the call;
* n beyond the budget (10^6 at quick, whose budget is 50,000 calls): nobody's finding, the
  limit the rule docs state; the arithmetic is tested with small budgets, since the long
  level's 2,000,000 calls do not fit its wall-clock safety net on a loaded 2-core machine.
"""
from __future__ import annotations

import dataclasses

import pytest

from conformance.report.catalogue import Catalogue, default_catalogue
from conformance.report.findings import FmuReport, Severity, thaw
from conformance.run.engine import EngineOptions, check_fmu
from tests.fixtures import build_scene
from tests.reportkit import errors_and_warnings

BUDGET = default_catalogue()["evaluation-fails-late"].option_values


def _check(n: int, call: str = "", *, catalogue: Catalogue | None = None,
           **options) -> FmuReport:
    defines = ["DEFECT_LATE_ERROR", f"DEFECT_LATE_AFTER={n}"]
    if call:
        defines.append(f"DEFECT_LATE_CALL={call}")
    return check_fmu(build_scene("HelloWorldDAE", defines=defines), catalogue=catalogue,
                     options=EngineOptions(**options))


def _found(report: FmuReport) -> dict[str, list]:
    """The errors and warnings, and evaluation-fails-late at any severity: it is information
    since issue 29 (no text requires a call to keep working after many: advice)."""
    found = errors_and_warnings(report)
    late = [f for f in report.findings if f.code == "DAE760"]
    if late:
        found["DAE760"] = late
    return found


def _detail(report: FmuReport) -> str:
    return "\n".join(f"{f.code}: {f.message}" for f in report.findings) + "\n" + "\n".join(
        f"not run {c}: {why}" for c, why in report.rules_not_run)


def _budget(calls: int) -> Catalogue:
    rules = []
    for rule in default_catalogue():
        if rule.code == "DAE760":
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, "calls_quick": calls}.items())))
        rules.append(rule)
    return Catalogue(rules)


@pytest.mark.parametrize("call", ["", "fmi3GetFloat64", "fmi3GetDirectionalDerivative",
                                  "fmi3GetContinuousStateDerivatives"])
def test_a_failure_after_ten_calls_is_the_point_probes_finding(call):
    report = _check(10, call, select=("DAE7",))     # the point probes and the endurance ones
    found = _found(report)
    assert found, _detail(report)
    # a fresh instance fails as early: no failure that comes with use
    assert "DAE760" not in found


CALLS = ["fmi3GetFloat64", "fmi3SetFloat64", "fmi3SetTime", "fmi3SetContinuousStates",
         "fmi3GetContinuousStateDerivatives", "fmi3GetDirectionalDerivative"]


@pytest.mark.parametrize("call", CALLS)
def test_a_failure_within_the_budget_is_evaluation_fails_late_in_every_call(call):
    n = 10_000      # beyond the point probes' calls on one instance, within quick's 50,000
    report = _check(n, call, select=("DAE7",))
    found = _found(report)
    assert set(found) == {"DAE760"}, _detail(report)
    finding = found["DAE760"][0]
    assert finding.subject == call and finding.severity == Severity.INFO
    ev = thaw(finding.evidence)
    assert ev["calls_before"] >= n - 200      # the path instance's own calls, not a fresh one's
    assert ev["fresh_instance"] == "ok"


def test_a_failure_after_a_million_calls_is_beyond_the_quick_budget():
    report = _check(1_000_000, "fmi3GetFloat64", select=("DAE76",))
    assert _found(report) == {}, _detail(report)
    info = thaw(report.info)["endurance"]
    assert info["budget_calls"] <= BUDGET["calls_quick"] < 1_000_000
    assert info["path_calls"] < info["budget_calls"] + 10 < 1_000_000   # a step may end past it


@pytest.mark.parametrize("budget, found", [(2_000, False), (6_000, True)])
def test_the_budget_decides_which_late_failures_are_reached(budget, found):
    # n = 3,000: a budget of 2,000 calls cannot reach it, one of 6,000 does; the same
    # arithmetic puts 10^6 beyond quick (50,000) and within long (2,000,000) when the long
    # run is not stopped by its wall-clock safety net first
    report = _check(3_000, "fmi3GetFloat64", catalogue=_budget(budget), select=("DAE76",))
    assert ("DAE760" in _found(report)) is found, _detail(report)
    info = thaw(report.info)["endurance"]
    assert info["budget_calls"] == budget
