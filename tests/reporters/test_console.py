"""Console output: compiler-style diagnostics; measured findings show their numbers."""
from __future__ import annotations

import shutil
import zipfile

import pytest

from conformance.report.catalogue import default_catalogue
from conformance.run.engine import EngineOptions, check_paths
from conformance.report.findings import (Finding, FmuReport, Location, Report, Severity,
                                         evidence)
from conformance.reporters.console import EVIDENCE_ITEMS, render
from tests.reporters.samples import SAMPLE_CATALOGUE, sample_report
from tests.scenes.test_corpus import corpus_fmu

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
# --- the manifest-missing finding is worded true for the FMU's interface types (issue 8) ------

@pytest.mark.parametrize("name, kinds", [
    ("CoSimulationOnly", "a Co-Simulation FMU"),
    ("ScheduledExecutionOnly", "a Scheduled Execution FMU"),
    ("ModelExchangeEvents", "a Model Exchange FMU"),
    ("StartTime", "a Model Exchange and Co-Simulation FMU"),
])
def test_manifest_missing_names_the_interface_types(name, kinds):
    text = render(check_paths([corpus_fmu(name)], options=EngineOptions(probes=False)))
    assert f"{kinds} that does not use the DAE layer" in text
    assert "ordinary Model Exchange" not in text


def test_manifest_missing_names_what_declares_the_layer(tmp_path):
    fmu = tmp_path / "Declared.fmu"
    shutil.copyfile(corpus_fmu("CoSimulationOnly"), fmu)
    with zipfile.ZipFile(fmu, "a") as zf:
        zf.writestr("extra/org.fmi-standard.fmi-ls-dae/README.txt", "the manifest is coming")
    text = render(check_paths([fmu], options=EngineOptions(probes=False)))
    assert ("although extra/org.fmi-standard.fmi-ls-dae/README.txt declares the fmi-ls-dae "
            "layer") in text


# --- exact lines: the summary a user reads, and the evidence values as printed -------------

def test_evidence_values_nested_in_lists_and_long_values_are_cut():
    text = render(_report(_finding("directional-derivative-mismatch",
                                   points=[{"t": 0.5, "x": 1}, [1, 2]], long="x" * 150)),
                  CATALOGUE)
    assert "      points: [(t=0.5, x=1), [1, 2]]\n" in text
    assert f"      long: {'x' * 99}…\n" in text


def test_summary_lines_name_the_draft_counts_and_unchecked_binaries():
    warning = Finding("DAE021", "legacy-draft-shape", Severity.WARNING, "w", Location())
    probed = FmuReport(path="a.fmu", draft=None, findings=(warning,),
                       info=evidence(manifest="0.1"))
    unprobed = FmuReport(path="b.fmu", draft="alpha1", findings=(),
                         info=evidence(probes="not run: no binary"))
    plain = FmuReport(path="c.fmu", draft=None, findings=())
    lines = render(Report("0", (probed, unprobed, plain))).splitlines()
    assert "a.fmu: fmi-ls-dae manifest 0.1; 0 errors, 1 warning, 0 info" in lines
    assert "c.fmu: no fmi-ls-dae manifest; 0 errors, 0 warnings, 0 info" in lines
    assert lines[-1] == ("checked 3 FMUs: 0 errors, 1 warning; "
                         "the binary of 1 FMU was not checked")


def test_an_interrupted_run_names_the_first_fmus_not_checked():
    report = Report("0", (), not_checked=("a.fmu", "b.fmu", "c.fmu", "d.fmu"))
    assert render(report).splitlines()[-1] == \
        "interrupted: 4 FMUs not checked (a.fmu, b.fmu, c.fmu, …)"
