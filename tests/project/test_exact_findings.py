"""Every rule has at least one test that asserts its exact finding (tests/exactkit.py).

The assertion is found in one of two places: an ``[[exact]]`` table of a failing rule case
(``tests/fixtures/<CODE>/fail*/fixture.toml``, run by ``tests/checks/test_fixtures.py``), or a
call ``assert_exact(..., code="DAEnnn", ...)`` in a test module, the code written as a literal.
"""
from __future__ import annotations

import ast
from pathlib import Path

from conformance.report.catalogue import default_catalogue
from tests.fixtures import all_cases

TESTS = Path(__file__).resolve().parents[1]


def _calls_in(path: Path) -> set[str]:
    """The literal codes of the assert_exact calls of one module."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    codes = set()
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", None)
        if name != "assert_exact":
            continue
        for kw in node.keywords:
            if kw.arg == "code" and isinstance(kw.value, ast.Constant) \
                    and isinstance(kw.value.value, str):
                codes.add(kw.value.value)
    return codes


def exact_codes() -> dict[str, list[str]]:
    """Rule code -> where its exact assertions are (case ids and test modules)."""
    where: dict[str, list[str]] = {}
    for case in all_cases():
        if case.kind == "fail" and case.spec.get("exact"):
            where.setdefault(case.code, []).append(case.id)
    for path in sorted(TESTS.rglob("test_*.py")):
        for code in _calls_in(path):
            where.setdefault(code, []).append(path.relative_to(TESTS).as_posix())
    return where


def test_every_rule_has_an_exact_assertion():
    codes = sorted(r.code for r in default_catalogue())
    where = exact_codes()
    missing = [code for code in codes if code not in where]
    assert not missing, f"rules without an exact-finding assertion: {missing}"


def test_every_asserted_code_is_a_rule():
    known = {r.code for r in default_catalogue()}
    unknown = sorted(set(exact_codes()) - known)
    assert not unknown, f"exact assertions of codes the catalogue does not have: {unknown}"


def test_the_call_finder_sees_a_literal_code_only(tmp_path):
    module = tmp_path / "test_sample.py"
    module.write_text("def test_a(report, c):\n"
                      "    assert_exact(report, code='DAE401', severity='error', subject='x',\n"
                      "                 file=None, line=None, evidence={})\n"
                      "    kit.assert_exact(report, code='DAE402', severity='error',\n"
                      "                     subject='x', file=None, line=None, evidence={})\n"
                      "    assert_exact(report, code=c, severity='error', subject='x',\n"
                      "                 file=None, line=None, evidence={})\n"
                      "    other(code='DAE403')\n")
    assert _calls_in(module) == {"DAE401", "DAE402"}
