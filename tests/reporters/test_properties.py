"""Any report, whatever text it carries, renders in every format and stays readable."""
from __future__ import annotations

import json

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from conformance.report.findings import Finding, FmuReport, Location, Report, RunInfo, Severity
from conformance.reporters import REPORTER_BY_NAME
from tests.reporters.samples import SAMPLE_CATALOGUE, SCHEMAS, expected_junit_counts
from tests.reporters.test_github import parse
from tests.reporters.test_sarif import github_problems

SCHEMA = etree.XMLSchema(etree.parse(str(SCHEMAS / "junit.xsd")))
CODES = [r.code for r in SAMPLE_CATALOGUE] + ["DAE790"]
NAMES = {r.code: r.name for r in SAMPLE_CATALOGUE} | {"DAE790": "binary-crashed"}

words = st.text(min_size=0, max_size=30)
names = st.text(st.characters(blacklist_categories=("Cs",)), min_size=1, max_size=20)


@st.composite
def findings(draw) -> Finding:
    code = draw(st.sampled_from(CODES))
    location = Location(file=draw(st.none() | st.sampled_from(["modelDescription.xml", "x y.xml"])),
                        line=draw(st.none() | st.integers(1, 10_000)),
                        column=draw(st.none() | st.integers(1, 300)),
                        path=draw(st.none() | words), snippet=draw(st.none() | words))
    ev: tuple = (("value", draw(st.floats() | st.integers() | words)),)
    if draw(st.booleans()):
        ev += (("baselined", True),)
    return Finding(code, NAMES[code], draw(st.sampled_from(list(Severity))), draw(words),
                   location, ev, draw(st.none() | words), draw(st.integers(1, 5)))


@st.composite
def fmu_reports(draw, index: int = 0) -> FmuReport:
    stem = draw(names).replace("/", "_").replace("\\", "_").strip() or "m"
    path = f"dir{index}/{stem}" + draw(st.sampled_from([".fmu", ""]))
    return FmuReport(
        path=path, draft=draw(st.none() | st.sampled_from(["alpha1", "formulation"])),
        findings=tuple(draw(st.lists(findings(), max_size=6))),
        rules_run=tuple(draw(st.lists(st.sampled_from(CODES), unique=True, max_size=4))),
        rules_skipped=tuple((c, draw(words)) for c in draw(
            st.lists(st.sampled_from(CODES), unique=True, max_size=3))),
        info=(("model_name", draw(words)),))


@st.composite
def reports(draw) -> Report:
    n = draw(st.integers(1, 3))
    return Report("9.9.9", tuple(draw(fmu_reports(i)) for i in range(n)))


RUN = RunInfo("2026-11-21T22:28:40+00:00", "host", ())


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(reports())
def test_every_format_renders_and_stays_valid(report):
    outputs = {name: render(report, SAMPLE_CATALOGUE, run=RUN, environ={})
               for name, render in REPORTER_BY_NAME.items()}
    doc = etree.fromstring(outputs["junit"].encode("utf-8"))
    assert SCHEMA.validate(doc), SCHEMA.error_log
    counts = expected_junit_counts(json.loads(outputs["json"]))
    for suite, want in zip(doc.findall("testsuite"), counts, strict=True):
        assert {k: int(suite.get(k)) for k in want} == want
    assert github_problems(json.loads(outputs["sarif"])) == []
    commands, _ = parse(outputs["github"])
    total = sum(len(f.findings) for f in report.fmus)
    kinds = [c.kind for c in commands]
    new = [f for f in report.all_findings() if not f.evidence_dict().get("baselined")]
    per_kind = [sum(f.severity == s for f in new)
                for s in (Severity.ERROR, Severity.WARNING, Severity.INFO)]
    shown = [kinds.count(k) for k in ("error", "warning", "notice")]
    if max(per_kind) <= 10:
        assert shown == per_kind and kinds.count("group") == (len(new) < total)
    else:  # capped, and the last notice points at the full report
        e, w, n = per_kind
        assert shown == [min(e, 10), min(w, 10), min(n, 9) + 1]
        assert kinds.count("group") == 1 + (len(new) < total)
    rows = [line for line in outputs["markdown"].splitlines() if line.startswith("| `")]
    assert len(rows) == len(report.fmus)

