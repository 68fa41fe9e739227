"""The mutation campaign (bench/mutation): a small seeded sample of real mutants of HelloWorldDAE
goes the whole way (build, oracle, lsdae check, verdicts), and the pieces it is made of.

Each class of mutant is a family: sign flips in three different analytic partials are killed;
three ways not to compile are stillborn; a survivor is UNEXPLAINED without a verdict, explained
with one, CONTRADICTED when its verdict says "consistent" but a promise is broken.
"""
from __future__ import annotations

import fcntl
from pathlib import Path
from typing import Any, Callable

import pytest

from bench.mutation.campaign import Cache, Runner, run_mutant
from bench.mutation.cli import main
from bench.mutation.checking import MAIN, SETTINGS, CheckResult, Setting, outcome, read_findings
from bench.mutation.generate import Mutant, _parse, generate, sample
from bench.mutation.oracle import differences
from bench.mutation.report import classify, tally, unexplained
from bench.mutation.targets import Target, all_targets, function_lines, live_lines
from bench.mutation.verdicts import Verdict, VerdictError, load
from tests import checkkit
from tests.fixtures import SCENES_DIR

SOURCE = "HelloWorldDAE/model.c"
TEXT = (SCENES_DIR / SOURCE).read_text().splitlines()


def mutant(old: str, new: str) -> Mutant:
    """The mutant of HelloWorldDAE/model.c that replaces ``old`` (in one line) by ``new``."""
    [n] = [i for i, line in enumerate(TEXT) if old in line]
    return Mutant(SOURCE, SOURCE, "HelloWorldDAE", n + 1, TEXT[n], TEXT[n].replace(old, new))


class _SessionCache(Cache):
    """The campaign's result cache in the session's folder (``tests/checkkit.py``): empty when
    the session starts, so as fresh as ``fresh=True``, and shared by both pytest-xdist workers,
    each result (the original's check and oracle, a mutant's) computed once under a lock."""

    def get(self, key: str, compute: Callable[[], Any]) -> Any:
        self.root.mkdir(parents=True, exist_ok=True)
        with open(self.root / f"{key}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            return super().get(key, compute)


@pytest.fixture(scope="module")
def runner(tmp_path_factory) -> Runner:
    shared = checkkit.SHARED or tmp_path_factory.mktemp("checked")
    return Runner(_SessionCache(root=shared / "mutation-results"))


@pytest.mark.parametrize("old, new", [
    ("D_RES_X(1, 0) = -2;", "D_RES_X(1, 0) = 2;"),     # d g2 / d x
    ("D_DER_W(0, 0) = 1;", "D_DER_W(0, 0) = -1;"),     # d der(x) / d y
    ("D_RES_W(0, 1) = 2;", "D_RES_W(0, 1) = -2;"),     # d g1 / d z
])
def test_a_sign_flipped_in_an_analytic_partial_is_killed(runner, old, new):
    rec = run_mutant(runner, mutant(old, new))
    assert rec["outcome"] == "killed"
    # the adjoint gives the same wrong entry: one defect, one finding (DAE740's, issue 29)
    codes = {code for code, _, _ in rec["killed_by"]}
    assert "DAE740" in codes and "DAE741" not in codes


def test_a_mutant_that_changes_nothing_observable_is_equivalent(runner):
    rec = run_mutant(runner, mutant("(void)t; (void)x; (void)w; (void)u;",
                                    "/*(void)t; (void)x; (void)w; (void)u;*/"))
    assert rec["outcome"] == "equivalent" and rec["oracle_detail"] == []
    assert rec["equivalent_but_reported"] is False


@pytest.mark.parametrize("old, new", [
    ("fmi3False", "fmi1False"),                    # an undeclared identifier
    ("D_RES_W(1, 1) = -3;", "D_RES_W(1, 1) = -3"),  # a syntax error
    ("der[0] = w[0];", "der[0] = w0(0);"),         # an implicit declaration (links, fails to load)
])
def test_a_mutant_that_does_not_compile_is_stillborn(runner, old, new):
    rec = run_mutant(runner, mutant(old, new))
    assert rec["outcome"] == "stillborn" and rec["build_detail"]


def test_the_nominal_mutant_is_said_by_state_nominal_not_xml_as_information(runner):
    # The binary's nominal of x differs from the XML's (1): a survivor of the first campaign,
    # closed by state-nominal-not-xml (DAE716), which no text backs (issue 29: advice): the
    # mutant is told, at information, and is no kill.
    rec = run_mutant(runner, mutant(".x_nominal = {1.0}", ".x_nominal = {2.0}"))
    assert rec["outcome"] == "informed" and rec["killed_by"] == []
    assert [code for code, _, _ in rec["informed_by"]] == ["DAE716"]


def test_a_survivor_needs_a_verdict_that_the_evidence_does_not_contradict(runner, monkeypatch):
    # The same mutant with state-nominal-not-xml ignored: a promise the campaign derives and
    # the check (so configured) does not see, as a survivor lsdae misses has.
    main = SETTINGS[MAIN]
    monkeypatch.setitem(SETTINGS, MAIN, Setting(main.name, main.label,
                                                (*main.args, "--ignore", "DAE716")))
    guess = ".x_nominal = {1.0}"
    rec = run_mutant(runner, mutant(guess, ".x_nominal = {2.0}"))
    assert rec["outcome"] == "survived"
    assert any(key.startswith("derived: nominals") for key in rec["promises"])
    classify([rec], {})
    assert rec["explained"] == "UNEXPLAINED" and unexplained([rec]) == [rec]
    classify([rec], {rec["id"]: Verdict("missed-defect", "nominal of x", "derived")})
    assert rec["explained"] == "explained" and unexplained([rec]) == []
    classify([rec], {rec["id"]: Verdict("consistent-model-change", "no promise broken")})
    assert rec["explained"] == "CONTRADICTED" and unexplained([rec]) == [rec]


def test_the_seeded_sample_is_reproducible_and_drawn_from_the_live_lines():
    target = next(t for t in all_targets() if t.name == SOURCE)
    mutants = generate(target)
    live = set(live_lines(target))
    assert mutants and {m.line for m in mutants} <= live
    # the DEFECT_NAN_DERIVATIVE lines, the comments and the blank lines are not live
    assert not any("NAN" in TEXT[n - 1] or TEXT[n - 1].lstrip().startswith(("*", "/*"))
                   or not TEXT[n - 1].strip() for n in live)
    first = sample(mutants, 5, seed=0, target=target.name)
    assert first == sample(mutants, 5, seed=0, target=target.name)
    assert first != sample(mutants, 5, seed=1, target=target.name)
    assert len({m.id for m in first}) == 5 and set(first) <= set(mutants)


def test_function_lines_find_one_line_and_multi_line_definitions():
    text = "int a;\nstatic int f(int x) { return x; }\nint g(void)\n{\n    if (1) { }\n}\n"
    assert list(function_lines(text, "f")) == [2]
    assert list(function_lines(text, "g")) == [3, 4, 5, 6]
    framework = (SCENES_DIR / "common" / "fmi3_framework.c").read_text().splitlines()
    lines = function_lines("\n".join(framework), "fmi3Reset")
    assert framework[lines[0] - 1].startswith("fmi3Status fmi3Reset(")
    assert framework[lines[-1] - 1] == "}"


def test_a_mutant_that_inserts_a_line_is_parsed_as_one_change():
    target = Target("t", "x.c", "HelloWorldDAE")
    original = ["a;\n", "b;\n", "c;\n"]
    m = _parse(target, original, ["a;\n", "b;\n", "break;\n", "c;\n"])
    assert m is not None and (m.line, m.original, m.mutated) == (2, "b;", "b;\nbreak;")
    assert m.apply("a;\nb;\nc;\n") == "a;\nb;\nbreak;\nc;\n"
    m = _parse(target, original, ["a;\n", "b;\n", "c;\n", "break;\n"])
    assert m is not None and (m.line, m.mutated) == (3, "c;\nbreak;")
    assert _parse(target, original, list(original)) is None
    m = _parse(target, original, ["a;\n", "B;\n", "c;\n"])
    assert m is not None and (m.line, m.original, m.mutated) == (2, "b;", "B;")
    assert m.apply("a;\nb;\nc;\n") == "a;\nB;\nc;\n"
    with pytest.raises(ValueError):
        m.apply("a;\nX;\nc;\n")


def _report(*findings: tuple[str, str, str | None, str]) -> dict:
    return {"fmus": [{"findings": [
        {"code": c, "name": c.lower(), "severity": sev, "subject": subj, "path": path,
         "message": "m"} for c, sev, subj, path in findings]}]}


def test_the_kill_criterion_is_a_new_error_or_warning_by_rule_and_subject():
    original = CheckResult("ok", 1.0, *read_findings(_report(
        ("DAE740", "error", "d(a)/d(b)", "/p"), ("DAE743", "info", "d(c)/d(d)", "/q"))))
    same = CheckResult("ok", 1.0, *read_findings(_report(("DAE740", "error", "d(a)/d(b)", "/p"))))
    assert outcome(original, same) == "survived"
    other_subject = _report(("DAE740", "error", "d(a)/d(b)", "/p"),
                            ("DAE740", "error", "d(x)/d(b)", "/p"))
    assert outcome(original, CheckResult("ok", 1, *read_findings(other_subject))) == "killed"
    info_only = _report(("DAE743", "info", "d(x)/d(y)", "/q"))
    # a new finding of information: said at the weight its text gives, no verdict (issue 29)
    assert outcome(original, CheckResult("ok", 1, *read_findings(info_only))) == "informed"
    known_info = _report(("DAE743", "info", "d(c)/d(d)", "/q"))
    assert outcome(original, CheckResult("ok", 1, *read_findings(known_info))) == "survived"
    by_path = _report(("DAE747", "warning", None, "/r"))
    assert outcome(original, CheckResult("ok", 1, *read_findings(by_path))) == "killed"
    internal = _report(("DAE099", "error", None, "/"))
    assert outcome(original, CheckResult("ok", 1, *read_findings(internal))) == "internal-error"
    assert outcome(original, CheckResult("timeout", 300.0)) == "check-timeout"
    assert outcome(original, CheckResult("failed", 1.0)) == "check-failed"


def test_the_oracle_compares_at_1e12_relative():
    a = {"ode": {"p1": {"values": [1.0, 0.0, "error: x"], "counts": 2}}}
    assert differences(a, {"ode": {"p1": {"values": [1.0 + 1e-13, 1e-15, "error: x"],
                                          "counts": 2}}}) == []
    assert differences(a, {"ode": {"p1": {"values": [1.0 + 1e-9, 0.0, "error: x"],
                                          "counts": 2}}})
    assert differences(a, {"ode": {"p1": {"values": [1.0, 0.0, 0.5], "counts": 2}}})
    assert differences(a, {"ode": {"p1": "failed: fmi3SetTime"}})


def test_the_score_is_computed_from_the_records():
    recs = [{"target": "t", "host": "h", "outcome": o, "id": str(i),
             "verdict": {"class": c} if c else None}
            for i, (o, c) in enumerate([("killed", None)] * 6 + [("stillborn", None)] +
                                       [("survived", "missed-defect")] * 2 +
                                       [("survived", "consistent-model-change")])]
    [row, total] = tally(recs, {"t": 100})
    assert row["score"] == total["score"] == 6 / 8
    assert (row["generated"], row["sampled"], row["stillborn"]) == (100, 10, 1)


def test_the_new_findings_per_killed_mutant_are_counted_beside_the_score():
    """Issue 29: one defect, one finding, measured: each killed mutant's new error and warning
    findings, mean, median and max; survivors and other outcomes do not count."""
    sizes = [1, 1, 3, 1, 2, 5]
    recs = [{"target": "t", "host": "h", "outcome": "killed", "id": str(i),
             "killed_by": [["DAE740", f"s{k}", "x"] for k in range(n)]}
            for i, n in enumerate(sizes)]
    recs.append({"target": "t", "host": "h", "outcome": "survived", "id": "s",
                 "killed_by": [], "verdict": {"class": "missed-defect"}})
    [row, total] = tally(recs, {"t": 10})
    assert row["per_kill"] == total["per_kill"] == {"mean": 13 / 6, "median": 1.5, "max": 5}


def test_verdicts_need_a_class_a_reason_and_for_a_missed_defect_the_promise(tmp_path):
    path = tmp_path / "v.toml"
    path.write_text('[verdict."a:1:x"]\nclass = "missed-defect"\nreason = "r"\n')
    with pytest.raises(VerdictError):
        load(path)
    path.write_text('[verdict."a:1:x"]\nclass = "maybe"\nreason = "r"\n')
    with pytest.raises(VerdictError):
        load(path)
    path.write_text('[verdict."a:1:x"]\nclass = "undetectable"\nreason = "r"\n')
    assert load(path)["a:1:x"].cls == "undetectable"
    assert load(Path(tmp_path / "missing.toml")) == {}


FRAMEWORK = "common/fmi3_framework.c"
FRAMEWORK_TEXT = (SCENES_DIR / FRAMEWORK).read_text().splitlines()


@pytest.mark.parametrize("old, new", [
    # reading a residual, an output or w alone no longer brings the values up to date
    ("computed |= kind == K_DER || kind == K_RES || kind == K_Y || kind == K_W || kind == K_Z;",
     "computed |= kind == K_DER || (0==1) || kind == K_Z;"),
    # fmi3SetFloat64 refuses the states (fmi3SetContinuousStates still works)
    ("    case K_X:\n", "    /*case K_X:*/\n"),
    # fmi3GetContinuousStateDerivatives returns the cached derivatives without an update
    ("    if ((status = update(c)) != fmi3OK) return status;\n    memcpy(der, c->der",
     "    if (0==1) return status;\n    memcpy(der, c->der"),
    # the switch's setter no longer checks the first value reference it is given (an illegal
    # call accepted)
    ("    for (k = 0; k < nvr; k++)\n        if (lookup(c, vr[k], &idx) != K_ENABLE) "
     "FAIL(\"fmi3SetBoolean",
     "    for (k = (0+1); k < nvr; k++)\n        if (lookup(c, vr[k], &idx) != K_ENABLE) "
     "FAIL(\"fmi3SetBoolean"),
])
def test_the_oracle_sees_what_only_an_order_of_calls_or_a_setter_shows(runner, old, new):
    text = "\n".join(FRAMEWORK_TEXT) + "\n"
    assert text.count(old) == 1
    start = text[:text.index(old)].count("\n")
    lines = text.replace(old, new).splitlines()
    m = Mutant("framework", FRAMEWORK, "HelloWorldDAE", start + 1, FRAMEWORK_TEXT[start],
               lines[start])
    assert m.apply(text) == text.replace(old, new)
    rec = run_mutant(runner, m)
    assert rec["outcome"] != "equivalent" and rec["oracle_detail"]


def test_rescore_applies_the_verdicts_file_to_a_written_campaign(tmp_path, capsys):
    survivor = {"id": "HelloWorldDAE/model.c:49:0000000000", "target": SOURCE,
                "source": SOURCE, "host": "HelloWorldDAE", "line": 49, "original": "a",
                "mutated": "b", "outcome": "survived", "promises": {}, "oracle_detail": ["x"]}
    killed = {**survivor, "id": "HelloWorldDAE/model.c:50:1111111111", "outcome": "killed",
              "killed_by": [["DAE740", "d(g1)/d(x)", "directional-derivative-mismatch"]]}
    campaign = tmp_path / "campaign.json"
    campaign.write_text(__import__("json").dumps({
        "meta": {"table": [], "main": "quick"}, "sweep": None,
        "targets": [{"target": SOURCE, "generated": 399}, {"target": "total"}],
        "mutants": [survivor, killed]}))
    verdicts = tmp_path / "verdicts.toml"
    verdicts.write_text("")
    out = tmp_path / "report"
    assert main(["--rescore", str(campaign), "--verdicts", str(verdicts), "--out", str(out),
                 "--stubs", str(tmp_path / "stubs.toml")]) == 1
    assert "UNEXPLAINED" in capsys.readouterr().out
    with pytest.raises(VerdictError, match="REVIEW"):   # a stub never passes for a verdict
        load(tmp_path / "stubs.toml")
    verdicts.write_text(f'[verdict."{survivor["id"]}"]\nclass = "missed-defect"\n'
                        'promise = "MV-23"\nreason = "r"\n')
    assert main(["--rescore", str(campaign), "--verdicts", str(verdicts), "--out", str(out)]) == 0
    data = __import__("json").loads((out / "campaign.json").read_text())
    assert data["targets"][-1]["score"] == 0.5 and (out / "summary.md").is_file()
