"""The result types (conformance/report/findings.py), the names of causes
(conformance/report/causes.py) and the data folders (conformance/report/paths.py)."""
from __future__ import annotations

from pathlib import Path

import pytest

from conformance.report import causes
from conformance.report.findings import (Finding, FmuReport, Location, Report, RunInfo,
                                         Severity, Violation, evidence, thaw)
from conformance.report.paths import rules_dir, schemas_dir


def test_severities_are_ordered_parsed_and_shown_in_lower_case():
    assert Severity.INFO < Severity.WARNING < Severity.ERROR
    assert [str(s) for s in Severity] == ["info", "warning", "error"]
    assert Severity.parse(" Warning ") is Severity.WARNING
    with pytest.raises(ValueError) as caught:
        Severity.parse("fatal")
    assert str(caught.value) == "unknown severity 'fatal' (use info, warning or error)"


def test_evidence_is_frozen_in_order_and_thawed_back():
    ev = evidence({"b": [1, {"c": [2, 3]}], "a": 1}, a=2, z={"k": "v"})
    assert ev == (("b", (1, (("c", (2, 3)),))), ("a", 2), ("z", (("k", "v"),)))
    hash(ev)
    assert thaw(ev) == {"b": [1, {"c": [2, 3]}], "a": 2, "z": {"k": "v"}}
    assert evidence() == () and evidence(None, x=1) == (("x", 1),)
    assert thaw(()) == [] and thaw((1, 2)) == [1, 2] and thaw("s") == "s"
    assert thaw((("k", 1), (2, 3))) == [["k", 1], [2, 3]]


def test_a_violation_fills_its_subject_in():
    assert Violation("{subject} is wrong", subject="x").text == "'x' is wrong"
    assert Violation("{subject}is wrong").text == "is wrong"


def test_findings_sort_by_file_line_column_code_message():
    def f(code, file=None, line=None, column=None, message="m"):
        return Finding(code, "n", Severity.INFO, message, Location(file, line, column))
    found = [f("DAE2", "b", 1), f("DAE1", "a", 2, 3), f("DAE1", "a", 2, 1), f("DAE3"),
             f("DAE1", "a", 2, 1, "l"), f("DAE0", "a", None)]
    assert [(x.code, x.location.file, x.location.line, x.location.column, x.message)
            for x in sorted(found, key=Finding.sort_key)] == [
        ("DAE3", None, None, None, "m"), ("DAE0", "a", None, None, "m"),
        ("DAE1", "a", 2, 1, "l"), ("DAE1", "a", 2, 1, "m"), ("DAE1", "a", 2, 3, "m"),
        ("DAE2", "b", 1, None, "m")]
    assert Location("x", 4, 2).sort_key() == ("x", 4, 2)
    assert f("DAE1").evidence_dict() == {}


def _fmu(*severities: Severity, info=()) -> FmuReport:
    return FmuReport("a.fmu", None, tuple(Finding("DAE1", "n", s, "m") for s in severities),
                     info=evidence(dict(info)))


def test_an_fmu_report_counts_by_severity_and_knows_its_worst():
    fmu = _fmu(Severity.WARNING, Severity.ERROR, Severity.WARNING)
    assert [fmu.count(s) for s in Severity] == [0, 2, 1]
    assert fmu.worst is Severity.ERROR and _fmu().worst is None
    assert _fmu(Severity.INFO).worst is Severity.INFO


def test_an_fmu_report_says_why_it_or_its_binary_was_not_checked():
    assert _fmu(info={"not_checked": "FMI 2.0 FMU"}).not_checked == "FMI 2.0 FMU"
    assert _fmu(info={"not_checked": 3}).not_checked is None and _fmu().not_checked is None
    assert _fmu(info={"probes": "not run: no binary"}).binary_not_checked == "no binary"
    assert _fmu(info={"probes": "not run"}).binary_not_checked == "not run"
    assert _fmu(info={"probes": "ran 3 probes"}).binary_not_checked is None
    assert _fmu(info={"probes": ["not run"]}).binary_not_checked is None


def test_a_report_holds_its_findings_and_its_worst():
    report = Report("1", (_fmu(Severity.WARNING), _fmu(Severity.INFO, Severity.INFO)))
    assert [f.severity for f in report.all_findings()] == [Severity.WARNING, Severity.INFO,
                                                           Severity.INFO]
    assert report.has_at_least(Severity.WARNING) and not report.has_at_least(Severity.ERROR)
    assert not report.interrupted and Report("1", (), not_checked=("b",)).interrupted
    assert RunInfo(durations=(("a", 1.5),)).duration("a") == 1.5
    assert RunInfo().duration("a") == 0.0


def test_causes_are_named_alike_by_every_check():
    assert causes.through("x") == "through 'x'"
    assert causes.entry("y", "x") == ("through 'y'", "through 'x'")
    assert causes.failing("the start state", "ODE mode") == (
        "evaluation fails in the start state, ODE mode")


def test_the_data_folders_are_those_of_the_checkout():
    """Beside the package in a checkout (``conformance/_rules`` only in a wheel)."""
    package = Path(causes.__file__).resolve().parents[1]
    assert rules_dir() == package.parent / "rules" and (rules_dir() / "core.toml").is_file()
    assert schemas_dir() == package.parent / "schemas"
    assert any(schemas_dir().glob("*.xsd"))
