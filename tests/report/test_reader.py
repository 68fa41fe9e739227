"""The JSON report read back (conformance/report/reader.py) is the report that was written."""
from __future__ import annotations

import json
from dataclasses import replace

import pytest

from conformance.run.engine import EngineOptions, check_paths
from conformance.report.findings import evidence
from conformance.report.reader import SCHEMA_VERSION, ReportFormatError, read_report
from conformance.reporters import REPORTER_BY_NAME, json_report


@pytest.fixture(scope="module")
def report(fixture_fmus, scene_fmus):
    """Every rule fixture and the scenes, statically: every kind of evidence and info."""
    return check_paths([*fixture_fmus, *scene_fmus], options=EngineOptions(probes=False))


def test_a_report_read_back_renders_the_same_in_every_format(report):
    shard = replace(report, shard=evidence(index=1, count=1, positions=[0, 1]))
    text = json_report.render(shard)
    again = read_report(json.loads(text))
    assert json_report.render(again) == text            # snippets and shard section included
    assert again.shard == shard.shard
    assert any(f.location.snippet for f in again.all_findings())
    plain = replace(again, shard=())
    for name, render in REPORTER_BY_NAME.items():
        assert render(plain, color=False) == render(report, color=False), name


def test_an_ordinary_report_has_no_shard_section_nor_snippets(report):
    data = json.loads(json_report.render(report))
    assert "shard" not in data
    assert all("snippet" not in f for fmu in data["fmus"] for f in fmu["findings"])


def test_the_reader_reads_the_version_the_reporter_writes():
    assert SCHEMA_VERSION == json_report.SCHEMA_VERSION


def test_non_finite_evidence_comes_back_as_floats():
    data = {"tool": "lsdae", "version": "0", "schema_version": SCHEMA_VERSION, "options": {},
            "fmus": [{"path": "a", "draft": None, "info": {"x": ["nan", 1]},
                      "findings": [{"code": "DAE1", "name": "n", "severity": "error",
                                    "message": "m", "file": None, "line": None, "column": None,
                                    "path": None, "subject": None, "count": 1,
                                    "evidence": {"error": "inf", "tolerance": "-inf"}}],
                      "rules_run": [], "rules_skipped": []}]}
    report = read_report(data)
    assert dict(report.fmus[0].findings[0].evidence) == {"error": float("inf"),
                                                        "tolerance": float("-inf")}
    nan = dict(report.fmus[0].info)["x"][0]
    assert isinstance(nan, float) and nan != nan


@pytest.mark.parametrize("data", [
    [], {"tool": "other"}, {"tool": "lsdae", "schema_version": 9},
    {"tool": "lsdae", "schema_version": 1, "version": "x"},
    {"tool": "lsdae", "schema_version": 1, "version": "x", "fmus": [{"path": 3}]},
    {"tool": "lsdae", "schema_version": 1, "version": "x", "fmus": {}},
    {"tool": "lsdae", "schema_version": 1, "version": "x", "fmus": [
        {"path": "a", "draft": None, "findings": [{"code": "X"}], "rules_run": [],
         "rules_skipped": []}]},
    {"tool": "lsdae", "schema_version": 1, "version": "x", "fmus": [
        {"path": "a", "draft": None, "findings": [], "rules_run": [],
         "rules_skipped": [{"code": "X"}]}]},
])
def test_the_reader_refuses_what_is_not_a_report(data):
    with pytest.raises(ReportFormatError):
        read_report(data)


def _fmu_data(**changes):
    fmu = {"path": "a", "draft": "alpha1", "info": {}, "rules_run": ["DAE101"],
           "rules_skipped": [{"code": "DAE2", "reason": "r"}],
           "rules_not_run": [{"code": "DAE3", "reason": "budget"}],
           "findings": [{"code": "DAE1", "name": "n", "severity": "warning", "message": "m",
                         "file": "f.xml", "line": 3, "column": 4, "path": "/a",
                         "subject": "s", "count": 2, "part": "p"}]}
    fmu.update(changes)
    return fmu


def _data(**changes):
    data = {"tool": "lsdae", "version": "0.1", "schema_version": SCHEMA_VERSION,
            "options": {"seed": 1}, "fmus": [_fmu_data()],
            "interrupted": {"not_checked": ["b", "c"]}}
    data.update(changes)
    return data


def test_every_field_of_a_report_is_read_back():
    from conformance.report.findings import Finding, FmuReport, Location, Report, Severity

    report = read_report(_data())
    assert report == Report(
        tool_version="0.1", options=(("seed", 1),), not_checked=("b", "c"), fmus=(FmuReport(
            path="a", draft="alpha1", rules_run=("DAE101",), rules_skipped=(("DAE2", "r"),),
            rules_not_run=(("DAE3", "budget"),), findings=(Finding(
                code="DAE1", name="n", severity=Severity.WARNING, message="m",
                location=Location(file="f.xml", line=3, column=4, path="/a"), subject="s",
                count=2, part="p"),)),))
    plain = read_report(_data(interrupted=None))
    assert plain.not_checked == () and not plain.interrupted
    old = dict(_fmu_data())
    del old["rules_not_run"]
    old["findings"][0]["part"] = None
    del old["info"]
    fmu = read_report(_data(fmus=[old], options=None)).fmus[0]
    assert fmu.rules_not_run == () and fmu.findings[0].part is None and fmu.info == ()
    assert read_report(_data(options=None)).options == ()


@pytest.mark.parametrize("changes, says", [
    ({"fmus": {}}, "fmus is not a list"),
    ({"fmus": [3]}, "fmus[] is not an object"),
    ({"version": 1}, "version is not a string"),
    ({"options": [1]}, "options is not an object"),
    ({"shard": [1]}, "shard is not an object"),
    ({"interrupted": {"not_checked": "b"}}, "not_checked is not a list"),
    ({"interrupted": {"not_checked": [1]}}, "not_checked is not a string"),
    ({"fmus": [_fmu_data(path=1)]}, "path is not a string"),
    ({"fmus": [_fmu_data(findings={})]}, "findings is not a list"),
    ({"fmus": [_fmu_data(findings=[1])]}, "findings[] is not an object"),
    ({"fmus": [_fmu_data(rules_run={})]}, "rules_run is not a list"),
    ({"fmus": [_fmu_data(rules_run=[1])]}, "rules_run is not a string"),
    ({"fmus": [_fmu_data(rules_skipped={})]}, "rules_skipped is not a list"),
    ({"fmus": [_fmu_data(rules_skipped=[{"code": 1, "reason": "r"}])]},
     "rules_skipped is not a string"),
    ({"fmus": [_fmu_data(rules_not_run=[{"code": "X", "reason": 2}])]},
     "rules_not_run is not a string"),
    ({"fmus": [_fmu_data(info=[1])]}, "info is not an object"),
])
def test_what_is_wrong_in_a_report_is_named(changes, says):
    with pytest.raises(ReportFormatError) as caught:
        read_report(_data(**changes))
    assert str(caught.value) == f"not an lsdae JSON report: {says}"


@pytest.mark.parametrize("key, value", [("code", 1), ("name", 1), ("severity", 1),
                                        ("message", 1), ("part", 1), ("evidence", [1])])
def test_what_is_wrong_in_a_finding_is_named(key, value):
    fmu = _fmu_data()
    fmu["findings"][0][key] = value
    with pytest.raises(ReportFormatError) as caught:
        read_report(_data(fmus=[fmu]))
    assert str(caught.value) == (f"not an lsdae JSON report: {key} is not "
                                 f"{'an object' if key == 'evidence' else 'a string'}")


def test_a_missing_field_is_named_with_its_error():
    fmu = _fmu_data()
    del fmu["findings"][0]["subject"]
    with pytest.raises(ReportFormatError) as caught:
        read_report(_data(fmus=[fmu]))
    assert str(caught.value) == "not an lsdae JSON report: KeyError: 'subject'"
    with pytest.raises(ReportFormatError) as caught:
        read_report({"tool": "lsdae", "schema_version": 3})
    assert str(caught.value) == "JSON report schema version 3; this lsdae reads version 1"
    with pytest.raises(ReportFormatError) as caught:
        read_report({"TOOL": "lsdae"})
    assert str(caught.value) == 'not an lsdae JSON report (no "tool": "lsdae")'
