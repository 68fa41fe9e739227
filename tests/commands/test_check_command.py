"""``lsdae check`` (conformance/commands/check.py): the options it hands the engine, where its
outputs go, its messages and its baseline note, run in this process."""
from __future__ import annotations

import json
import locale
import logging
import sys

import pytest

from conformance.commands import check
from conformance.commands.arguments import build_parser
from conformance.commands.exit_codes import UsageError
from conformance.run.options import EngineOptions
from tests.clikit import lsdae
from tests.fixtures import BOOLEAN_DAE, INT_DAE


def _args(*argv: str):
    return build_parser().parse_args(["check", "x.fmu", *argv])


def test_options_without_config_or_arguments_are_the_engines_defaults():
    assert check._options(_args(), {}) == EngineOptions(probe_workers=0)


def test_options_from_the_config_file():
    config = {"select": ["DAE2"], "ignore": ["DAE201"], "severity": {"DAE091": "info"},
              "draft": "alpha1", "probes": False, "endurance": "long"}
    assert check._options(_args(), config) == EngineOptions(
        select=("DAE2",), ignore=("DAE201",), severity=(("DAE091", "info"),), draft="alpha1",
        probes=False, endurance="long")


def test_options_from_the_command_line_win_over_the_config_file():
    config = {"select": ["DAE2"], "ignore": ["DAE201"], "severity": {"DAE091": "info"},
              "draft": "alpha1", "probes": True, "endurance": "long"}
    args = _args("--select", "DAE1, DAE3", "--ignore", "DAE101", "--severity", " DAE091 = error",
                 "--severity", "DAE104=warning", "--draft", "auto", "--no-probes",
                 "--endurance", "off", "--seed", "5", "--probe-workers", "2")
    assert check._options(args, config) == EngineOptions(
        select=("DAE1", "DAE3"), ignore=("DAE101",),
        severity=(("DAE091", "error"), ("DAE104", "warning")), draft="auto", probes=False,
        seed=5, endurance="off", probe_workers=2)


@pytest.mark.parametrize("argv, config, message", [
    (["--severity", "DAE091"], {}, "--severity takes RULE=LEVEL, not 'DAE091'"),
    ([], {"severity": {"DAE091": "loud"}}, "unknown severity 'loud'"),
])
def test_bad_severity_is_a_usage_error(argv, config, message):
    with pytest.raises(UsageError) as error:
        check._options(_args(*argv), config)
    assert str(error.value).startswith(message)


def test_settings_defaults_and_config():
    assert check._settings(_args(), {}) == check._RunSettings("error", False, None, 1)
    config = {"fail-on": "warning", "exit-zero": True, "baseline": "/b.json", "jobs": 3}
    assert check._settings(_args(), config) == check._RunSettings("warning", True, "/b.json", 3)
    assert check._settings(_args("--fail-on", "never", "--no-baseline", "-j", "2"), config) \
        == check._RunSettings("never", True, None, 2)


@pytest.mark.parametrize("argv, outputs", [
    ([], [("console", None)]),
    (["--format", "json", "-o", "r.json"], [("json", "r.json")]),
    (["--format", "json:a.json", "--format", "sarif", "-o", "r.sarif"],
     [("json", "a.json"), ("sarif", "r.sarif")]),
    (["--format", "console:-", "--format", "junit"], [("console", "-"), ("junit", None)]),
])
def test_outputs(argv, outputs):
    assert check._outputs(_args(*argv)) == outputs


@pytest.mark.parametrize("argv", [["--format", "json", "--format", "sarif", "-o", "r"],
                                  ["--format", "json:a.json", "-o", "r"]])
def test_output_file_needs_exactly_one_bare_format(argv):
    code, out, err = lsdae("check", "x.fmu", *argv)
    assert (code, out, err) == (2, "", "lsdae: -o needs exactly one --format without its own "
                                       "file\n")


def test_unknown_select_pattern_names_itself(tmp_path):
    code, out, err = lsdae("check", str(tmp_path), "--no-probes", "--select", "NOPE999")
    assert (code, out, err) == (2, "", "lsdae: no rule matches 'NOPE999' (see `lsdae rules`)\n")


@pytest.mark.parametrize("choice, file, no_color, tty, expected", [
    ("always", "r.txt", "1", False, True),
    ("never", None, "", True, False),
    ("auto", None, "", True, True),
    ("auto", None, "", False, False),
    ("auto", None, "1", True, False),
    ("auto", "r.txt", "", True, False),   # a file never gets colour codes, on a terminal too
    ("auto", "-", "", True, False),
])
def test_use_color(monkeypatch, choice, file, no_color, tty, expected):
    monkeypatch.setenv("NO_COLOR", no_color)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: tty)
    assert check._use_color(choice, file) is expected


def test_outputs_go_to_new_nested_folders_and_stdout(fmu, tmp_path):
    path = str(fmu("plain"))
    nested = tmp_path / "out" / "deeper" / "r.json"
    assert lsdae("check", path, "--no-probes", "--format", f"json:{nested}",
                 "--format", "json:-")[0] == 0
    written = nested.read_text(encoding="utf-8")
    assert json.loads(written)["fmus"][0]["path"] == path
    # the same text again: the folder exists now
    code, out, _ = lsdae("check", path, "--no-probes", "--format", f"json:{nested}",
                         "--format", "json:-")
    assert code == 0 and out == nested.read_text(encoding="utf-8")


def test_a_failing_reporter_is_logged_with_its_traceback(fmu, monkeypatch, caplog):
    from conformance import reporters

    def broken(report, catalogue, **_):
        raise RuntimeError("boom")

    monkeypatch.setitem(reporters.REPORTER_BY_NAME, "junit", broken)
    with caplog.at_level(logging.DEBUG, logger="conformance.commands.check"):
        code, out, err = lsdae("check", str(fmu("plain")), "--no-probes", "--format", "junit")
    assert (code, out) == (2, "")
    assert err == "lsdae: internal error in the junit reporter: RuntimeError: boom\n"
    (record,) = [r for r in caplog.records if r.name == "conformance.commands.check"]
    assert record.getMessage() == "reporter junit failed"
    assert record.exc_info is not None and record.exc_info[0] is RuntimeError


def test_baseline_note_is_the_last_console_line(fmu, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fmu("bad", edits=((BOOLEAN_DAE, INT_DAE),))
    argv = ["check", "bad", "--no-probes", "--color", "never"]
    code, out, _ = lsdae(*argv, "--write-baseline", "b.json")
    assert code == 0
    assert [f["code"] for f in json.loads((tmp_path / "b.json").read_text())["findings"]] \
        == ["DAE203"]
    assert out.endswith("\nbaseline b.json: 1 finding accepted, 0 new\n")
    code, out, _ = lsdae(*argv, "--baseline", "b.json", "--format", "json:r.json",
                         "--format", "console")
    assert code == 0
    assert out.endswith("\nbaseline b.json: 1 finding accepted, 0 new\n")
    assert "baseline b.json" not in (tmp_path / "r.json").read_text()   # the console's alone


def test_baseline_note_counts():
    class Result:
        def __init__(self, baselined, new, stale):
            self.counts = {"baselined": baselined, "new": new, "stale": stale}

        def summary(self):
            return self.counts

    assert check._baseline_note(Result(1, 0, 0), "b.json") == \
        "baseline b.json: 1 finding accepted, 0 new\n"
    assert check._baseline_note(Result(0, 2, 3), "c.json") == (
        "baseline c.json: 0 findings accepted, 2 new, 3 fixed since (rewrite it with "
        "--write-baseline)\n")


def test_rule_options_read_toml_values():
    args = _args("--rule-option", "DAE740.rtol=1e-4", "--rule-option", "DAE004.max_member = 7",
                 "--rule-option", "x.y.flag=true", "--rule-option", "DAE740.kind=word")
    config = {"rule-options": {"DAE740": {"atol": 1.0, "rtol": 0.5}}}
    assert check.rule_options(args, config) == {
        "DAE740": {"atol": 1.0, "rtol": 1e-4, "kind": "word"},
        "DAE004": {"max_member": 7}, "x.y": {"flag": True}}
    assert config == {"rule-options": {"DAE740": {"atol": 1.0, "rtol": 0.5}}}   # not changed
    assert check.rule_options(_args(), config) == {"DAE740": {"atol": 1.0, "rtol": 0.5}}


@pytest.mark.parametrize("item", ["DAE740.rtol", ".rtol=1", "DAE740.=1", "rtol=1"])
def test_rule_option_without_its_parts_is_a_usage_error(item):
    with pytest.raises(UsageError) as error:
        check.rule_options(_args("--rule-option", item), {})
    assert str(error.value) == f"--rule-option takes RULE.OPTION=VALUE, not {item!r}"


@pytest.fixture
def ascii_locale():
    """The C locale (ASCII), as on a machine without a UTF-8 locale; restored afterwards."""
    saved = locale.setlocale(locale.LC_CTYPE)
    locale.setlocale(locale.LC_CTYPE, "C")
    if sys.flags.utf8_mode or locale.getpreferredencoding(False).lower() in ("utf-8", "utf8"):
        locale.setlocale(locale.LC_CTYPE, saved)
        pytest.skip("Python's UTF-8 mode: every locale writes UTF-8")
    yield
    locale.setlocale(locale.LC_CTYPE, saved)


def test_reports_are_written_as_utf8_whatever_the_locale(fmu, tmp_path, ascii_locale):
    path = str(fmu("Pr\u00fcfstand"))
    out = tmp_path / "r.json"
    assert lsdae("check", path, "--no-probes", "--format", f"json:{out}") == (0, "", "")
    assert json.loads(out.read_bytes().decode("utf-8"))["fmus"][0]["path"] == path
