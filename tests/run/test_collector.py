"""The collector (conformance/run/collector.py): which rule and severity a violation gets, when
repeated violations become one finding, what that finding says, and the line it points at."""
from __future__ import annotations

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Location, Severity, Violation, evidence, thaw
from conformance.run.collector import Collector, LineCache, limit_said
from conformance.run.options import EngineOptions, RuleSelection

CATALOGUE = default_catalogue()
XML = "modelDescription.xml"


def _collector(threshold: int = 3, texts=None, **options) -> Collector:
    return Collector(RuleSelection(CATALOGUE, EngineOptions(**options)), texts or {}, threshold)


def _odd(i: int, **kw) -> Violation:
    return Violation("variable {subject} is odd", Location(file=XML, line=10 + i),
                     subject=f"v{i}", **kw)


def test_violations_up_to_the_threshold_stay_apart_and_more_are_one_finding():
    rule = CATALOGUE["DAE740"]
    three = _collector()
    three.add(rule, [_odd(i) for i in range(3)])
    assert [(f.subject, f.count, f.message) for f in three.findings()] == [
        ("v0", 1, "variable 'v0' is odd"), ("v1", 1, "variable 'v1' is odd"),
        ("v2", 1, "variable 'v2' is odd")]
    seven = _collector()
    seven.add(rule, [_odd(i) for i in (6, 5, 4, 3, 2, 1, 0)])
    (finding,) = seven.findings()
    assert (finding.code, finding.count, finding.subject) == ("DAE740", 7, None)
    assert finding.message == ("variable 7 items ('v0', 'v1', 'v2', 'v3', 'v4', …) are odd")
    assert finding.location == Location(file=XML, line=10)
    assert thaw(finding.evidence) == {"count": 7,
                                      "subjects": ["v0", "v1", "v2", "v3", "v4", "v5", "v6"],
                                      "lines": [10, 11, 12, 13, 14, 15, 16]}


def test_a_group_keeps_its_first_evidence_and_twenty_subjects_and_lines():
    collector = _collector()
    collector.add(CATALOGUE["DAE740"], [
        Violation("odd", Location(file=XML, line=i + 1), evidence(k=i), subject=f"v{i:02d}")
        for i in range(25)])
    (finding,) = collector.findings()
    assert finding.message == "odd (25 times)"
    ev = thaw(finding.evidence)
    assert ev["k"] == 0 and ev["count"] == 25
    assert ev["subjects"] == [f"v{i:02d}" for i in range(20)]
    assert ev["lines"] == list(range(1, 21))


def test_a_group_folds_with_another_cause_under_its_count_and_place():
    collector = _collector()
    rule = CATALOGUE["DAE741"]
    collector.add(rule, [Violation("{subject} is wrong", evidence=evidence(place="adjoint"),
                                   subject=f"d(y{i})/d(x)", cause=f"through 'y{i}'")
                         for i in range(4)])
    collector.add(CATALOGUE["DAE740"], [Violation(
        "{subject} is wrong", evidence=evidence(place="ode"), subject="d(y0)/d(x)",
        cause=("through 'y0'", "through 'x'"))])
    (finding,) = collector.findings()
    assert finding.code == "DAE740"
    assert finding.message == (
        "'d(y0)/d(x)' is wrong; the same defect in 1 more place: 4 items ('d(y0)/d(x)', "
        "'d(y1)/d(x)', 'd(y2)/d(x)', 'd(y3)/d(x)'), adjoint")
    assert thaw(finding.evidence)["also"] == [{
        "rule": "DAE741", "where": "4 items ('d(y0)/d(x)', 'd(y1)/d(x)', 'd(y2)/d(x)', "
        "'d(y3)/d(x)'), adjoint", "message": "4 items ('d(y0)/d(x)', 'd(y1)/d(x)', "
        "'d(y2)/d(x)', 'd(y3)/d(x)') are wrong"}]
    assert finding.count == 1
    unfolded = Collector(collector.selection, {}, 3, fold=False)
    unfolded.items = list(collector.items)
    assert sorted((f.code, f.count) for f in unfolded.findings()) == [("DAE740", 1),
                                                                      ("DAE741", 4)]


def test_a_violation_goes_to_the_rule_it_names_if_that_rule_is_on():
    collector = _collector(ignore=("DAE742",))
    ran = CATALOGUE["DAE740"]
    collector.add(ran, [Violation("own"), Violation("named", rule="DAE741"),
                        Violation("by name", rule="adjoint-derivative-mismatch"),
                        Violation("by its own name", rule=ran.name),
                        Violation("unknown", rule="no-such-rule"),
                        Violation("ignored", rule="DAE742")])
    assert [(r.code, v.message) for r, v in collector.items] == [
        ("DAE740", "own"), ("DAE741", "named"), ("DAE741", "by name"),
        ("DAE740", "by its own name"), ("DAE740", "unknown")]
    off = _collector(ignore=("DAE740",))
    off.add(ran, [Violation("own")])
    assert off.items == []


def test_a_stage_violation_of_an_unknown_rule_is_an_internal_error():
    collector = _collector()
    collector.add_stage([Violation("bad zip", rule="archive-unreadable"),
                         Violation("odd", rule="nonsense"), Violation("none")])
    collector.emit("model-description-missing", Violation("broken"))
    assert [(r.name, v.message) for r, v in collector.items] == [
        ("archive-unreadable", "bad zip"), ("internal-error", "unknown rule 'nonsense': odd"),
        ("internal-error", "unknown rule None: none"), ("model-description-missing", "broken")]


def test_severity_is_the_parts_unless_the_user_set_the_rules():
    rule = next(r for r in CATALOGUE if r.parts and r.parts[0].severity != r.severity)
    part = rule.parts[0]
    collector = _collector()
    collector.add(rule, [Violation("a", subject="x", part=part.part), Violation("b")])
    assert sorted((f.message.split(" (")[0], f.severity, f.part)
                  for f in collector.findings()) == [("a", part.severity, part.part),
                                                     ("b", rule.severity, None)]
    forced = _collector(severity=((rule.code, "info"),))
    forced.add(rule, [Violation("a", part=part.part)])
    assert [f.severity for f in forced.findings()] == [Severity.INFO]


def test_a_limit_names_itself_and_other_bases_do_not():
    limit = next(r for r in CATALOGUE if r.basis.kind == "limit")
    assert limit_said(limit, None, "slow") == (
        f"slow (lsdae's own limit, not a verdict on the FMU: {limit.basis.word})")
    verdict = CATALOGUE["DAE740"]
    assert limit_said(verdict, None, "wrong") == "wrong"


def test_a_finding_points_at_the_line_where_its_start_tag_begins():
    text = b"<a>\n  <b x='1'\n     y='2'/>\n\n  text\n<c/>"
    lines = LineCache({XML: text})
    assert lines.with_snippet(Location(file=XML, line=3)) == Location(
        file=XML, line=2, snippet="  <b x='1'")
    assert lines.with_snippet(Location(file=XML, line=5)).line == 2
    assert lines.with_snippet(Location(file=XML, line=6)).snippet == "<c/>"
    assert lines.with_snippet(Location(file=XML, line=1)) == Location(file=XML, line=1,
                                                                      snippet="<a>")
    assert lines.with_snippet(Location(file=XML, line=7)) == Location(file=XML, line=7)
    assert lines.with_snippet(Location(file=XML)) == Location(file=XML)
    assert lines.with_snippet(Location(line=2)) == Location(line=2)
    assert LineCache({}).with_snippet(Location(file=XML, line=1)) == Location(file=XML, line=1)
    long = LineCache({XML: b"<" + b"x" * 300 + b"  \n"})
    assert long.with_snippet(Location(file=XML, line=1)).snippet == "<" + "x" * 239


def test_the_start_tag_is_searched_for_at_most_200_lines_up():
    far = b"<a\n" + b"x\n" * 250
    lines = LineCache({XML: far})
    assert lines.with_snippet(Location(file=XML, line=201)).line == 201
    assert lines.with_snippet(Location(file=XML, line=200)).line == 1
