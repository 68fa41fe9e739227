"""Engine behaviour: selection, severity overrides, grouping, skipping, internal errors."""
from __future__ import annotations

import dataclasses

import pytest

from conformance.run import engine
from conformance.report.catalogue import Catalogue, default_catalogue
from conformance.checks import REGISTRY
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Severity, Violation
from conformance.model.layer import NOT_A_DAE_FMU
from tests.fixtures import Case, materialise, zip_scene


def _scene(tmp_path, **spec):
    (tmp_path / "spec").mkdir()
    case = Case("TEST", "pass", tmp_path / "spec", {"base": "HelloWorldDAE", **spec})
    return materialise(case, tmp_path)


def test_internal_error_is_a_finding(tmp_path, monkeypatch):
    code = sorted(REGISTRY)[0]

    def broken(ctx, **_):
        raise ZeroDivisionError("boom")
        yield  # pragma: no cover

    monkeypatch.setitem(engine.REGISTRY, code, broken)
    report = check_fmu(_scene(tmp_path), options=EngineOptions(probes=False))
    errors = [f for f in report.findings if f.name == "internal-error"]
    assert len(errors) == 1 and dict(errors[0].evidence)["rule"] == code
    assert code in report.rules_run  # the other rules still ran
    assert len(report.rules_run) > 1


def test_missing_manifest_skips_dae_rules_not_fails(tmp_path):
    report = check_fmu(_scene(tmp_path, remove=["manifest"]), options=EngineOptions(probes=False))
    assert {f.code for f in report.findings} == {"DAE091"}
    assert report.rules_skipped, "DAE rules should be listed as skipped"
    # the layer's rules do not apply; the ODE-mode probes would, but the probes are off
    assert {reason for _, reason in report.rules_skipped} == {
        NOT_A_DAE_FMU, "probes turned off (--no-probes)"}
    catalogue = default_catalogue()
    for code, reason in report.rules_skipped:
        layer = bool({"manifest", "dae-layer"} & set(catalogue[code].needs))
        assert (reason == NOT_A_DAE_FMU) == layer, code


def test_grouping_many_identical_violations(tmp_path, monkeypatch):
    code = sorted(REGISTRY)[0]

    def many(ctx, **_):
        for i in range(200):
            yield Violation("variable {subject} is odd", subject=f"v{i}")

    monkeypatch.setitem(engine.REGISTRY, code, many)
    report = check_fmu(_scene(tmp_path), options=EngineOptions(probes=False, select=(code,)))
    assert len(report.findings) == 1
    finding = report.findings[0]
    assert finding.count == 200
    assert dict(finding.evidence)["subjects"][:2] == ("v0", "v1")


def test_select_ignore_and_severity_override(tmp_path):
    path = _scene(tmp_path, remove=["manifest"])
    ignored = check_fmu(path, options=EngineOptions(probes=False, ignore=("manifest-missing",)))
    assert ignored.findings == ()
    raised = check_fmu(path, options=EngineOptions(probes=False,
                                                   severity=(("DAE091", "error"),)))
    assert [f.severity for f in raised.findings] == [Severity.ERROR]


def test_unknown_selection_is_a_usage_error(tmp_path):
    with pytest.raises(ValueError):
        engine.check_paths([_scene(tmp_path)], options=EngineOptions(select=("NOPE999",)))


def test_report_is_deterministic(tmp_path):
    path = _scene(tmp_path)
    a = check_fmu(path, options=EngineOptions(probes=False))
    b = check_fmu(path, options=EngineOptions(probes=False))
    assert a == b


def test_findings_point_at_the_line_where_a_multi_line_start_tag_begins(tmp_path):
    # The scene's root element spreads its attributes over several lines; a header finding
    # must point at `<fmiDAEManifest`, not at the line where libxml2 says the tag ends.
    path = _scene(tmp_path, edit=[{"file": "manifest", "old": 'fmi-ls:fmi-ls-version="1.0.0-alpha.1"',
                                   "new": 'fmi-ls:fmi-ls-version=""'}])
    report = check_fmu(path, options=EngineOptions(probes=False))
    [finding] = [f for f in report.findings if f.name == "ls-version-invalid"]
    assert finding.location.snippet.lstrip().startswith("<fmiDAEManifest")
    manifest = (path / "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml").read_text()
    assert manifest.splitlines()[finding.location.line - 1].lstrip().startswith("<fmiDAEManifest")


def test_unicode_digits_in_value_references_are_findings_not_crashes(tmp_path):
    # str.isdigit() accepts '²' but int() refuses it: such a value must read as "not an
    # unsigned integer" (a schema and an unknown-vr finding), never as an internal error.
    path = _scene(tmp_path, edit=[{"file": "manifest", "old": '<AlgebraicVariable valueReference="4"/>',
                                   "new": '<AlgebraicVariable valueReference="\u00b2"/>'}])
    report = check_fmu(path, options=EngineOptions(probes=False))
    names = {f.name for f in report.findings}
    assert "internal-error" not in names and "algebraic-unknown-vr" in names


def _small_members(limit: int):
    """The default catalogue with archive-too-large's max_member set to ``limit`` bytes."""
    rules = []
    for rule in default_catalogue():
        if rule.name == "archive-too-large":
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, "max_member": limit}.items())))
        rules.append(rule)
    return Catalogue(rules)


def test_a_file_left_out_by_an_archive_limit_is_not_read_not_missing(tmp_path):
    """modelDescription.xml over the size limit: archive-too-large, and the file is "not read
    because of" it -- not model-description-missing; the rules that need it say so."""
    fmu = zip_scene("HelloWorldDAE", tmp_path / "big.fmu")
    report = engine.check_fmu(fmu, options=engine.EngineOptions(probes=False),
                              catalogue=_small_members(1500))
    names = {f.name for f in report.findings}
    assert "archive-too-large" in names
    assert "model-description-missing" not in names
    info = dict(report.info)
    assert info["modelDescription"] == "not read because of archive-too-large"
    reasons = dict(report.rules_skipped)
    assert reasons["DAE501"] == "modelDescription.xml not read because of archive-too-large"


def test_a_reader_that_fails_never_calls_a_present_manifest_absent(tmp_path, monkeypatch):
    """When lsdae itself fails before the manifest is read, the summary says the manifest is
    there and not checked, and the console never says "no fmi-ls-dae manifest"."""
    from conformance.report.findings import Report
    from conformance.reporters import console

    def broken(*_args, **_kwargs):
        raise RecursionError("deep")

    from conformance.run import reading

    monkeypatch.setattr(reading, "detect_draft", broken)  # fails before the draft is known
    report = check_fmu(_scene(tmp_path), options=EngineOptions(probes=False))
    assert "internal-error" in {f.name for f in report.findings}
    assert dict(report.info)["manifest"].startswith("present, not checked")
    text = console.render(Report(tool_version="1", fmus=(report,)))
    assert "no fmi-ls-dae manifest" not in text


def test_an_fmi2_fmu_is_one_warning_and_not_checked(tmp_path, capsys):
    """An FMI 2.0 FMU: fmi-version-unsupported once, no schema noise, every other rule skipped
    with the reason, exit 0 under the default --fail-on, and "not checked" in the summary."""
    from conformance.commands.cli import main
    from tests.fixtures import all_cases

    case = next(c for c in all_cases() if c.id == "DAE092/fail")
    path = materialise(case, tmp_path)
    report = check_fmu(path, options=EngineOptions(probes=True))
    assert [f.name for f in report.findings] == ["fmi-version-unsupported"]
    assert report.not_checked and not report.rules_run
    assert {reason for _, reason in report.rules_skipped} == {report.not_checked}
    assert main(["check", str(path), "--color", "never"]) == 0
    out = capsys.readouterr().out
    assert "not checked" in out and "schema-violation" not in out


def test_an_fmi2_fmu_with_the_dae_layer_is_the_part(tmp_path):
    """[[rule.parts]] fmi2-with-dae-layer: an FMI 1.0/2.0 FMU that carries files of
    extra/org.fmi-standard.fmi-ls-dae/ claims a layered standard of FMI 3.0; without them it is
    the rule's own (info) case. Same message, location and evidence either way."""
    from tests.fixtures import all_cases

    case = next(c for c in all_cases() if c.id == "DAE092/fail")
    plain = materialise(case, tmp_path / "plain")
    (plain_finding,) = check_fmu(plain, options=EngineOptions(probes=False)).findings
    assert plain_finding.part is None
    layered = materialise(case, tmp_path / "layered")
    manifest = layered / "extra" / "org.fmi-standard.fmi-ls-dae" / "fmi-ls-manifest.xml"
    manifest.parent.mkdir(parents=True)
    manifest.write_text("<fmiDAEManifest/>")
    (finding,) = check_fmu(layered, options=EngineOptions(probes=False)).findings
    assert finding.part == "fmi2-with-dae-layer"
    assert (finding.message, finding.location, finding.evidence) == \
        (plain_finding.message, plain_finding.location, plain_finding.evidence)
