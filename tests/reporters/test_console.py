"""Console output: compiler-style diagnostics; measured findings show their numbers."""
from __future__ import annotations

from conformance.catalogue import default_catalogue
from conformance.findings import Finding, FmuReport, Location, Report, Severity, evidence
from conformance.reporters.console import EVIDENCE_ITEMS, render
from tests.reporters.samples import SAMPLE_CATALOGUE, sample_report

CATALOGUE = default_catalogue()


def _report(*findings: Finding) -> Report:
    return Report(tool_version="0", fmus=(FmuReport(path="m.fmu", draft="alpha1",
                                                    findings=findings),))


def _finding(name: str, **ev) -> Finding:
    rule = CATALOGUE[name]
    return Finding(rule.code, rule.name, rule.severity, "something is off",
                   Location(file="modelDescription.xml", line=3, snippet="<Float64 .../>"),
                   evidence(ev))


def test_probe_finding_shows_its_evidence_with_nested_values():
    text = render(_report(_finding("directional-derivative-mismatch", fmu=-0.5,
                                   finite_difference=0.5, tolerance=1e-6,
                                   point={"t": 0.0, "values": {"x": 1.0}})), CATALOGUE)
    assert "= evidence:" in text
    assert "finite_difference: 0.5" in text and "point: t=0, values=(x=1)" in text


def test_static_finding_keeps_its_evidence_in_json_only():
    text = render(_report(_finding("enable-parameter-not-boolean", type="Float64")), CATALOGUE)
    assert "= evidence:" not in text and "--> m.fmu!modelDescription.xml:3" in text


def test_long_evidence_is_capped():
    many = {f"k{i}": i for i in range(EVIDENCE_ITEMS + 5)}
    text = render(_report(_finding("nan-or-inf", **many)), CATALOGUE)
    assert "… 5 more in the JSON report" in text


def test_colour_only_when_asked():
    report = _report(_finding("nan-or-inf", value=float("nan")))
    assert "\033[" not in render(report, CATALOGUE)
    assert "\033[" in render(report, CATALOGUE, color=True)


def test_rules_that_could_not_run_are_listed_and_counted():
    text = render(sample_report(), SAMPLE_CATALOGUE)
    block = text[text.index("models/Crashy.fmu"):]
    assert "not run: DAE720" in block and "the worker failed before the probes could run" in block
    assert "1 rule not run" in block
    assert text.rstrip().splitlines()[-1].count("1 rule not run") == 1
