"""A fix that would make the check worse is not applied; hostile archives are not touched."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from conformance.commands.cli import main
from conformance.commands.fix import fix_fmu
from conformance.fixes import fixers
from conformance.fixes.apply import ALL
from conformance.fixes.change import Change
from conformance.fixes.edits import Edit
from tests.fix.conftest import STATIC, codes
from tests.fixturekit import all_cases, materialise


def _case(case_id: str, dest: Path) -> Path:
    return materialise(next(c for c in all_cases() if c.id == case_id), dest)


def _breaks_the_manifest(package, findings):
    file = findings[0].location.file
    data = package.read(file)
    return Change("broken", tuple(findings), (Edit(file, len(data) - 20, len(data), b""),))


def _claims_without_fixing(package, findings):
    file = findings[0].location.file
    return Change("idle", tuple(findings), (Edit(file, 0, 0, b""),))


@pytest.mark.parametrize("fixer", [_breaks_the_manifest, _claims_without_fixing])
def test_a_fix_that_is_not_proven_is_refused(fixer, tmp_path, monkeypatch):
    source = _case("DAE104/fail-1", tmp_path)
    monkeypatch.setitem(fixers.FIXERS, "header-fields", (("DAE104",), fixer))
    outcome = fix_fmu(source, options=STATIC)
    assert not outcome.applied and not outcome.package.modified
    assert [name for name, _ in outcome.refused] == ["header-fields"]
    assert "DAE104" in {f.code for f in outcome.report.findings}


def test_a_refused_fix_does_not_stop_the_others(tmp_path, monkeypatch):
    source = _case("DAE104/fail-1", tmp_path / "a")
    manifest = source / "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
    manifest.write_bytes(manifest.read_bytes().replace(b' xmlns:fmi-ls="http://fmi-standard.org/'
                                                       b'fmi-ls-manifest"', b""))
    assert {"DAE010"} <= codes(source)
    monkeypatch.setitem(fixers.FIXERS, "header-fields", (("DAE104",), _breaks_the_manifest))
    outcome = fix_fmu(source, options=STATIC)
    assert [c.fixer for c in outcome.applied] == ["declare-prefix"]


@pytest.mark.parametrize("case_id", ["DAE002/fail", "DAE004/fail"])
def test_hostile_archives_are_neither_rewritten_nor_copied(case_id, tmp_path):
    source = _case(case_id, tmp_path / "in")
    outcome = fix_fmu(source, options=STATIC)
    assert [name for name, _ in outcome.refused] == [ALL] and not outcome.applied
    out = tmp_path / "out" / "F.fmu"
    out.parent.mkdir()
    before = sorted(str(p) for p in tmp_path.rglob("*"))
    main(["fix", str(source), "-o", str(out), "--no-probes"])
    assert sorted(str(p) for p in tmp_path.rglob("*")) == before
    assert not out.exists()


def test_diff_writes_nothing_and_shows_the_change(tmp_path, capsys):
    source = _case("DAE104/fail-1", tmp_path)
    snapshot = {p: p.read_bytes() for p in source.rglob("*") if p.is_file()}
    assert main(["fix", str(source), "--diff", "--no-probes"]) == 0
    assert {p: p.read_bytes() for p in source.rglob("*") if p.is_file()} == snapshot
    assert sorted(tmp_path.rglob("*")) == sorted([tmp_path / "fmu", *source.rglob("*")])
    out = capsys.readouterr().out
    assert "--- a/extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml" in out


def test_exit_codes(tmp_path):
    clean = _case("DAE104/fail-1", tmp_path / "a")
    assert main(["fix", str(clean), "-o", str(tmp_path / "fixed"), "--no-probes"]) == 0
    assert "DAE104" not in codes(tmp_path / "fixed")
    remains = _case("DAE010/fail-2", tmp_path / "b")     # a residual vr no fix can invent
    assert main(["fix", str(remains), "-o", str(tmp_path / "b2"), "--no-probes"]) == 1
    assert main(["fix", str(remains), "-o", str(tmp_path / "b3"), "--no-probes",
                 "--fail-on", "never"]) == 0


def test_in_place(tmp_path):
    source = _case("DAE102/fail-1", tmp_path)
    assert main(["fix", str(source), "-o", str(source), "--no-probes"]) == 2
    assert "DAE102" in codes(source)
    assert main(["fix", str(source), "--in-place", "--no-probes"]) == 0
    assert "DAE102" not in codes(source)


@pytest.mark.parametrize("argv", [
    ["fix", "{src}", "--no-probes"],                          # nowhere to write
    ["fix", "{tmp}/missing.fmu", "--diff"],                   # no such FMU
    ["fix", "{src}", "--diff", "--in-place"],
    ["fix", "{src}", "-o", "{tmp}"],                          # an existing folder
    ["fix", "{src}", "--diff", "--select", "NOSUCHRULE"],
])
def test_usage_errors_exit_2(argv, tmp_path):
    source = _case("DAE104/fail-1", tmp_path)
    args = [a.format(src=source, tmp=tmp_path) for a in argv]
    assert main(args) == 2
    assert "DAE104" in codes(source)


def test_select_limits_the_fixes(tmp_path):
    source = _case("DAE104/fail-1", tmp_path / "a")
    out = tmp_path / "out"
    assert main(["fix", str(source), "-o", str(out), "--no-probes", "--select", "DAE103"]) == 0
    assert "DAE104" in codes(out)
    assert os.path.isdir(out)


def test_pre_commit_fixes_the_fmus_of_the_changed_files_and_fails_when_it_changed_one(
        tmp_path, monkeypatch):
    source = _case("DAE104/fail-1", tmp_path)
    monkeypatch.chdir(tmp_path)
    changed = ["fmu/extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml",
               "fmu/modelDescription.xml", "notes.txt"]
    assert main(["fix", "--pre-commit", "--no-probes", *changed]) == 1
    assert "DAE104" not in codes(source)
    snapshot = {p: p.read_bytes() for p in source.rglob("*") if p.is_file()}
    assert main(["fix", "--pre-commit", "--no-probes", *changed]) == 0
    assert {p: p.read_bytes() for p in source.rglob("*") if p.is_file()} == snapshot
    assert main(["fix", "--pre-commit", "--no-probes", "notes.txt"]) == 0


def test_several_fmus_take_in_place_or_diff(tmp_path):
    one = _case("DAE104/fail-1", tmp_path / "a")
    two = _case("DAE102/fail-1", tmp_path / "b")
    assert main(["fix", str(one), str(two), "-o", str(tmp_path / "x"), "--no-probes"]) == 2
    assert main(["fix", str(one), str(two), "--in-place", "--no-probes"]) == 0
    assert "DAE104" not in codes(one) and "DAE102" not in codes(two)


def test_a_finding_without_a_fix_says_why(tmp_path, capsys):
    remains = _case("DAE010/fail-2", tmp_path)           # DAE401: a residual vr to guess
    assert main(["fix", str(remains), "-o", str(tmp_path / "out"), "--no-probes"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert any(line.startswith("no fix for DAE401 ") for line in lines)
