"""--fail-on, --exit-zero and baselines, from the command line and from [tool.lsdae]."""
from __future__ import annotations

import json

import pytest

from conformance.report.baseline import identity, load
from conformance.commands.cli import main
from tests.integration.conftest import BOOLEAN_DAE, INT_DAE

# A manifest-less FMU has one finding, DAE091, whose severity the tests choose.
LEVEL = {"info": "DAE091=info", "warning": "DAE091=warning", "error": "DAE091=error"}


@pytest.mark.parametrize("level, fail_on, expected", [
    ("info", "error", 0), ("info", "warning", 0), ("info", "never", 0),
    ("warning", "error", 0), ("warning", "warning", 1), ("warning", "never", 0),
    ("error", "error", 1), ("error", "warning", 1), ("error", "never", 0),
])
def test_fail_on(fmu, level, fail_on, expected):
    path = fmu("plain", manifest=False)
    argv = ["check", str(path), "--no-probes", "--severity", LEVEL[level], "--fail-on", fail_on]
    assert main(argv) == expected


def test_default_fails_on_errors_only(fmu):
    path = str(fmu("plain", manifest=False))
    assert main(["check", path, "--no-probes", "--severity", LEVEL["warning"]]) == 0
    assert main(["check", path, "--no-probes", "--severity", LEVEL["error"]]) == 1


def test_exit_zero(fmu, tmp_path, capsys):
    path = str(fmu("plain", manifest=False))
    assert main(["check", path, "--no-probes", "--severity", LEVEL["error"], "--exit-zero"]) == 0
    # usage errors still exit 2
    assert main(["check", path, "--no-probes", "--exit-zero", "--select", "NOPE9"]) == 2


def test_config_keys_and_command_line_precedence(fmu, tmp_path, monkeypatch):
    path = str(fmu("plain", manifest=False))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pyproject.toml").write_text(
        '[tool.lsdae]\nfail-on = "warning"\nseverity = { DAE091 = "warning" }\n')
    assert main(["check", path, "--no-probes"]) == 1
    assert main(["check", path, "--no-probes", "--fail-on", "error"]) == 0
    (tmp_path / "pyproject.toml").write_text(
        '[tool.lsdae]\nexit-zero = true\njobs = 2\nseverity = { DAE091 = "error" }\n')
    assert main(["check", path, "--no-probes"]) == 0


@pytest.mark.parametrize("table", [
    'fail-on = "sometimes"', 'exit-zero = "yes"', "jobs = 0", "jobs = true", "baseline = 3",
])
def test_bad_config_values_are_usage_errors(fmu, tmp_path, monkeypatch, capsys, table):
    path = str(fmu("plain", manifest=False))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pyproject.toml").write_text(f"[tool.lsdae]\n{table}\n")
    assert main(["check", path, "--no-probes"]) == 2
    assert capsys.readouterr().err.startswith("lsdae: ")


def _findings(report_file):
    data = json.loads(report_file.read_text())
    return [(fmu["path"], f["code"], bool(f["evidence"].get("baselined")))
            for fmu in data["fmus"] for f in fmu["findings"]], data


def test_baseline_round_trip(fmu, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    bad = fmu("bad", edits=((BOOLEAN_DAE, INT_DAE),))
    argv = ["check", "bad", "--no-probes", "--color", "never"]
    assert main(argv) == 1
    capsys.readouterr()

    # accept today's findings: writing the baseline passes the run and lists them by identity
    assert main([*argv, "--write-baseline", "base/lsdae-baseline.json"]) == 0
    assert "accepted, 0 new" in capsys.readouterr().out
    baseline = load(tmp_path / "base" / "lsdae-baseline.json")
    assert baseline.counts and all(fmu_ == "../bad" for fmu_, _, _ in baseline.counts)
    assert ("../bad", "DAE203", "dae") in baseline.counts

    # the same findings, shown but marked, pass; the line they are on does not matter
    md = bad / "modelDescription.xml"
    md.write_text(md.read_text().replace("<ModelVariables>", "<ModelVariables>\n\n\n"))
    out = tmp_path / "r.json"
    assert main([*argv, "--baseline", "base/lsdae-baseline.json", "--format",
                 f"json:{out}", "--format", "console"]) == 0
    found, data = _findings(out)
    assert found and all(marked for _, _, marked in found)
    assert data["options"]["baseline"]["new"] == 0
    assert "finding" in capsys.readouterr().out

    # a new fault fails the run; only it is unmarked
    md.write_text(md.read_text().replace('name="x" valueReference="2"',
                                         'name="x" valueReference="1"'))
    assert main([*argv, "--baseline", "base/lsdae-baseline.json", "--format",
                 f"json:{out}"]) == 1
    found, data = _findings(out)
    new = {code for _, code, marked in found if not marked}
    assert new and "DAE203" not in new
    assert data["options"]["baseline"]["new"] == len([1 for *_, m in found if not m])


def test_baseline_reports_fixed_findings_and_does_not_cover_other_fmus(fmu, tmp_path,
                                                                        monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    fmu("one", edits=((BOOLEAN_DAE, INT_DAE),))
    fmu("two", edits=((BOOLEAN_DAE, INT_DAE),))
    assert main(["check", "one", "--no-probes", "--write-baseline", "b.json"]) == 0
    capsys.readouterr()
    # the same fault in another FMU is new
    assert main(["check", "one", "two", "--no-probes", "--baseline", "b.json"]) == 1
    # fixing the fault leaves a stale entry, which the console names
    md = tmp_path / "one" / "modelDescription.xml"
    md.write_text(md.read_text().replace(INT_DAE, BOOLEAN_DAE))
    capsys.readouterr()
    assert main(["check", "one", "--no-probes", "--baseline", "b.json", "--color", "never"]) == 0
    assert "fixed since" in capsys.readouterr().out


def test_baseline_from_config_is_relative_to_pyproject(fmu, tmp_path, monkeypatch, capsys):
    bad = fmu("bad", edits=((BOOLEAN_DAE, INT_DAE),))
    (tmp_path / "pyproject.toml").write_text('[tool.lsdae]\nbaseline = "ci/base.json"\n')
    monkeypatch.chdir(tmp_path)
    # configured but not yet written: a usage error that says how to create it
    assert main(["check", str(bad), "--no-probes"]) == 2
    assert "--write-baseline" in capsys.readouterr().err
    assert main(["check", str(bad), "--no-probes", "--write-baseline", "ci/base.json"]) == 0
    sub = tmp_path / "ci"
    monkeypatch.chdir(sub)  # from another folder, the same baseline applies
    assert main(["check", str(bad), "--no-probes"]) == 0
    assert main(["check", str(bad), "--no-probes", "--no-baseline"]) == 1


def test_unreadable_baseline_is_a_usage_error(fmu, tmp_path, capsys):
    path = str(fmu("plain"))
    broken = tmp_path / "b.json"
    broken.write_text("{not json")
    assert main(["check", path, "--no-probes", "--baseline", str(broken)]) == 2
    broken.write_text('{"baseline_version": 99}')
    assert main(["check", path, "--no-probes", "--baseline", str(broken)]) == 2


def test_identity_prefers_subject_then_path_then_message():
    from conformance.report.findings import Finding, Location, Severity
    base = Finding("DAE001", "x", Severity.ERROR, "msg", Location("f", 3, path="/a"), (), "s")
    assert identity(base) == "s"
    assert identity(Finding("DAE001", "x", Severity.ERROR, "msg", Location("f", 3, path="/a"))
                    ) == "/a"
    assert identity(Finding("DAE001", "x", Severity.ERROR, "msg", Location("f", 3))) == "msg"
