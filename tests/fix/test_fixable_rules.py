"""Per fixable rule: its failing fixtures are fixed, the rule no longer fires, nothing gets worse,
and fixing again changes nothing."""
from __future__ import annotations

from pathlib import Path

import pytest

from conformance.commands.fix import fix_fmu
from conformance.fixes.apply import keys
from tests.fix.conftest import FIXABLE, STATIC, codes
from tests.fixturekit import all_cases, materialise

# Failing fixtures of fixable rules whose fault has no exact fix (an entry to remove).
NO_FIX = {"DAE513/fail-2", "DAE513/fail-3"}
CASES = [c for c in all_cases()
         if c.code in FIXABLE and c.kind == "fail" and c.id not in NO_FIX]


def test_every_fixable_rule_has_a_failing_fixture():
    assert {c.code for c in CASES} == set(FIXABLE)


def _fixed(case, tmp_path: Path) -> tuple[Path, Path]:
    source = materialise(case, tmp_path / "in")
    outcome = fix_fmu(source, options=STATIC)
    assert outcome.applied, outcome.refused
    out = tmp_path / ("out" + source.suffix)
    outcome.package.write(out)
    return source, out


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_the_rule_no_longer_fires_and_nothing_is_worse(case, tmp_path):
    source, out = _fixed(case, tmp_path)
    assert case.code in codes(source)
    assert case.code not in codes(out)
    before = keys(fix_fmu(source, options=STATIC).original.findings)
    after = keys(fix_fmu(out, options=STATIC).original.findings)
    assert not after - before


@pytest.mark.parametrize("case", [c for c in all_cases() if c.id in NO_FIX], ids=lambda c: c.id)
def test_a_fault_without_an_exact_fix_is_left(case, tmp_path):
    source = materialise(case, tmp_path / "in")
    outcome = fix_fmu(source, options=STATIC)
    assert not outcome.applied and not outcome.package.modified
    assert case.code in codes(source)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_fixing_is_idempotent(case, tmp_path):
    _, out = _fixed(case, tmp_path)
    again = fix_fmu(out, options=STATIC)
    assert not again.applied and not again.package.modified
    if out.is_file():
        second = tmp_path / "again.fmu"
        again.package.write(second)
        assert second.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("case", [c for c in CASES if c.code != "DAE003"], ids=lambda c: c.id)
def test_a_folder_changes_only_in_the_files_fixed(case, tmp_path):
    source, out = _fixed(case, tmp_path)
    if not source.is_dir():
        pytest.skip("a zip fixture")
    changed = {p.relative_to(source).as_posix() for p in source.rglob("*") if p.is_file()
               and p.read_bytes() != (out / p.relative_to(source)).read_bytes()}
    named = {f.location.file for f in fix_fmu(source, options=STATIC).original.findings
             if f.code == case.code}
    assert changed == named and len(changed) == 1
    name = changed.pop()
    if case.code in ("DAE021", "DAE513"):
        return   # several lines: tests/fix/test_migrate.py and test_initial_unknowns.py
    before = (source / name).read_bytes().splitlines()
    after = (out / name).read_bytes().splitlines()
    assert len(before) == len(after)
    assert sum(a != b for a, b in zip(before, after)) == 1   # one line edited, the rest as was
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == \
        sorted(p.relative_to(source) for p in source.rglob("*"))
