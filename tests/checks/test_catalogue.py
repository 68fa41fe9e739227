"""The catalogue is the single source of truth: registry, fixtures and docs must match it."""
from __future__ import annotations

import re

import pytest

from conformance.report.catalogue import (BASIS_SEVERITY, DOCUMENTS, KEYWORDS, CatalogueError,
                                          default_catalogue, load_catalogue)
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


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_every_verdict_records_its_basis_and_its_severity_follows_from_it(rule):
    """Issue 29.1: every rule, and every sub-check whose basis differs (a part), records the kind
    of text its verdict rests on and where that text is (document and version, section, the
    words as written); the severity is the kind's, never set by hand; explain shows it all."""
    assert rule.basis is not None, f"{rule.code} records no basis"
    text = explain_text(rule)
    for basis in (rule.basis, *rule.parts):
        assert basis.kind in BASIS_SEVERITY and basis.document in DOCUMENTS, basis
        assert basis.word, f"{rule.code}: a basis quotes the text, or says why there is none"
        if basis.kind in ("must", "should", "definition"):   # normative text of an original
            assert basis.document not in ("importers", "lsdae", "none") and basis.section
        if basis.kind in KEYWORDS:
            assert any(w in basis.word.lower() for w in KEYWORDS[basis.kind]), basis.word
        if basis.kind == "advice" and basis.document == "none":
            assert basis.word.startswith("no text"), basis.word
        assert basis.describe() in text
    assert rule.severity == BASIS_SEVERITY[rule.basis.kind]
    assert all(p.part and p.what for p in rule.parts)
    assert f"Basis:      {rule.basis.describe()}, hence {rule.severity}" in text


def test_the_kinds_cover_every_severity():
    assert set(BASIS_SEVERITY.values()) == set(Severity)
    assert {k for k, s in BASIS_SEVERITY.items() if s == Severity.ERROR} == {
        "must", "definition", "contradiction"}
    assert {k for k, s in BASIS_SEVERITY.items() if s == Severity.WARNING} == {
        "should", "interop", "limit"}
    assert {k for k, s in BASIS_SEVERITY.items() if s == Severity.INFO} == {"advice"}


_BASIS = re.compile(r'(?ms)^\[rule\.basis\]\nkind = "must"\ndocument = "[^"]*"\nsection = "[^"]*"\n'
                    r'word = "[^"]*"\n')


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('[rule.basis]\nkind = "must"\n', '[rule.basisx]\nkind = "must"\n', 1),
     "lacks basis"),
    (lambda t: t.replace('[rule.basis]\nkind = "must"\n', '[rule.basis]\nkind = "nice"\n', 1),
     "basis kind 'nice'"),
    (lambda t: t.replace('code = "DAE701"\n', 'code = "DAE701"\nseverity = "warning"\n', 1),
     "sets 'severity'"),
    (lambda t: _BASIS.sub('[rule.basis]\nkind = "must"\ndocument = "FMI 3.0.2"\n'
                          'section = "2.2"\nword = "it returns fmi3Error"\n', t, count=1),
     "quotes its keyword"),
    (lambda t: _BASIS.sub('[rule.basis]\nkind = "must"\ndocument = "FMI 3.0.2"\n'
                          'section = ""\nword = "it must"\n', t, count=1),
     "names the original's section"),
    (lambda t: _BASIS.sub('[rule.basis]\nkind = "limit"\ndocument = "FMI 3.0.2"\n'
                          'section = ""\nword = "probe_seconds"\n', t, count=1),
     "lsdae's own"),
])
def test_the_loader_refuses_a_basis_without_kind_location_or_keyword(tmp_path, edit, words):
    text = (FIXTURES.parents[1] / "rules" / "probes.toml").read_text(encoding="utf-8")
    changed = edit(text)
    assert changed != text, "the edit found nothing to change"
    (tmp_path / "probes.toml").write_text(changed, encoding="utf-8")
    with pytest.raises(CatalogueError, match=words):
        load_catalogue(tmp_path)


_PART = re.compile(r"""part=["']([a-z0-9-]+)["']""")


def _tags() -> dict[str, set[str]]:
    """part id -> the modules of conformance/ that tag a violation with it (``part="id"``)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "conformance"
    found: dict[str, set[str]] = {}
    for path in root.rglob("*.py"):
        for part in _PART.findall(path.read_text("utf-8")):
            found.setdefault(part, set()).add(str(path.relative_to(root.parent)))
    return found


TAGS = _tags()


@pytest.mark.parametrize("rule", [r for r in RULES if r.parts], ids=lambda r: r.code)
def test_every_part_is_decided_by_code_that_tags_it(rule):
    """A part of the catalogue is a sub-check some module tags (``part="id"``): a part nobody
    tags would record a basis that no finding ever shows."""
    untagged = [p.part for p in rule.parts if p.part not in TAGS]
    assert untagged == [], (rule.code, untagged)


def test_every_part_a_module_tags_is_in_the_catalogue():
    known = {p.part for r in RULES for p in r.parts}
    assert set(TAGS) - known == set(), {p: TAGS[p] for p in set(TAGS) - known}


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
