"""The stages of one check (conformance/run/engine.py, conformance/run/reading.py) on small FMU
folders, with the probe runner replaced: what an FMI 2.0 FMU, an FMU without a manifest, a
failing stage and a probe outcome leave in the report."""
from __future__ import annotations

import logging
from pathlib import Path

import pytest

from conformance.probes.machinery import runner
from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Location, Severity, Violation, evidence
from conformance.run import engine, source_texts
from conformance.run.engine import EngineOptions, check_fmu, check_paths
from conformance.run.reading import RunState
from conformance.intake.fmu import ArchiveLimits
from tests.fixtures import make_fmu

CATALOGUE = default_catalogue()
STATIC = EngineOptions(probes=False)


def _fmi2(root: Path, *, layer: bool) -> Path:
    make_fmu(root, manifest=layer)
    md = root / "modelDescription.xml"
    md.write_text(md.read_text().replace('fmiVersion="3.0"', 'fmiVersion="2.0"'))
    return root


@pytest.mark.parametrize("layer", [False, True])
def test_an_fmi2_fmu_is_one_finding_and_nothing_else_is_checked(tmp_path, layer):
    report = check_fmu(_fmi2(tmp_path / "a", layer=layer), options=STATIC)
    (finding,) = report.findings
    assert (finding.name, finding.part) == ("fmi-version-unsupported",
                                            "fmi2-with-dae-layer" if layer else None)
    assert finding.message == ("an FMI 2.0 FMU: fmi-ls-dae is a layered standard of FMI 3.0, "
                               "so this FMU is not checked")
    assert finding.location == Location(file="modelDescription.xml", line=2,
                                        path="/fmiModelDescription",
                                        snippet="<fmiModelDescription")
    assert dict(finding.evidence) == {"fmi_version": "2.0"}
    reason = "FMI 2.0 FMU: fmi-ls-dae needs FMI 3.0"
    assert report.not_checked == reason and dict(report.info)["not_checked"] == reason
    assert report.rules_run == ()
    skipped = {code for code, why in report.rules_skipped if why == reason}
    assert skipped == {r.code for r in CATALOGUE if r.stage != "archive"}
    assert all(why == reason for _, why in report.rules_skipped)


def test_a_static_check_says_what_it_read_and_why_the_probes_did_not_run(tmp_path):
    path = make_fmu(tmp_path / "a")
    report = check_fmu(path, options=STATIC)
    assert report.path == str(path) and report.draft == "alpha1"
    info = dict(report.info)
    assert (info["model_name"], info["fmi_version"]) == ("HelloWorldDAE", "3.0")
    assert info["variables"] > 0
    assert info["probes"] == "not run: probes turned off (--no-probes)"
    assert report.binary_not_checked == "probes turned off (--no-probes)"
    assert ("DAE740", "probes turned off (--no-probes)") in report.rules_skipped
    assert "DAE101" in report.rules_run
    shown = check_fmu(path, options=STATIC, display_path="shown.fmu")
    assert shown.path == "shown.fmu" and shown.findings == report.findings


def test_only_the_probes_of_an_fmu_skip_the_static_rules(tmp_path):
    path = make_fmu(tmp_path / "a")
    report = check_fmu(path, options=EngineOptions(probes=False, probes_only=True))
    assert [f.name for f in report.findings if f.name == "internal-error"] == []
    assert report.rules_run == () and report.draft == "alpha1"
    assert dict(report.info)["model_name"] == "HelloWorldDAE"


def test_the_report_of_many_paths_records_the_options(tmp_path):
    a, b = make_fmu(tmp_path / "a"), make_fmu(tmp_path / "b", manifest=False)
    durations: dict[str, float] = {}
    options = EngineOptions(probes=False, select=("DAE0", "DAE1"), ignore=("DAE101",),
                            severity=(("DAE091", "error"),), seed=4)
    report = check_paths([a, str(b)], options=options, durations=durations)
    assert [f.path for f in report.fmus] == [str(a), str(b)]
    assert set(durations) == {str(a), str(b)} and all(s > 0 for s in durations.values())
    assert dict(report.options) == {"draft": "auto", "select": ("DAE0", "DAE1"),
                                    "ignore": ("DAE101",), "severity": ("DAE091=error",),
                                    "probes": False, "probes_only": False, "seed": 4}
    assert [(f.code, f.severity) for f in report.fmus[1].findings] == [("DAE091",
                                                                      Severity.ERROR)]


def test_a_failure_of_ours_keeps_the_report_and_says_the_manifest_was_not_checked(
        tmp_path, monkeypatch, caplog):
    def broken(*args, **kw):
        raise RuntimeError("boom")

    monkeypatch.setattr(engine, "read_manifest_file", broken)
    caplog.set_level(logging.DEBUG, logger="conformance.run.engine")
    path = make_fmu(tmp_path / "a")
    report = check_fmu(path, options=STATIC)
    (finding,) = [f for f in report.findings if f.name == "internal-error"]
    assert finding.message.startswith("lsdae failed while checking this FMU: RuntimeError: boom")
    assert dict(finding.evidence) == {"exception": "RuntimeError"}
    assert dict(report.info)["manifest"] == ("present, not checked: lsdae failed (see the "
                                             "internal-error finding)")
    assert f"internal error while checking {path}" in caplog.messages
    without = check_fmu(make_fmu(tmp_path / "b", manifest=False), options=STATIC)
    assert "manifest" not in dict(without.info)


def test_the_probe_stage_gets_its_rules_and_merges_the_outcome(tmp_path, monkeypatch):
    calls = []

    def fake(source, ctx, rules, *, seed, endurance, workers):
        calls.append(([r.code for r in rules], seed, endurance, workers))
        return runner.ProbeOutcome(
            violations=[("DAE740", Violation("{subject} is wrong", subject="d(a)/d(b)"))],
            run={"DAE740"}, skipped={("DAE741", "budget")}, not_run={("DAE741", "budget")},
            info={"probes": "ran", "lanes": 2})

    monkeypatch.setattr(runner, "run_probes", fake)
    options = EngineOptions(select=("DAE740", "DAE741", "DAE101"), seed=7, endurance="off",
                            probe_workers=2)
    report = check_fmu(make_fmu(tmp_path / "a"), options=options)
    assert calls == [(["DAE740", "DAE741"], 7, "off", 2)]
    assert [(f.code, f.message) for f in report.findings] == [("DAE740", "'d(a)/d(b)' is wrong")]
    assert report.rules_run == ("DAE101", "DAE740")
    assert report.rules_skipped == (("DAE741", "budget"),)
    assert report.rules_not_run == (("DAE741", "budget"),)
    assert dict(report.info)["probes"] == "ran" and dict(report.info)["lanes"] == 2


def test_a_rule_is_skipped_for_what_is_missing_or_unread():
    state = RunState()
    assert state.skip_for("DAE1", ("manifest",), {"manifest": False}, "no manifest") == (
        "no manifest")
    state.unread["manifest"] = "the manifest cannot be read or parsed"
    state.unread["binary"] = "not read"
    have = {"manifest": False, "model-description": True, "binary": True}
    assert state.skip_for("DAE2", ("model-description", "binary", "manifest"), have,
                          "no manifest") == "the manifest cannot be read or parsed"
    assert state.skip_for("DAE3", ("binary",), have, "other") == "other"
    assert state.skipped == {("DAE1", "no manifest"),
                             ("DAE2", "the manifest cannot be read or parsed"),
                             ("DAE3", "other")}
    assert state.not_run == {("DAE2", "the manifest cannot be read or parsed")}


def test_a_large_file_read_again_that_fails_has_no_lines(tmp_path, monkeypatch, caplog):
    def gone(*args, **kw):
        raise OSError("vanished")

    limits = ArchiveLimits.from_options(CATALOGUE["archive-too-large"].option_values)
    texts = source_texts.SourceTexts(tmp_path / "a.fmu", limits)
    texts.keep("big.xml", b"x" * (source_texts.KEEP_BYTES + 1))
    texts.keep("small.xml", b"<a/>")
    monkeypatch.setattr(source_texts, "open_fmu", gone)
    caplog.set_level(logging.DEBUG, logger="conformance.run.source_texts")
    assert texts.get("big.xml") is None and texts.get("small.xml") == b"<a/>"
    assert caplog.messages == ["cannot read big.xml again for its source lines"]


def test_an_fmu_without_a_model_description_or_that_cannot_be_opened(tmp_path):
    path = make_fmu(tmp_path / "a")
    (path / "modelDescription.xml").unlink()
    report = check_fmu(path, options=STATIC)
    names = {f.name for f in report.findings}
    assert "model-description-missing" in names and "internal-error" not in names
    assert "model_name" not in dict(report.info)
    gone = check_fmu(tmp_path / "missing.fmu", options=STATIC)
    assert dict(gone.info) == {"manifest": "not read: the FMU could not be opened"}
    assert gone.rules_run == () and "internal-error" not in {f.name for f in gone.findings}
