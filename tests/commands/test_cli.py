"""The command line: exit codes, outputs, configuration, never a traceback."""
from __future__ import annotations

import json

import pytest

from conformance.commands import cli
from conformance.commands.cli import main
from conformance.commands.exit_codes import UsageError
from conformance.report.catalogue import CatalogueError
from tests.clikit import lsdae
from tests.fixtures import Case, materialise


@pytest.fixture
def scene(tmp_path):
    def make(**spec):
        dest = tmp_path / f"case{len(list(tmp_path.iterdir()))}"
        (dest / "spec").mkdir(parents=True)
        case = Case("CLI", "pass", dest / "spec", {"base": "HelloWorldDAE", **spec})
        return str(materialise(case, dest))
    return make


def test_clean_scene_exits_zero_and_writes_json(scene, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["check", scene(), "--no-probes", "--format", "json", "-o", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["tool"] == "lsdae" and data["schema_version"] == 1
    fmu = data["fmus"][0]
    assert fmu["draft"] == "alpha1" and fmu["summary"]["error"] == 0


def test_error_finding_exits_one(scene, capsys):
    path = scene(remove=["modelDescription"])
    assert main(["check", path, "--no-probes", "--color", "never"]) == 1
    out = capsys.readouterr().out
    assert "DAE090" in out and "model-description-missing" in out


def test_unreadable_input_is_a_finding_not_a_traceback(tmp_path, capsys):
    bogus = tmp_path / "broken.fmu"
    bogus.write_bytes(b"PK\x03\x04 this is not really a zip")
    out = tmp_path / "r.json"
    code = main(["check", str(bogus), str(tmp_path / "missing.fmu"), "--no-probes",
                 "--format", "json", "-o", str(out)])
    assert code == 1
    data = json.loads(out.read_text())
    assert [f["code"] for f in data["fmus"][0]["findings"]] == ["DAE001"]
    assert len(data["fmus"]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_several_formats_in_one_run(scene, tmp_path):
    j, c = tmp_path / "a.json", tmp_path / "a.txt"
    assert main(["check", scene(), "--no-probes", "--format", f"json:{j}",
                 "--format", f"console:{c}"]) == 0
    assert json.loads(j.read_text())["fmus"] and "checked 1 FMU" in c.read_text()


@pytest.mark.parametrize("argv", [
    ["check", "x.fmu", "--select", "NOPE999"],
    ["check", "x.fmu", "--severity", "DAE091"],
    ["check", "x.fmu", "--severity", "DAE091=loud"],
    ["check", "x.fmu", "--format", "yaml"],
    ["explain", "no-such-rule"],
])
def test_usage_errors_exit_two(argv, capsys):
    assert main(argv) == 2
    assert capsys.readouterr().err.startswith("lsdae: ")


def test_pyproject_config_and_cli_precedence(scene, tmp_path, monkeypatch, capsys):
    path = scene(remove=["manifest"])
    (tmp_path / "pyproject.toml").write_text(
        '[tool.lsdae]\nseverity = { manifest-missing = "error" }\n')
    monkeypatch.chdir(tmp_path)
    assert main(["check", path, "--no-probes"]) == 1
    assert main(["check", path, "--no-probes", "--severity", "DAE091=info"]) == 0


def test_bad_config_key_is_a_usage_error(scene, tmp_path, monkeypatch, capsys):
    (tmp_path / "pyproject.toml").write_text('[tool.lsdae]\nselct = ["DAE"]\n')
    monkeypatch.chdir(tmp_path)
    assert main(["check", scene(), "--no-probes"]) == 2


def test_rules_and_explain(capsys):
    assert main(["rules"]) == 0
    listing = capsys.readouterr().out
    assert "DAE091" in listing and "manifest-missing" in listing
    assert main(["explain", "manifest-missing"]) == 0
    text = capsys.readouterr().out
    assert "DAE091" in text and "Spec:" in text
    assert main(["explain", "dae091"]) == 0


def test_a_failing_reporter_does_not_lose_the_other_outputs(scene, tmp_path, monkeypatch, capsys):
    from conformance import reporters

    def broken(report, catalogue, **_):
        raise RuntimeError("boom")

    monkeypatch.setitem(reporters.REPORTER_BY_NAME, "console", broken)
    out = tmp_path / "r.json"
    assert main(["check", scene(), "--no-probes", "--format", "console",
                 "--format", f"json:{out}"]) == 2
    assert json.loads(out.read_text())["fmus"]
    err = capsys.readouterr().err
    assert "console reporter" in err and "Traceback" not in err


def test_unwritable_output_is_a_clear_error(scene, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["check", scene(), "--no-probes", "--format", "json",
                 "-o", str(blocker / "sub" / "r.json")]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_a_crashing_check_prints_no_traceback(scene, monkeypatch, capsys):
    from conformance.run import engine
    from conformance.checks import REGISTRY

    def broken(ctx, **_):
        raise ZeroDivisionError("boom")
        yield  # pragma: no cover

    monkeypatch.setitem(engine.REGISTRY, sorted(REGISTRY)[0], broken)
    # internal-error is a warning (a limit of lsdae's, no verdict on the FMU), yet the FMU was
    # not checked: exit 2, as for a usage or internal error, even with --fail-on error
    assert main(["check", scene(), "--no-probes", "--color", "never"]) == 2
    captured = capsys.readouterr()
    assert "warning[DAE099 internal-error]" in captured.out
    assert "Traceback" not in captured.err + captured.out
    assert main(["check", scene(), "--no-probes", "--fail-on", "never"]) == 0


def _codes(out_file) -> set[str]:
    return {f["code"] for f in json.loads(out_file.read_text())["fmus"][0]["findings"]}


def test_rule_options_from_the_command_line_and_pyproject(scene, tmp_path, monkeypatch, capsys):
    """A rule's option, set on the command line or in [tool.lsdae.rule-options], changes the
    verdict: modelDescription.xml (about 1.9 kB) is too large for a 1000-byte member limit.
    The limit is lsdae's own: a warning (issue 29), so --fail-on warning makes it fail."""
    path = scene()
    out = tmp_path / "r.json"
    base = ["check", path, "--no-probes", "--fail-on", "warning", "--format", "json",
            "-o", str(out)]
    monkeypatch.chdir(tmp_path)
    assert main(base) == 0 and "DAE004" not in _codes(out)
    assert main([*base, "--rule-option", "DAE004.max_member=1000"]) == 1
    assert "DAE004" in _codes(out)
    (limit,) = [f for f in json.loads(out.read_text())["fmus"][0]["findings"]
                if f["code"] == "DAE004"]
    assert limit["severity"] == "warning"
    (tmp_path / "pyproject.toml").write_text(
        "[tool.lsdae.rule-options.archive-too-large]\nmax_member = 1000\n")
    assert main(base) == 1 and "DAE004" in _codes(out)
    # the command line wins over the file
    assert main([*base, "--rule-option", "archive-too-large.max_member=100000000"]) == 0


@pytest.mark.parametrize("option", ["DAE004.no_such_option=1", "NOPE.max_member=1",
                                    "DAE004.max_member=large", "DAE004max_member=1"])
def test_bad_rule_option_is_a_usage_error(scene, option, capsys):
    assert main(["check", scene(), "--no-probes", "--rule-option", option]) == 2
    assert capsys.readouterr().err.startswith("lsdae: ")


def test_explain_says_how_to_set_an_option(capsys):
    assert main(["explain", "DAE740"]) == 0
    text = capsys.readouterr().out
    assert "--rule-option DAE740." in text and "[tool.lsdae.rule-options.DAE740]" in text


@pytest.mark.parametrize("exc, code, message", [
    (KeyboardInterrupt(), 130, "lsdae: interrupted\n"),
    (UsageError("no such thing"), 2, "lsdae: no such thing\n"),
    (CatalogueError("duplicate rule code DAE001"), 2,
     "lsdae: the rule catalogue is broken: duplicate rule code DAE001\n"),
    (ValueError("bad"), 2, "lsdae: internal error: ValueError: bad (run with -v for details)\n"),
])
def test_what_a_command_raises_is_one_line_and_an_exit_code(monkeypatch, exc, code, message):
    """Outside a run of checks (which writes what it finished), Ctrl-C, a usage error, a broken
    catalogue and an internal error each end in one line on stderr."""
    seen = []

    def command(args):
        seen.append(args.command)
        raise exc

    monkeypatch.setitem(cli.COMMANDS, "rules", command)
    assert lsdae("rules") == (code, "", message)
    assert seen == ["rules"]
