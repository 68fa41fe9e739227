"""One defect, one finding: violations that name the same cause fold into one (issue 29.3)."""
from __future__ import annotations

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Severity, Violation, evidence, thaw
from conformance.run.causes import fold_causes

CATALOGUE = default_catalogue()


def _v(place: str, cause: str | None, subject: str = "d(a)/d(b)") -> Violation:
    return Violation(f"{{subject}} is wrong in {place}", evidence=evidence(place=place),
                     subject=subject, cause=cause)


def _severity(rule, part) -> Severity:
    return rule.severity_of(part)


def test_violations_of_one_cause_are_one_finding_wherever_they_were_seen():
    """The same cause in several rules and places is the first's finding (in the order of codes,
    then places), with the others in its evidence; other causes, and violations without one,
    are left alone, whatever order the probe workers gave them in."""
    items = [(CATALOGUE["DAE752"], _v("init", "c1")), (CATALOGUE["DAE741"], _v("adjoint", "c1")),
             (CATALOGUE["DAE740"], _v("ode", "c1")), (CATALOGUE["DAE740"], _v("dae", "c1")),
             (CATALOGUE["DAE740"], _v("dae", "c2", "d(x)/d(y)")),
             (CATALOGUE["DAE742"], _v("dae", None))]
    for order in (items, items[::-1]):
        kept = fold_causes(order, _severity)
        assert sorted(r.code for r, _ in kept) == ["DAE740", "DAE740", "DAE742"]
        (first,) = [v for _, v in kept if v.cause == "c1"]
        assert first.text == ("'d(a)/d(b)' is wrong in dae; the same defect in 3 more places: "
                              "ode; adjoint; init")
        assert [(a["rule"], a["where"]) for a in thaw(dict(first.evidence)["also"])] == [
            ("DAE740", "ode"), ("DAE741", "adjoint"), ("DAE752", "init")]


def test_the_weightiest_finding_keeps_the_folded_ones():
    """A cause seen as an error and as information is the error's finding."""
    info = CATALOGUE["DAE743"]                       # advice: information
    error = CATALOGUE["DAE744"]
    assert info.severity == Severity.INFO and error.severity == Severity.ERROR
    kept = fold_causes([(info, _v("a", "c")), (error, _v("b", "c"))], _severity)
    assert [(r.code, v.text.split(";")[0]) for r, v in kept] == [
        ("DAE744", "'d(a)/d(b)' is wrong in b")]


def test_a_violation_without_a_place_is_named_by_its_subject():
    kept = fold_causes([(CATALOGUE["DAE021"], Violation("legacy", subject="formulation",
                                                         cause="legacy")),
                        (CATALOGUE["DAE104"], Violation("{subject} differs",
                                                        subject="fmi-ls-description",
                                                        cause="legacy"))], _severity)
    ((rule, v),) = kept
    assert rule.code == "DAE021"
    assert v.text == "legacy; the same defect in 1 more place: 'fmi-ls-description'"


def test_a_limit_of_lsdae_says_so_and_how_to_raise_it():
    """A finding whose basis is lsdae's own limit (issue 29: kind limit, a warning) names the
    limit and how to raise it, in the message every reporter shows; other findings do not."""
    from conformance.run.collector import Collector
    from conformance.run.options import EngineOptions, RuleSelection

    collector = Collector(RuleSelection(CATALOGUE, EngineOptions()), {}, threshold=5)
    collector.add(CATALOGUE["DAE702"], [Violation("the binary did not respond in 60 s")])
    collector.add(CATALOGUE["DAE740"], [Violation("{subject} is wrong", subject="d(a)/d(b)")])
    limit, verdict = sorted(collector.findings(), key=lambda f: f.code)
    assert limit.code == "DAE702" and limit.severity == Severity.WARNING
    assert limit.message == ("the binary did not respond in 60 s (lsdae's own limit, not a "
                             f"verdict on the FMU: {CATALOGUE['DAE702'].basis.word})")
    assert "--rule-option DAE702.probe_seconds" in limit.message
    assert verdict.message == "'d(a)/d(b)' is wrong"


def test_every_folded_place_is_kept_up_to_a_limit_and_the_rest_counted():
    """Up to ALSO_KEPT places in the evidence, each with its rule, place and message; the
    message names the first PLACES_SHOWN and how many more."""
    from conformance.run.causes import ALSO_KEPT, PLACES_SHOWN

    items = [(CATALOGUE["DAE740"], _v(f"p{k:03d}", "c")) for k in range(ALSO_KEPT + 3)]
    ((rule, v),) = fold_causes(items, _severity)
    assert (PLACES_SHOWN, ALSO_KEPT) == (5, 200)
    assert v.text == ("'d(a)/d(b)' is wrong in p000; the same defect in 202 more places: "
                      "p001; p002; p003; p004; p005; and 197 more")
    ev = dict(v.evidence)
    also = thaw(ev["also"])
    assert len(also) == ALSO_KEPT and ev["also_left_out"] == 2
    assert also[0] == {"rule": "DAE740", "where": "p001",
                       "message": "'d(a)/d(b)' is wrong in p001"}
    assert also[-1]["where"] == "p200"
    assert ev["place"] == "p000"
    six = fold_causes(items[:6], _severity)
    assert six[0][1].text.endswith("p001; p002; p003; p004; p005")
    assert "also_left_out" not in dict(six[0][1].evidence)


def test_a_place_is_named_by_subject_element_path_or_file():
    """A folded violation with no place of its own is named by its subject, else its element
    path, else its file; one seen elsewhere about another subject by both."""
    from conformance.report.findings import Location
    from conformance.run.causes import label, where

    assert where(Violation("m", Location(file="f.xml", path="/a/b"), subject="s")) == "'s'"
    assert where(Violation("m", Location(file="f.xml", path="/a/b"))) == "/a/b"
    assert where(Violation("m", Location(file="f.xml"))) == "f.xml"
    assert where(Violation("m")) == ""
    owner = _v("dae", "c", "d(a)/d(b)")
    assert label(_v("ode", "c", "d(a)/d(b)"), owner) == "ode"
    assert label(_v("ode", "c", "d(x)/d(b)"), owner) == "'d(x)/d(b)', ode"
    assert label(Violation("m", Location(file="f.xml")), owner) == "f.xml"


def test_the_first_cause_and_the_narrowest_call_keep_a_group():
    """Among equal severities: a rule of FIRST before the others whatever its code, then the
    code, then the call that named the fewest variables, then the place."""
    from conformance.run.causes import FIRST, _breadth, _rank

    failed, other = CATALOGUE["evaluation-failed"], CATALOGUE["DAE722"]
    assert _rank(failed) == FIRST.index("evaluation-failed") and _rank(other) == len(FIRST)
    assert failed.severity == other.severity
    assert failed.code > other.code          # the rank, not the code, puts it first
    kept = fold_causes([(other, _v("a", "c")), (failed, _v("b", "c"))], _severity)
    assert [(r.name, dict(v.evidence)["place"]) for r, v in kept] == [("evaluation-failed", "b")]

    def call(place: str, n) -> Violation:
        return Violation("crash", evidence=evidence(place=place, value_reference_count=n),
                         cause="c")
    assert [_breadth(call("x", n)) for n in (3, None, "2")] == [3, 0, 0]
    kept = fold_causes([(failed, call("a", 4)), (failed, call("b", 1)), (failed, call("c", 2))],
                       _severity)
    assert [dict(v.evidence)["place"] for _, v in kept] == ["b"]
