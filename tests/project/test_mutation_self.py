"""The mutation-self driver's own arithmetic: scores, verdicts, classes and the package files.

mutmut itself is not run here (``make mutation-self`` does that); these tests feed the driver
records as mutmut's results would give them.
"""
from __future__ import annotations

from collections import Counter

import pytest

from scripts.mutation_self import (SETTINGS, VerdictError, class_rows, judge, load_packages,
                                   load_verdicts, markdown, sample, split_name, tally)


def _rec(name, outcome, module="conformance/x/a.py", verdict=None, added=("y = 1",)):
    rec = {"name": name, "package": "x", "module": module, "outcome": outcome,
           "status": outcome, "added": list(added), "removed": ["y = 0"], "line": 3,
           "function": "f"}
    if verdict:
        rec["verdict"] = verdict
    return rec


def test_score_leaves_out_equivalent_survivors_and_counts_timeouts_as_killed():
    records = [_rec("a", "killed"), _rec("b", "killed"), _rec("c", "timeout"),
               _rec("d", "survived", verdict="equivalent"), _rec("e", "survived", verdict="open"),
               _rec("f", "survived", verdict="unexplained"), _rec("g", "other")]
    rows = tally(records, "package", Counter({"x": 40}))
    row = rows[0]
    assert (row["package"], row["generated"], row["mutants"]) == ("x", 40, 7)
    assert (row["killed"], row["timeout"], row["survived"], row["equivalent"], row["open"],
            row["unexplained"], row["other"]) == (2, 1, 3, 1, 1, 1, 1)
    assert row["score"] == pytest.approx(3 / 5)   # (2 + 1) / (7 - 1 equivalent - 1 other)
    assert rows[-1]["package"] == "total" and rows[-1]["score"] == pytest.approx(3 / 5)


def test_a_package_of_only_equivalent_survivors_has_no_score():
    rows = tally([_rec("d", "survived", verdict="equivalent")], "package", Counter({"x": 1}))
    assert rows[0]["score"] is None


def test_a_verdict_recorded_for_another_mutated_line_is_stale():
    verdicts = {"n": {"verdict": "equivalent", "mutated": "y = 2", "reason": "r"}}
    rec = _rec("n", "survived")
    judge(rec, verdicts)
    assert rec["verdict"] == "unexplained" and "stale" in rec["reason"]
    rec = _rec("n", "survived", added=("y = 2",))
    judge(rec, verdicts)
    assert (rec["verdict"], rec["reason"]) == ("equivalent", "r")
    rec = _rec("m", "survived")
    judge(rec, verdicts)
    assert (rec["verdict"], rec["reason"]) == ("unexplained", "")


def test_a_class_is_closed_when_every_mutant_run_of_it_is_killed():
    classes = {"c1": {"title": "t", "mutants": ["a", "b", "z"], "tests": ["t::x"],
                      "package": "x"},
               "c2": {"title": "t", "mutants": ["a", "s"], "tests": ["t::y"], "package": "x"},
               "c3": {"title": "t", "mutants": ["z"], "tests": ["t::z"], "package": "x"},
               "c4": {"title": "t", "mutants": ["a"], "tests": ["t::w"], "package": "other"}}
    records = [_rec("a", "killed"), _rec("b", "timeout"), _rec("s", "survived")]
    rows = {r["class"]: r for r in class_rows(classes, records, ["x"])}
    assert set(rows) == {"c1", "c2", "c3"}                  # c4's package was not run
    assert rows["c1"]["closed"] and rows["c1"]["mutants"]["z"] == "not run"
    assert not rows["c2"]["closed"]                         # a mutant of it survives
    assert not rows["c3"]["closed"]                         # nothing of it was measured


def test_the_report_lists_the_classes_and_the_unexplained_survivors():
    records = [_rec("pkg.mod.x_f__mutmut_1", "killed"),
               _rec("pkg.mod.x_f__mutmut_2", "survived", verdict="unexplained")]
    records[1]["reason"] = ""
    classes = class_rows({"c1": {"title": "a line off by one", "decides": "the line",
                                 "mutants": ["pkg.mod.x_f__mutmut_1"], "tests": ["t::x"],
                                 "package": "x"}}, records, ["x"])
    data = {"meta": {"table": [("commit", "abc")], "selection": {}},
            "packages": tally(records, "package", Counter({"x": 2})),
            "modules": tally(records, "module", Counter({"conformance/x/a.py": 2})),
            "mutants": records, "classes": classes}
    text = markdown(data)
    assert "defect classes (1 of 1 closed)" in text
    assert "| `c1` | `x` | a line off by one | the line | `x_f__mutmut_1`: killed |" in text
    assert "### unexplained (1)" in text and "`pkg.mod.x_f__mutmut_2`" in text


def test_the_sample_is_seeded_and_a_larger_one_holds_the_smaller():
    names = [f"m{i}" for i in range(50)]
    small, large = sample(names, 10, 0, "x"), sample(names, 20, 0, "x")
    assert small == sample(list(reversed(names)), 10, 0, "x")
    assert set(small) <= set(large) and len(small) == 10 and len(large) == 20
    assert small != sample(names, 10, 1, "x")
    assert sample(names, None, 0, "x") == sorted(names)


def test_mutant_names_split_into_module_and_function():
    assert split_name("conformance.numerics.limits.x_f__mutmut_3") == \
        ("conformance.numerics.limits", "f")
    assert split_name("conformance.numerics.settings.xǁTrajectoryǁto_info__mutmut_93") == \
        ("conformance.numerics.settings", "Trajectory.to_info")


def test_the_package_files_of_the_tree_load():
    packages = load_packages(SETTINGS)
    assert {"checks", "model", "intake", "numerics", "report", "reporters", "fixes", "run",
            "commands", "probes", "simulate"} <= set(packages)
    load_verdicts(SETTINGS)


@pytest.mark.parametrize("text, message", [
    ("[package]\nmutate = ['a']\n", "needs mutate and tests"),
    ("[package]\nmutate = ['a']\ntests = ['t']\n[verdict.m]\nverdict = 'maybe'\nmutated = 'x'\n",
     "needs verdict"),
    ("[package]\nmutate = ['a']\ntests = ['t']\n[verdict.m]\nverdict = 'equivalent'\n"
     "mutated = 'x'\n", "needs a reason"),
    ("[package]\nmutate = ['a']\ntests = ['t']\n[verdict.m]\nverdict = 'open'\nmutated = 'x'\n"
     "reason = 'REVIEW: a.py:3'\n", "nobody reviewed"),
    ("[package]\nmutate = ['a']\ntests = ['t']\n[class.c]\ntitle = 't'\nmutants = ['m']\n",
     "needs title, mutants and tests"),
])
def test_a_malformed_package_file_is_refused(tmp_path, text, message):
    (tmp_path / "p.toml").write_text(text)
    with pytest.raises(VerdictError, match=message):
        load_packages(tmp_path)
        load_verdicts(tmp_path)
