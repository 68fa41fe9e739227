"""Baselines (conformance/report/baseline.py): the keys, the file, and which findings are new."""
from __future__ import annotations

import io
import json
import os
from collections import Counter
from pathlib import Path

import pytest

from conformance.report.baseline import (Baseline, BaselineError, apply, finding_key, fmu_key,
                                         identity, is_baselined, load, write)
from conformance.report.findings import (Finding, FmuReport, Location, Report, Severity,
                                         evidence)


def _f(code: str, message: str = "m", *, subject=None, path=None, line=None) -> Finding:
    return Finding(code, "name", Severity.ERROR, message,
                   Location(file="modelDescription.xml", line=line, path=path),
                   evidence(x=1), subject)


def _report(tmp_path: Path, *fmus: tuple[str, list[Finding]]) -> Report:
    return Report("1", tuple(FmuReport(str(tmp_path / name), "d", tuple(findings))
                             for name, findings in fmus), options=evidence(seed=0))


def test_a_findings_identity_is_its_subject_else_its_path_else_its_message():
    assert identity(_f("DAE1", "m", subject="x", path="/p", line=3)) == "x"
    assert identity(_f("DAE1", "m", path="/p", line=3)) == "/p"
    assert identity(_f("DAE1", "m", line=3)) == "m"


def test_an_fmu_is_keyed_by_its_path_relative_to_the_baseline(tmp_path: Path):
    anchor = tmp_path / "ci"
    assert fmu_key(str(tmp_path / "fmus" / "a.fmu"), anchor) == "../fmus/a.fmu"
    assert fmu_key(str(anchor / "b" / "c.fmu"), anchor) == "b/c.fmu"
    fmu = FmuReport(str(anchor / "a.fmu"), None, ())
    assert finding_key(fmu, _f("DAE7", subject="v", line=9), anchor) == ("a.fmu", "DAE7", "v")


def test_a_baseline_counts_its_keys_and_writes_them_sorted(tmp_path: Path):
    report = _report(tmp_path, ("b.fmu", [_f("DAE2", "second", subject="v"),
                                          _f("DAE2", "second again", subject="v"),
                                          _f("DAE1", "first", path="/p")]),
                     ("a.fmu", [_f("DAE3", "third")]))
    baseline = Baseline.from_report(report, tmp_path)
    assert baseline.counts == Counter({("b.fmu", "DAE2", "v"): 2, ("b.fmu", "DAE1", "/p"): 1,
                                       ("a.fmu", "DAE3", "third"): 1})
    doc = json.loads(baseline.to_json(report))
    assert doc == {"tool": "lsdae", "baseline_version": 1, "findings": [
        {"fmu": "a.fmu", "code": "DAE3", "identity": "third", "count": 1, "message": "third"},
        {"fmu": "b.fmu", "code": "DAE1", "identity": "/p", "count": 1, "message": "first"},
        {"fmu": "b.fmu", "code": "DAE2", "identity": "v", "count": 2, "message": "second"}]}
    assert "message" not in json.loads(baseline.to_json())["findings"][0]
    assert baseline.to_json().endswith("}\n") and baseline.to_json().startswith('{\n  "tool"')


def test_a_baseline_keeps_text_as_written(tmp_path: Path, monkeypatch):
    """UTF-8 whatever the locale's encoding (Windows: cp1252): a file that opens with no
    encoding takes the locale's, here made Latin-1."""
    monkeypatch.setattr(io, "text_encoding", lambda encoding, stacklevel=2: encoding or "latin-1")
    report = _report(tmp_path, ("ä.fmu", [_f("DAE1", "wärme", subject="θ")]))
    text = write(report, tmp_path / "deep" / "baseline.json").to_json(report)
    data = (tmp_path / "deep" / "baseline.json").read_bytes()
    assert data == text.encode("utf-8") and "wärme" in text and "\\u" not in text


def test_a_baseline_written_reads_back_the_same(tmp_path: Path):
    report = _report(tmp_path, ("a.fmu", [_f("DAE1", subject="v"), _f("DAE1", subject="v"),
                                          _f("DAE2", path="/x")]))
    file = tmp_path / "sub" / "baseline.json"
    written = write(report, file)
    assert written.anchor == file.parent.resolve()
    again = load(file)
    assert again.counts == written.counts == Counter({("../a.fmu", "DAE1", "v"): 2,
                                                      ("../a.fmu", "DAE2", "/x"): 1})
    assert again.anchor == file.parent.resolve()
    write(report, file)                                   # the folder exists already: no error


def test_a_baseline_file_that_omits_a_count_counts_one(tmp_path: Path):
    file = tmp_path / "b.json"
    file.write_text(json.dumps({"baseline_version": 1, "findings": [
        {"fmu": "a", "code": "DAE1", "identity": "v"},
        {"fmu": "a", "code": "DAE1", "identity": "v", "count": 3},
        {"fmu": 1, "code": "DAE2", "identity": 2, "count": "2"}]}))
    assert load(file).counts == Counter({("a", "DAE1", "v"): 4, ("1", "DAE2", "2"): 2})


@pytest.mark.parametrize("text, says", [
    ("{", "cannot read baseline"), ("[]", "is not an lsdae baseline (version 1)"),
    ('{"baseline_version": 2}', "is not an lsdae baseline (version 1)"),
    ('{"baseline_version": 1, "findings": [{"fmu": "a", "code": "X"}]}',
     ": malformed entry {'fmu': 'a', 'code': 'X'}"),
    ('{"baseline_version": 1, "findings": [{"fmu": "a", "code": "X", "identity": "i", '
     '"count": "many"}]}', ": malformed entry"),
])
def test_what_is_not_a_baseline_is_refused(tmp_path: Path, text: str, says: str):
    file = tmp_path / "b.json"
    file.write_text(text)
    with pytest.raises(BaselineError) as caught:
        load(file)
    assert str(caught.value).startswith(str(file)) or str(caught.value).startswith(
        f"cannot read baseline {file}")
    assert says in str(caught.value)


def test_a_baseline_that_cannot_be_written_says_so(tmp_path: Path):
    (tmp_path / "file").write_text("")
    with pytest.raises(BaselineError, match="cannot write baseline"):
        write(_report(tmp_path), tmp_path / "file" / "baseline.json")


def test_applying_a_baseline_marks_the_accepted_and_keeps_the_new(tmp_path: Path):
    old = _report(tmp_path, ("a.fmu", [_f("DAE1", subject="v"), _f("DAE2", subject="w")]),
                  ("b.fmu", [_f("DAE3", subject="gone")]))
    baseline = Baseline.from_report(old, tmp_path)
    now = _report(tmp_path, ("a.fmu", [_f("DAE1", subject="v", line=40),   # moved: still known
                                       _f("DAE1", subject="v"),           # a second one: new
                                       _f("DAE4", subject="v")]),          # another rule: new
                  ("b.fmu", []))
    result = apply(now, baseline, file="baseline.json")
    assert (result.baselined, result.stale) == (1, 2)
    assert result.summary() == {"baselined": 1, "new": 2, "stale": 2}
    marked = result.marked.fmus[0].findings
    assert [is_baselined(f) for f in marked] == [True, False, False]
    assert marked[0].evidence == (("x", 1), ("baselined", True))
    assert marked[1:] == now.fmus[0].findings[1:]
    assert [f.code for f in result.new.fmus[0].findings] == ["DAE1", "DAE4"]
    assert result.new.fmus[0].findings == now.fmus[0].findings[1:]
    assert [fmu.path for fmu in result.new.fmus] == [fmu.path for fmu in now.fmus]
    assert result.new.fmus[1].findings == () and result.marked.fmus[1].findings == ()
    assert result.new.options == now.options
    assert dict(result.marked.options) == {"seed": 0, "baseline": (
        ("file", "baseline.json"), ("baselined", 1), ("new", 2), ("stale", 2))}
    plain = apply(now, baseline)
    assert dict(plain.marked.options)["baseline"] == (("baselined", 1), ("new", 2),
                                                      ("stale", 2))


def test_a_baseline_accepts_as_many_as_it_counts(tmp_path: Path):
    three = _report(tmp_path, ("a.fmu", [_f("DAE1", subject="v")] * 3))
    two = Baseline(Counter({("a.fmu", "DAE1", "v"): 2, ("a.fmu", "DAE9", "z"): 0}), tmp_path)
    result = apply(three, two)
    assert (result.baselined, result.stale) == (2, 0)
    assert [is_baselined(f) for f in result.marked.fmus[0].findings] == [True, True, False]
    assert len(result.new.fmus[0].findings) == 1
    nothing = apply(_report(tmp_path, ("a.fmu", [])), Baseline(Counter(), tmp_path))
    assert (nothing.baselined, nothing.stale, nothing.summary()["new"]) == (0, 0, 0)


def test_a_baseline_matches_fmus_relative_to_its_own_folder(tmp_path: Path, monkeypatch):
    ci = tmp_path / "ci"
    ci.mkdir()
    report = _report(tmp_path, ("a.fmu", [_f("DAE1", subject="v")]))
    write(report, ci / "baseline.json")
    monkeypatch.chdir(ci)
    result = apply(report, load(Path("baseline.json")))
    assert result.baselined == 1 and result.summary()["new"] == 0
    elsewhere = apply(report, Baseline(load(ci / "baseline.json").counts, tmp_path))
    assert elsewhere.baselined == 0 and elsewhere.stale == 1


def test_an_fmu_on_another_drive_is_keyed_by_its_absolute_path(tmp_path: Path, monkeypatch):
    """Windows: no relative path between two drives (os.path.relpath raises ValueError)."""
    import conformance.report.baseline as baseline_module

    def other_drive(path, start=None):
        raise ValueError("path is on mount 'D:', start on mount 'C:'")

    monkeypatch.setattr(baseline_module.os.path, "relpath", other_drive)
    fmu = tmp_path / "fmus" / "a.fmu"
    assert fmu_key(str(fmu), tmp_path / "ci") == str(fmu.resolve()).replace(os.sep, "/")
