"""JUnit XML: read back by junitparser, valid against our JUnit XSD, equal to saved output."""
from __future__ import annotations

import json

import pytest
from junitparser import Error, Failure, JUnitXml, Skipped
from lxml import etree

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Report, RunInfo
from conformance.model.layer import NOT_A_DAE_FMU
from conformance.reporters import REPORTER_BY_NAME, json_report, junit
from tests.reporters.samples import (
    ENGINE_RUN,
    SAMPLE_CATALOGUE,
    SAMPLE_RUN,
    SCHEMAS,
    compare_expected,
    engine_catalogue,
    expected_junit_counts,
    sample_report,
)

SCHEMA = etree.XMLSchema(etree.parse(str(SCHEMAS / "junit.xsd")))


def _validate(text: str) -> None:
    doc = etree.fromstring(text.encode("utf-8"))
    assert SCHEMA.validate(doc), "\n".join(str(e) for e in SCHEMA.error_log)


def _read_back(text: str) -> JUnitXml:
    """As CI reads the file: UTF-8 bytes with the XML declaration."""
    return JUnitXml.fromstring(text.encode("utf-8"))


def test_registered():
    assert REPORTER_BY_NAME["junit"] is junit.render


def test_sample_matches_saved_output():
    compare_expected("sample.junit.xml", junit.render(sample_report(), SAMPLE_CATALOGUE,
                                                      run=SAMPLE_RUN))


def test_engine_report_matches_saved_output(engine):
    compare_expected("engine.junit.xml", junit.render(engine, engine_catalogue(),
                                                      run=ENGINE_RUN))


@pytest.mark.parametrize("which", ["sample", "engine", "engine-full-catalogue", "no-run"])
def test_valid_against_our_xsd_and_counts_match_json(which, engine):
    if which == "sample":
        report, catalogue, run = sample_report(), SAMPLE_CATALOGUE, SAMPLE_RUN
    elif which == "no-run":
        report, catalogue, run = sample_report(), None, None
    else:
        report, catalogue, run = engine, (engine_catalogue() if which == "engine"
                                          else default_catalogue()), ENGINE_RUN
    text = junit.render(report, catalogue, run=run)
    _validate(text)
    xml = _read_back(text)
    suites = list(xml)
    expected = expected_junit_counts(json.loads(json_report.render(report)))
    assert len(suites) == len(report.fmus)
    for suite, want, fmu in zip(suites, expected, report.fmus, strict=True):
        assert suite.name == fmu.path
        got = {"tests": suite.tests, "failures": suite.failures, "errors": suite.errors,
               "skipped": suite.skipped}
        assert got == want, fmu.path
        # junitparser's own reading of each case agrees with the suite's attributes
        cases = list(suite)
        outcomes = [type(c.result[0]).__name__ if c.result else "passed" for c in cases]
        assert outcomes.count("Failure") == want["failures"]
        assert outcomes.count("Error") == want["errors"]
        assert outcomes.count("Skipped") == want["skipped"]
        assert len(cases) == want["tests"]
    assert xml.tests == sum(w["tests"] for w in expected)
    assert xml.failures == sum(w["failures"] for w in expected)


def test_sample_outcomes_per_rule():
    xml = _read_back(junit.render(sample_report(), SAMPLE_CATALOGUE, run=SAMPLE_RUN))
    broken, plain, crashy, clean = list(xml)
    by_name = {c.name: c for c in broken}
    assert set(by_name) == {"DAE021 legacy-draft-shape", "DAE201 enable-parameter-missing",
                            "DAE203 enable-parameter-not-boolean",
                            "DAE301 algebraic-variable-unknown-vr",
                            "DAE701 initial-residual-nonzero"}
    assert all(c.classname == "Broken" for c in broken)
    # a warning passes, visible in the case's output
    warning = by_name["DAE021 legacy-draft-shape"]
    assert warning.is_passed and "legacy-draft-shape" in warning.system_out
    dae203 = by_name["DAE203 enable-parameter-not-boolean"].result[0]
    assert "modelDescription.xml:12" in dae203.text
    failure = by_name["DAE301 algebraic-variable-unknown-vr"].result[0]
    assert isinstance(failure, Failure) and failure.message.startswith("2 findings")
    skipped = by_name["DAE701 initial-residual-nonzero"].result[0]
    assert isinstance(skipped, Skipped) and skipped.message == "probes turned off (--no-probes)"
    # no manifest: the info finding passes, the DAE rules are skipped with the reason
    assert {c.name: (c.result[0].message if c.result else None) for c in plain} == {
        "DAE091 manifest-missing": None, "DAE201 enable-parameter-missing": NOT_A_DAE_FMU,
        "DAE301 algebraic-variable-unknown-vr": NOT_A_DAE_FMU,
        "DAE701 initial-residual-nonzero": NOT_A_DAE_FMU}
    # a crash and an internal error are errors, not failures; the rule unknown to the
    # catalogue keeps the finding's name
    kinds = {c.name: type(c.result[0]) for c in crashy
             if c.result and not isinstance(c.result[0], Skipped)}
    assert kinds == {"DAE099 internal-error": Error, "DAE790 binary-crashed": Error}
    # a rule that could not run is a skipped case that says so, with the reason
    not_run = {c.name.split()[0]: c.result[0].message for c in crashy
               if c.result and isinstance(c.result[0], Skipped)}
    assert not_run == {"DAE720": "not run: the worker failed before the probes could run"}
    assert all(c.is_passed for c in clean) and len(list(clean)) == 4


def test_attributes_for_jenkins_gitlab_and_ant():
    root = etree.fromstring(junit.render(sample_report(), SAMPLE_CATALOGUE,
                                         run=SAMPLE_RUN).encode())
    suite = root[0]
    assert suite.get("timestamp") == "2026-11-21T22:28:40"  # UTC, no zone (Ant)
    assert suite.get("hostname") == "ci-runner" and suite.get("time") == "0.250"
    assert suite.get("package") == "models" and suite.get("id") == "0"
    assert root.get("time") == "1.938" and root.get("tests") == "18"
    case = suite.find("testcase")
    assert case.get("file") == "models/Broken.fmu"  # GitLab shows it


def test_control_characters_never_break_the_xml():
    text = junit.render(sample_report(), SAMPLE_CATALOGUE, run=SAMPLE_RUN)
    assert "\x01" not in text and "\\x01bad" in text
    _validate(text)


def test_classnames_stay_unique_when_fmu_names_clash():
    report = sample_report()
    twin = report.fmus[0].__class__(path="other/Broken.fmu", draft=None, findings=(),
                                    rules_run=("DAE201",))
    report = Report(report.tool_version, (report.fmus[0], twin))
    xml = _read_back(junit.render(report, SAMPLE_CATALOGUE))
    assert [next(iter(s)).classname for s in xml] == ["models/Broken", "other/Broken"]


def test_only_time_and_timestamp_depend_on_the_run():
    report = sample_report()
    a = junit.render(report, SAMPLE_CATALOGUE, run=SAMPLE_RUN)
    b = junit.render(report, SAMPLE_CATALOGUE,
                     run=RunInfo("2030-01-01T00:00:00+00:00", "ci-runner", ()))
    def strip(text: str) -> list[str]:
        return [line for line in text.splitlines()
                if 'time="' not in line and "timestamp" not in line]

    assert a != b and strip(a) == strip(b)
    assert junit.render(report, SAMPLE_CATALOGUE, run=SAMPLE_RUN) == a


@pytest.mark.parametrize("stamp, want", [
    ("2026-11-21T22:28:40Z", "2026-11-21T22:28:40"),
    ("2026-11-21T23:28:40.750+01:00", "2026-11-21T22:28:40"),
    ("2026-11-21T22:28:40", "2026-11-21T22:28:40"),
    ("yesterday", "1970-01-01T00:00:00"),
    (None, "1970-01-01T00:00:00"),
])
def test_timestamps_are_utc_without_a_zone(stamp, want):
    root = etree.fromstring(junit.render(sample_report(), SAMPLE_CATALOGUE,
                                         run=RunInfo(stamp, "h", ())).encode())
    assert root.get("timestamp") == want
    assert {s.get("timestamp") for s in root.iter("testsuite")} == {want}
