"""The JSON report field by field: the keys and values other tools read (docs/json-report.md)."""
from __future__ import annotations

import json
import math

from conformance.report.findings import Report, evidence
from conformance.reporters import json_report
from tests.reporters.samples import MANIFEST, SAMPLE_CATALOGUE, sample_report


def test_a_finding_has_every_field_with_its_exact_value():
    f = sample_report().fmus[0].findings[1]   # DAE203 at modelDescription.xml:12
    assert json_report.finding_dict(f, SAMPLE_CATALOGUE) == {
        "code": "DAE203", "name": "enable-parameter-not-boolean", "severity": "error",
        "message": "enable parameter 'dae' is a <Float64>, not a <Boolean>",
        "file": "modelDescription.xml", "line": 12, "column": None,
        "path": "/fmiModelDescription/ModelVariables/Float64[@name='dae']",
        "subject": "dae", "count": 1, "evidence": {"value_reference": 1, "type": "Float64"},
        "fix": None,
    }


def test_a_grouped_finding_keeps_its_count_and_lists():
    f = sample_report().fmus[0].findings[2]
    out = json_report.finding_dict(f, SAMPLE_CATALOGUE, snippet=True)
    assert (out["file"], out["line"], out["count"]) == (MANIFEST, 7, 4)
    assert out["evidence"] == {"count": 4, "subjects": ["w1", "w2", "w3", "w4"],
                               "lines": [7, 8, 9, 10]}
    assert out["snippet"] == '  <AlgebraicVariable valueReference="91"/>'


def test_fmu_has_its_summary_info_and_rules_and_no_snippets_unless_asked():
    fmu = sample_report().fmus[0]
    out = json_report.fmu_dict(fmu, SAMPLE_CATALOGUE)
    assert out["path"] == "models/Broken.fmu"
    assert out["draft"] == "formulation"
    assert out["summary"] == {"error": 4, "warning": 1, "info": 0}
    assert out["info"] == {"model_name": "Broken", "fmi_version": "3.0", "variables": 9,
                           "jacobian": {"rows": ["g1"]}}
    assert out["rules_run"] == ["DAE021", "DAE201", "DAE203", "DAE301"]
    assert out["rules_skipped"] == [{"code": "DAE701",
                                     "reason": "probes turned off (--no-probes)"}]
    assert out["rules_not_run"] == []
    assert all("snippet" not in f for f in out["findings"])
    with_snippets = json_report.fmu_dict(fmu, SAMPLE_CATALOGUE, snippets=True)
    assert [f["snippet"] for f in with_snippets["findings"]][:2] == [
        "<fmiLayeredStandardManifest>", '    <Float64 name="dae" valueReference="1"/>']


def test_report_options_interruption_and_shard():
    report = sample_report()
    out = json.loads(json_report.render(report, SAMPLE_CATALOGUE))
    assert (out["tool"], out["version"], out["schema_version"]) == ("lsdae", "9.9.9", 1)
    assert out["options"] == {"draft": "auto", "probes": False}
    assert "interrupted" not in out and "shard" not in out
    assert all("snippet" not in f for fmu in out["fmus"] for f in fmu["findings"])
    sharded = Report(report.tool_version, report.fmus[:1], report.options,
                     not_checked=("models/Later.fmu",),
                     shard=evidence(index=1, total=3, inputs=["a.fmu", "b.fmu"]))
    out = json.loads(json_report.render(sharded, SAMPLE_CATALOGUE))
    assert out["interrupted"] == {"not_checked": ["models/Later.fmu"]}
    assert out["shard"] == {"index": 1, "total": 3, "inputs": ["a.fmu", "b.fmu"]}
    assert out["fmus"][0]["findings"][0]["snippet"] == "<fmiLayeredStandardManifest>"


def test_non_finite_numbers_are_strings():
    assert json_report.plain(evidence(a=math.inf, b=[1.0, -math.inf], c={"d": math.nan})) == {
        "a": "inf", "b": [1.0, "-inf"], "c": {"d": "nan"}}
