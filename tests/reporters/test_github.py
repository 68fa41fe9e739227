"""GitHub workflow commands: parsed back as the runner does, capped per step, escaped."""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

from hypothesis import given
from hypothesis import strategies as st

from conformance.report.findings import FmuReport, Report, Severity
from conformance.model.layer import NOT_A_DAE_FMU
from conformance.reporters import REPORTER_BY_NAME, github, json_report
from tests.reporters.samples import SAMPLE_CATALOGUE, compare_expected, sample_report

_COMMAND = re.compile(r"^::([a-z-]+)(?: ([^:]*))?::(.*)$")
ENV = {"GITHUB_SERVER_URL": "https://github.com", "GITHUB_REPOSITORY": "acme/fmus",
       "GITHUB_RUN_ID": "42"}


@dataclass
class Command:
    kind: str
    properties: dict[str, str]
    message: str


def _unescape(text: str) -> str:
    return re.sub(r"%(25|0D|0A|3A|2C)",
                  lambda m: {"25": "%", "0D": "\r", "0A": "\n", "3A": ":", "2C": ","}[m[1]],
                  text)


def parse(output: str) -> tuple[list[Command], list[str]]:
    """Split output into workflow commands and plain log lines, as the runner reads them:
    lines end at LF, CR or CRLF (nothing else), properties split at ',' and the first '='
    (then unescaped)."""
    commands, plain = [], []
    lines = re.split(r"\r\n|\r|\n", output)
    for line in lines[:-1] if lines and lines[-1] == "" else lines:
        match = _COMMAND.match(line)
        if not match:
            plain.append(line)
            continue
        props = {}
        for item in filter(None, (match[2] or "").split(",")):
            key, _, value = item.partition("=")
            props[key] = _unescape(value)
        commands.append(Command(match[1], props, _unescape(match[3])))
    return commands, plain


def _render(report: Report, **kw) -> str:
    return github.render(report, SAMPLE_CATALOGUE, environ=kw.pop("environ", ENV), **kw)


def test_registered():
    assert REPORTER_BY_NAME["github"] is github.render


def test_sample_matches_saved_output():
    compare_expected("sample.github.txt", _render(sample_report()))


def test_engine_report_matches_saved_output(engine):
    compare_expected("engine.github.txt", _render(engine))


def test_one_annotation_per_finding_with_file_line_and_title():
    report = sample_report()
    commands, plain = parse(_render(report))
    groups = [c for c in commands if c.kind in ("group", "endgroup")]
    unchecked = [c for c in commands if c.properties.get("title") == "lsdae: binary not checked"]
    commands = [c for c in commands if c not in groups and c not in unchecked]
    # the FMU whose probes did not run says so in a notice of its own
    assert [c.message for c in unchecked] == [
        f"models/unpacked/Plain: binary not checked: {NOT_A_DAE_FMU}"]
    findings = sorted(((fmu, f) for fmu in report.fmus for f in fmu.findings
                       if not f.evidence_dict().get("baselined")),
                      key=lambda item: -item[1].severity)  # errors first, stable otherwise
    assert len(commands) == len(findings)
    kinds = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "notice"}
    for command, (_, f) in zip(commands, findings, strict=True):
        assert command.kind == kinds[f.severity]
        assert command.properties["title"] == f"{f.code} {f.name}"
        assert command.message.startswith(f.message)
    # archive: the .fmu, no line; folder: the folder (its manifest is missing)
    assert commands[0].properties == {"file": "models/Broken.fmu",
                                      "title": "DAE203 enable-parameter-not-boolean"}
    assert commands[0].message.endswith("(in modelDescription.xml:12)")
    assert commands[-1].properties["file"] == "models/unpacked/Plain"
    # the error a baseline accepted is only listed, in its own group
    assert [g.kind for g in groups] == ["group", "endgroup"]
    assert groups[0].message == "lsdae: 1 finding accepted by the baseline"
    assert len(plain) == 2 and "DAE201" in plain[0]
    assert plain[1] == ("lsdae: checked 4 FMUs: 5 errors, 1 warning, 1 info; "
                        "1 accepted by the baseline")


def test_folder_findings_carry_the_xml_file_and_line():
    broken = replace(sample_report().fmus[0], path="models/unpacked/Broken")
    commands, _ = parse(_render(Report("9.9.9", (broken,))))
    assert commands[0].properties == {
        "file": "models/unpacked/Broken/modelDescription.xml", "line": "12",
        "title": "DAE203 enable-parameter-not-boolean"}


def test_hostile_text_cannot_inject_a_command():
    commands, plain = parse(_render(sample_report()))
    odd = [c for c in commands if c.message.startswith("odd name")]
    assert len(odd) == 1 and "\r\n::error::injected" in odd[0].message
    assert not any("injected" in line for line in plain)


def test_counts_match_the_json_report(engine):
    data = __import__("json").loads(json_report.render(engine))
    commands, _ = parse(_render(engine))
    for kind, severity in (("error", "error"), ("warning", "warning"), ("notice", "info")):
        assert sum(c.kind == kind for c in commands) == sum(f["summary"][severity]
                                                            for f in data["fmus"])


def _many(errors: int, warnings: int, notices: int) -> Report:
    base = sample_report().fmus[0].findings[1]
    findings = ([replace(base, subject=f"e{i}") for i in range(errors)]
                + [replace(base, severity=Severity.WARNING, subject=f"w{i}")
                   for i in range(warnings)]
                + [replace(base, severity=Severity.INFO, subject=f"n{i}")
                   for i in range(notices)])
    return Report("9.9.9", (FmuReport(path="m/Big.fmu", draft="alpha1",
                                      findings=tuple(findings)),))


def test_capped_at_ten_per_kind_with_a_pointer_to_the_full_report():
    output = _render(_many(25, 3, 12))
    commands, plain = parse(output)
    kinds = [c.kind for c in commands]
    assert kinds.count("error") == 10 and kinds.count("warning") == 3
    assert kinds.count("notice") == 10  # 9 findings and the pointer
    assert kinds.count("group") == 1 and kinds.count("endgroup") == 1
    assert len(plain) == 15 + 3  # the rest, in the collapsed group, as plain log lines
    pointer = commands[-1]
    assert pointer.kind == "notice" and "18 are only in the log" in pointer.message
    assert "https://github.com/acme/fmus/actions/runs/42" in pointer.message
    assert output.splitlines()[-1].startswith("::notice ")


def test_pointer_without_a_run_names_the_other_formats_or_the_given_url():
    pointer = parse(_render(_many(11, 0, 0), environ={}))[0][-1]
    assert "--format json" in pointer.message
    pointer = parse(_render(_many(11, 0, 0), report_url="https://x/y"))[0][-1]
    assert "https://x/y" in pointer.message


def test_exactly_ten_of_each_needs_no_pointer():
    commands, plain = parse(_render(_many(10, 10, 10)))
    assert [c.kind for c in commands].count("notice") == 10 and len(commands) == 30
    assert len(plain) == 1


@given(st.text(), st.text())
def test_escaping_round_trips(message, prop):
    commands, _ = parse(github.command("warning", message, file=prop, title="t"))
    assert len(commands) == 1
    assert commands[0].message == message and commands[0].properties["file"] == prop


def test_pointer_and_hidden_group_say_exactly_what_was_left_out():
    commands, _ = parse(_render(_many(12, 0, 1), environ={}))
    group = next(c for c in commands if c.kind == "group")
    assert group.message == "lsdae: 2 more findings (not annotated)"
    pointer = commands[-1]
    assert pointer.properties == {"title": "lsdae: more findings"}
    assert pointer.message == (
        "lsdae found 12 errors, 0 warnings, 1 info in 1 FMU; GitHub shows 10 annotations of "
        "each kind per step, so 2 are only in the log group above. See the full report: run "
        "lsdae with --format json:FILE or --format markdown:FILE")


def test_the_run_page_comes_from_the_process_environment_by_default(monkeypatch):
    for key, value in ENV.items():
        monkeypatch.setenv(key, value)
    output = github.render(_many(11, 0, 0), SAMPLE_CATALOGUE)
    pointer = parse(output)[0][-1]
    assert pointer.message.endswith(
        "See the full report: https://github.com/acme/fmus/actions/runs/42")
