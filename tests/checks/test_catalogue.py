"""The catalogue is the single source of truth: registry, fixtures and docs must match it."""
from __future__ import annotations

import re

import pytest

from conformance.report.catalogue import default_catalogue
from conformance.checks import REGISTRY
from conformance.commands.explain import explain_text
from tests.fixturekit import FIXTURES

CATALOGUE = default_catalogue()
RULES = list(CATALOGUE)
# Rules that no input can trigger on purpose; each has a dedicated test instead.
NO_FIXTURE = {"internal-error": "tests/checks/test_engine.py::test_internal_error_is_a_finding"}


def test_registry_matches_static_catalogue():
    static = {r.code for r in RULES if r.stage == "static"}
    assert set(REGISTRY) - static == set(), "registered checks without a static catalogue entry"
    assert static - set(REGISTRY) == set(), "static catalogue rules without a registered check"


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_rule_entry_is_complete(rule):
    assert re.fullmatch(r"DAE\d{3}", rule.code)
    assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", rule.name)
    assert rule.spec.strip() and rule.summary and rule.rationale and rule.bad and rule.good
    assert rule.code in explain_text(rule)


def test_fixture_exemptions_name_catalogue_rules():
    unknown = sorted(set(NO_FIXTURE) - {r.name for r in RULES})
    assert unknown == [], f"NO_FIXTURE names rules the catalogue does not have: {unknown}"


@pytest.mark.parametrize("rule", [r for r in RULES if r.stage in ("archive", "xml", "schema",
                                                                   "static")],
                         ids=lambda r: r.code)
def test_rule_has_failing_and_passing_fixture(rule):
    if rule.name in NO_FIXTURE:
        pytest.skip(f"covered by {NO_FIXTURE[rule.name]}")
    folder = FIXTURES / rule.code
    kinds = {p.name.split("-")[0] for p in folder.iterdir()} if folder.is_dir() else set()
    assert "fail" in kinds, f"{rule.code} {rule.name} has no failing fixture in {folder}"
    assert "pass" in kinds, f"{rule.code} {rule.name} has no passing fixture in {folder}"


def test_rule_docs_are_current():
    from pathlib import Path

    from conformance.commands.ruledocs import render_markdown

    docs = Path(__file__).resolve().parents[2] / "docs" / "rules.md"
    assert docs.read_text(encoding="utf-8") == render_markdown(CATALOGUE), (
        "docs/rules.md is stale: run `lsdae rules --format markdown > docs/rules.md`")
