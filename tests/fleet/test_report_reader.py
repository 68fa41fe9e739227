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
