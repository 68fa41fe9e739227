"""The catalogue is the single source of truth: registry, fixtures and docs must match it."""
from __future__ import annotations

import re

import pytest

from conformance.report.catalogue import (FORCE_SEVERITY, CatalogueError, default_catalogue,
                                          load_catalogue)
from conformance.report.findings import Severity
from conformance.checks import REGISTRY
from conformance.commands.explain import explain_text
from tests.fixtures import FIXTURES

CATALOGUE = default_catalogue()
RULES = list(CATALOGUE)
# Rules that no input can trigger on purpose; each has a dedicated test instead.
NO_FIXTURE = {"internal-error": "tests/run/test_engine.py::test_internal_error_is_a_finding"}


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


# Digest ids: AR-01, MV-23, DAE-14, Q-07, D-13, B0, A10, SG-MATRIX ... (see the digest's legend)
DIGEST_ID = re.compile(r"\b(?:[A-Z]{1,3}-\d{2}|DAE-\d{2}|[QD]-\d{2}|B\d|A\d{1,2}|SG-MATRIX)\b")


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_severity_rests_on_the_spec_word_it_records(rule):
    """Issue 21.4: must/shall -> error, should -> warning, may/advice/open -> info; interop (no
    spec word, named importers reject it) -> warning; lsdae (lsdae could not check) -> error.
    Every entry names the word and the digest id it comes from, and explain shows both."""
    assert rule.force in FORCE_SEVERITY, rule.force
    assert rule.severity == FORCE_SEVERITY[rule.force], (rule.code, rule.severity, rule.force)
    if rule.force == "lsdae":
        assert rule.force_spec.startswith("none:"), "lsdae rules rest on no spec id: say so"
    else:  # a digest id, or "none:" and why there is none
        assert DIGEST_ID.search(rule.force_spec) or (
            rule.force_spec.startswith("none:") and rule.force in ("interop", "advice", "open")
        ), (rule.code, rule.force_spec)
    if rule.force == "interop":   # the importers, or how importers differ, are named
        assert re.search(r"importer|fmi-rs|fmusim|solver", rule.force_spec + rule.rationale)
    text = explain_text(rule)
    assert f"Force:      {rule.force}, {rule.force_spec}" in text


def test_the_force_words_cover_every_severity():
    assert set(FORCE_SEVERITY.values()) == set(Severity)
    assert {w for w, s in FORCE_SEVERITY.items() if s == Severity.ERROR} >= {"must", "shall"}
    assert FORCE_SEVERITY["should"] == Severity.WARNING
    assert {FORCE_SEVERITY[w] for w in ("may", "advice", "open")} == {Severity.INFO}


@pytest.mark.parametrize("edit, words", [
    (('force = "must"\n', ''), "lacks force"),
    (('force = "must"\n', 'force = "nice"\n'), "has force 'nice'"),
    (('severity = "error"\nforce = "must"\n', 'severity = "warning"\nforce = "must"\n'),
     "makes it error"),
])
def test_the_loader_refuses_a_severity_that_is_not_its_word(tmp_path, edit, words):
    text = (FIXTURES.parents[1] / "rules" / "probes.toml").read_text(encoding="utf-8")
    assert edit[0] in text
    (tmp_path / "probes.toml").write_text(text.replace(edit[0], edit[1], 1), encoding="utf-8")
    with pytest.raises(CatalogueError, match=words):
        load_catalogue(tmp_path)


def test_the_two_known_cases_are_information():
    assert CATALOGUE["initial-residual-nonzero"].severity == Severity.INFO
    assert CATALOGUE["initial-residual-nonzero"].force == "may"
    assert CATALOGUE["directional-derivatives-missing"].force == "advice"
    assert CATALOGUE["directional-derivatives-missing"].severity == Severity.INFO


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


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_every_rule_points_to_the_module_that_decides_it(rule):
    """docs/rules.md names each rule's module (issue 28): the registered check's, the probe's,
    or the engine's or driver's module that emits it by name."""
    from pathlib import Path

    from conformance.commands.ruledocs import EMITTED_BY, rule_home
    from conformance.probes.machinery.registry import PROBES

    home = rule_home(rule)
    root = Path(__file__).resolve().parents[2]
    assert home and (root / home).is_file(), (rule.code, home)
    if rule.code in REGISTRY:
        assert home == REGISTRY[rule.code].__module__.replace(".", "/") + ".py"
    elif rule.code in PROBES:
        source = (root / home).read_text(encoding="utf-8")
        assert f'"{rule.code}":' in source and PROBES[rule.code].__name__ in source
    else:
        assert rule.name in EMITTED_BY
        assert f'"{rule.name}"' in (root / home).read_text(encoding="utf-8")
    assert f"Code: `{home}`" in render_markdown_of(rule)
    assert f"Code:       {home}\n" in explain_text(rule)


def render_markdown_of(rule) -> str:
    from conformance.commands.ruledocs import render_markdown
    return render_markdown(CATALOGUE).split(f"## {rule.code} ", 1)[1].split("\n## ", 1)[0]
