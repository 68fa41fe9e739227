"""SARIF: read back by sarif-tools, complete for GitHub code scanning, equal to saved output."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from sarif.loader import load_sarif_file

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import FmuReport, Location, Report, Severity
from conformance.reporters import REPORTER_BY_NAME, json_report, sarif
from tests.repokit import repo_file
from tests.reporters.samples import (
    MANIFEST,
    SAMPLE_CATALOGUE,
    compare_expected,
    engine_catalogue,
    sample_report,
)

LEVELS = {"error": "error", "warning": "warning", "info": "note"}


def github_problems(log: dict) -> list[str]:
    """Every property GitHub's "SARIF support for code scanning" page marks as required (an
    explicit, non-empty value), plus its limits and the fields we rely on it to use."""
    problems: list[str] = []

    def need(obj: dict, dotted: str, where: str) -> object:
        value: object = obj
        for part in dotted.split("."):
            value = value.get(part) if isinstance(value, dict) else None
        if value in (None, "", [], {}):
            problems.append(f"{where}: {dotted} is missing or empty")
        return value

    need(log, "$schema", "sarifLog")
    if log.get("version") != "2.1.0":
        problems.append("sarifLog: version is not 2.1.0")
    runs = need(log, "runs", "sarifLog") or []
    for r, run in enumerate(runs):
        where = f"runs[{r}]"
        driver = need(run, "tool.driver", where) or {}
        need(driver, "name", f"{where}.tool.driver")
        rules = need(driver, "rules", f"{where}.tool.driver") or []
        if "results" not in run:
            problems.append(f"{where}: results is missing")
        ids = [rule.get("id") for rule in rules]
        if len(ids) != len(set(ids)):
            problems.append(f"{where}: rule ids are not unique")
        for i, rule in enumerate(rules):
            at = f"{where}.rules[{i}]"
            for prop in ("id", "shortDescription.text", "fullDescription.text", "help.text"):
                need(rule, prop, at)
            for prop in ("shortDescription", "fullDescription"):
                if len(rule.get(prop, {}).get("text", "")) > 1024:
                    problems.append(f"{at}: {prop}.text is over 1024 characters")
            if len(rule.get("name", "")) > 255:
                problems.append(f"{at}: name is over 255 characters")
            level = rule.get("defaultConfiguration", {}).get("level", "warning")
            if level not in ("note", "warning", "error"):
                problems.append(f"{at}: defaultConfiguration.level {level!r}")
        for k, result in enumerate(run.get("results", [])):
            at = f"{where}.results[{k}]"
            need(result, "message.text", at)
            rule_id = result.get("ruleId")
            index = result.get("ruleIndex")
            if index is not None and (index >= len(rules) or rules[index]["id"] != rule_id):
                problems.append(f"{at}: ruleIndex {index} does not point at {rule_id}")
            if result.get("level") not in (None, "none", "note", "warning", "error"):
                problems.append(f"{at}: level {result.get('level')!r}")
            locations = need(result, "locations", at) or []
            if len(locations) > 10:
                problems.append(f"{at}: more than 10 locations")
            for n, location in enumerate(locations):
                physical = need(location, "physicalLocation", f"{at}.locations[{n}]") or {}
                for prop in ("artifactLocation.uri", "region.startLine", "region.startColumn",
                             "region.endLine", "region.endColumn"):
                    need(physical, prop, f"{at}.locations[{n}].physicalLocation")
            need(result, "partialFingerprints.primaryLocationLineHash", at)
    return problems


def _log(report: Report, catalogue=SAMPLE_CATALOGUE, **kw) -> dict:
    return json.loads(sarif.render(report, catalogue, **kw))


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "lsdae.sarif"
    path.write_text(text, encoding="utf-8")
    return path


def test_registered():
    assert REPORTER_BY_NAME["sarif"] is sarif.render


def test_sample_matches_saved_output():
    compare_expected("sample.sarif", sarif.render(sample_report(), SAMPLE_CATALOGUE))


def test_engine_report_matches_saved_output(engine):
    compare_expected("engine.sarif", sarif.render(engine, engine_catalogue()))


@pytest.mark.parametrize("which", ["sample", "engine", "engine-full-catalogue"])
def test_github_code_scanning_requirements(which, engine):
    report = sample_report() if which == "sample" else engine
    catalogue = {"sample": SAMPLE_CATALOGUE, "engine": engine_catalogue()}.get(
        which, default_catalogue())
    assert github_problems(_log(report, catalogue)) == []


@pytest.mark.parametrize("which", ["sample", "engine"])
def test_sarif_tools_reads_what_the_json_report_says(which, engine, tmp_path):
    report = sample_report() if which == "sample" else engine
    catalogue = SAMPLE_CATALOGUE if which == "sample" else engine_catalogue()
    data = json.loads(json_report.render(report))
    sarif_file = load_sarif_file(str(_write(tmp_path, sarif.render(report, catalogue))))
    assert sarif_file.get_distinct_tool_names() == ["lsdae"]
    assert sarif_file.get_result_count() == sum(len(f["findings"]) for f in data["fmus"])
    issues = sarif_file.get_report()
    for severity, level in LEVELS.items():
        want = sum(f["summary"][severity] for f in data["fmus"])
        assert issues.get_issue_count_for_severity(level) == want, severity
    records = sarif_file.get_records()
    want_codes = [f["code"] for fmu in data["fmus"] for f in fmu["findings"]]
    assert [r["Code"] for r in records] == want_codes
    for record in records:
        assert sarif_file.get_rules_by_id(record["Code"]), record["Code"]


def test_rules_come_from_the_catalogue_with_docs_and_spec():
    log = _log(sample_report())
    rules = log["runs"][0]["tool"]["driver"]["rules"]
    ids = [r["id"] for r in rules]
    assert ids[:len(SAMPLE_CATALOGUE)] == [r.code for r in SAMPLE_CATALOGUE]
    assert ids[len(SAMPLE_CATALOGUE):] == ["DAE790"]  # a finding the catalogue lacks
    dae203 = rules[ids.index("DAE203")]
    assert dae203["helpUri"].endswith("docs/rules.md#dae203-enable-parameter-not-boolean")
    assert "DAE-03; fmi-ls-dae §2" in dae203["help"]["text"]
    assert "DAE-03; fmi-ls-dae §2" in dae203["help"]["markdown"]
    assert len(dae203["fullDescription"]["text"]) <= 1024
    assert dae203["fullDescription"]["text"].endswith("…")
    assert rules[ids.index("DAE021")]["defaultConfiguration"] == {"level": "warning"}
    assert rules[ids.index("DAE091")]["defaultConfiguration"] == {"level": "note"}


def test_rule_help_shows_the_basis_of_the_rule_and_of_each_part():
    """Issue 29: SARIF's rule help says what the verdict rests on, parts included."""
    catalogue = default_catalogue()
    rules = {r["id"]: r for r in json.loads(sarif.render(sample_report(), catalogue))
             ["runs"][0]["tool"]["driver"]["rules"]}
    rule = catalogue["unsafe-archive-path"]
    help_ = rules[rule.code]["help"]
    assert f"Basis: {rule.basis.describe()}" in help_["text"]
    for part in rule.parts:
        assert f"Part {part.part} ({part.what}, {part.severity}): {part.describe()}" in \
            help_["text"]
    assert rule.basis.describe() in help_["markdown"]
    assert rules[rule.code]["properties"]["basis"] == rule.basis.kind


def test_docs_anchor_matches_the_generated_rule_docs():
    docs = repo_file("docs/rules.md").read_text("utf-8")
    rule = default_catalogue()["DAE203"]
    anchor = sarif.rule_url(rule.code, rule.name).split("#", 1)[1]
    assert f"](#{anchor})" in docs  # the docs' own table of contents links the same anchor


def test_locations_archive_and_folder():
    results = _log(sample_report())["runs"][0]["results"]
    by_fmu = {}
    for r in results:
        by_fmu.setdefault(r["properties"]["fmu"], []).append(r)
    archive = by_fmu["models/Broken.fmu"][1]  # DAE203 at modelDescription.xml:12
    loc = archive["locations"][0]["physicalLocation"]
    assert loc["artifactLocation"] == {"uri": "models/Broken.fmu", "uriBaseId": "%SRCROOT%"}
    assert loc["region"]["startLine"] == 1
    assert archive["message"]["text"].endswith("(in modelDescription.xml:12)")
    assert archive["locations"][0]["logicalLocations"][0]["fullyQualifiedName"].startswith(
        "/fmiModelDescription")
    # an unpacked folder in the repository: the XML file itself, with its line
    folder = replace(sample_report().fmus[0], path="models/unpacked/Broken")
    result = _log(Report("9.9.9", (folder,)))["runs"][0]["results"][1]
    loc = result["locations"][0]["physicalLocation"]
    assert loc["artifactLocation"]["uri"] == "models/unpacked/Broken/modelDescription.xml"
    assert loc["region"] == {"startLine": 12, "startColumn": 5, "endLine": 12,
                             "endColumn": 45}
    assert not result["message"]["text"].endswith(")")


def test_folder_on_disk_missing_file_points_at_the_folder(tmp_path):
    fmu = tmp_path / "Plain"
    (fmu / "extra").mkdir(parents=True)
    (fmu / "modelDescription.xml").write_text("<x/>\n")
    report = Report("9.9.9", (FmuReport(path=str(fmu), draft=None, findings=(
        sample_report().fmus[1].findings[0],  # the manifest is missing
        replace(sample_report().fmus[0].findings[1], location=Location(file="modelDescription.xml",
                                                                     line=1)),
    )),))
    results = _log(report, root=str(tmp_path))["runs"][0]["results"]
    uris = [r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in results]
    assert uris == ["Plain", "Plain/modelDescription.xml"]


def test_paths_relative_to_the_repository_root(tmp_path):
    inside = str(tmp_path / "repo" / "dir with space" / "M.fmu")
    outside = str(tmp_path / "elsewhere" / "M.fmu")
    assert sarif.repo_path(inside, root=str(tmp_path / "repo")) == ("dir with space/M.fmu", True)
    assert sarif.repo_path(outside, root=str(tmp_path / "repo")) == (outside, False)
    assert sarif.repo_path("./a/../b/M.fmu") == ("b/M.fmu", True)
    fmu = replace(sample_report().fmus[3], path=inside, findings=sample_report().fmus[2].findings)
    results = _log(Report("9.9.9", (fmu,)), root=str(tmp_path / "repo"))["runs"][0]["results"]
    artifact = results[0]["locations"][0]["physicalLocation"]["artifactLocation"]
    assert artifact == {"uri": "dir%20with%20space/M.fmu", "uriBaseId": "%SRCROOT%"}
    fmu = replace(fmu, path=outside)
    results = _log(Report("9.9.9", (fmu,)), root=str(tmp_path / "repo"))["runs"][0]["results"]
    artifact = results[0]["locations"][0]["physicalLocation"]["artifactLocation"]
    assert artifact == {"uri": Path(outside).as_uri()}


def _fingerprints(report: Report) -> list[dict]:
    return [r["partialFingerprints"] for r in _log(report)["runs"][0]["results"]]


def test_fingerprints_survive_unrelated_edits_but_not_a_new_subject():
    report = sample_report()
    broken = report.fmus[0]
    moved = tuple(replace(f, location=replace(f.location, line=(f.location.line or 0) + 7,
                                              snippet="  " + (f.location.snippet or "")))
                  for f in broken.findings)
    shifted = replace(report, fmus=(replace(broken, findings=moved), *report.fmus[1:]))
    assert _fingerprints(shifted) == _fingerprints(report)
    renamed = replace(broken.findings[1], subject="other")
    changed = replace(report, fmus=(replace(broken, findings=(
        broken.findings[0], renamed, *broken.findings[2:])), *report.fmus[1:]))
    before, after = _fingerprints(report), _fingerprints(changed)
    assert before[0] == after[0] and before[1] != after[1]
    hashes = [f["primaryLocationLineHash"] for f in before]
    assert len(hashes) == len(set(hashes))


def test_identical_keys_get_distinct_occurrences():
    f = sample_report().fmus[2].findings[1]
    fmu = FmuReport(path="m/X.fmu", draft=None, findings=(f, f))
    prints = _fingerprints(Report("9.9.9", (fmu,)))
    assert [p["primaryLocationLineHash"][-2:] for p in prints] == [":1", ":2"]


def test_levels_follow_effective_severity_not_the_default():
    broken = sample_report().fmus[0]
    demoted = replace(broken, findings=(replace(broken.findings[1], severity=Severity.WARNING),))
    result = _log(Report("9.9.9", (demoted,)))["runs"][0]["results"][0]
    assert result["level"] == "warning"


def test_invocation_and_category():
    run = _log(sample_report())["runs"][0]
    invocation = run["invocations"][0]
    assert invocation["executionSuccessful"] is False  # the sample has an internal error
    assert invocation["toolExecutionNotifications"][0]["descriptor"] == {"id": "DAE099"}
    assert "automationDetails" not in run
    run = _log(sample_report(), category="lsdae/fmus")["runs"][0]
    assert run["automationDetails"] == {"id": "lsdae/fmus/"}


def test_brackets_in_messages_are_not_links():
    texts = [r["message"]["text"] for r in _log(sample_report())["runs"][0]["results"]]
    assert any(r"\[l\](u)" in t for t in texts)


def test_deterministic():
    assert sarif.render(sample_report(), SAMPLE_CATALOGUE) == sarif.render(sample_report(),
                                                                           SAMPLE_CATALOGUE)
    assert MANIFEST in sarif.render(sample_report(), SAMPLE_CATALOGUE)


def test_an_interrupted_run_is_an_error_notification_per_fmu_not_checked():
    report = replace(sample_report(), not_checked=("models/Later.fmu",))
    invocation = _log(report)["runs"][0]["invocations"][0]
    assert invocation["executionSuccessful"] is False
    assert invocation["toolExecutionNotifications"][-1] == {
        "level": "error", "message": {"text": "models/Later.fmu: not checked, the run was "
                                              "interrupted"}}
