"""The new formats through the command line, several at once, each readable by its consumer."""
from __future__ import annotations

import json

from junitparser import JUnitXml
from sarif.loader import load_sarif_file

from conformance.commands.cli import main
from conformance.reporters import REPORTER_BY_NAME
from tests.fixtures import all_cases, materialise
from tests.repokit import repo_file
from tests.reporters.test_github import parse
from tests.reporters.test_sarif import github_problems


def test_all_ci_formats_in_one_run(tmp_path, monkeypatch):
    by_id = {c.id: c for c in all_cases()}
    bad = materialise(by_id["DAE203/fail"], tmp_path / "bad")
    good = materialise(by_id["DAE203/pass"], tmp_path / "good")
    monkeypatch.chdir(tmp_path)  # the repository root, as in CI
    for var in ("GITHUB_WORKSPACE", "GITHUB_SERVER_URL", "GITHUB_REPOSITORY", "GITHUB_RUN_ID"):
        monkeypatch.delenv(var, raising=False)
    out = tmp_path / "out"
    code = main(["check", str(bad.relative_to(tmp_path)), str(good.relative_to(tmp_path)),
                 "--no-probes", "--format", f"json:{out}/r.json",
                 "--format", f"junit:{out}/r.xml", "--format", f"sarif:{out}/r.sarif",
                 "--format", f"github:{out}/r.txt", "--format", f"markdown:{out}/r.md"])
    assert code == 1
    data = json.loads((out / "r.json").read_text())
    errors = sum(f["summary"]["error"] for f in data["fmus"])
    xml = JUnitXml.fromfile(str(out / "r.xml"))
    assert xml.failures == 1 and xml.errors == 0 and len(list(xml)) == 2
    log = json.loads((out / "r.sarif").read_text())
    assert github_problems(log) == []
    result = log["runs"][0]["results"][0]
    assert result["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] == (
        "bad/fmu/modelDescription.xml")
    assert load_sarif_file(str(out / "r.sarif")).get_result_count() == errors
    commands, _ = parse((out / "r.txt").read_text())
    assert [c.kind for c in commands] == ["error"] * errors + ["notice"] * 2
    assert commands[0].properties["file"] == "bad/fmu/modelDescription.xml"
    assert "| `bad/fmu` | fail |" in (out / "r.md").read_text()
    # --no-probes: no format lets a clean result pass for a checked binary
    unchecked = "binary not checked: probes turned off (--no-probes)"
    assert [c.message for c in commands[errors:]] == [f"bad/fmu: {unchecked}",
                                                      f"good/fmu: {unchecked}"]
    assert (out / "r.md").read_text().count("Binary not checked:** probes turned off") == 2
    notes = log["runs"][0]["invocations"][0]["toolExecutionNotifications"]
    assert [n["message"]["text"] for n in notes] == [f"bad/fmu: {unchecked}",
                                                     f"good/fmu: {unchecked}"]
    skipped = [case for suite in xml for case in suite if case.is_skipped]
    assert {case.name.split()[0] for case in skipped} >= {"DAE720", "DAE740", "DAE801"}


def test_every_format_is_documented():
    docs = repo_file("docs/formats.md").read_text("utf-8")
    for name in REPORTER_BY_NAME:
        assert f"| `{name}` |" in docs, f"docs/formats.md does not describe --format {name}"
