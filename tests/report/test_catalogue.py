"""The catalogue loader (conformance/report/catalogue.py): what it reads, what it refuses, and how
a rule's verdict gets its severity from its basis."""
from __future__ import annotations

import copy
from pathlib import Path

import pytest

from conformance.report.catalogue import (Basis, Catalogue, CatalogueError, RuleSpec, _basis,
                                          _rule, default_catalogue, load_catalogue,
                                          with_options)
from conformance.report.findings import Severity
from conformance.report.paths import rules_dir

BASIS = {"kind": "must", "document": "FMI 3.0.2", "section": "2.4.8  Model\nStructure",
         "word": "The  FMU must   do it."}
PART = {"part": "dae-mode", "what": "DAE mode", "kind": "should",
        "document": "fmi-ls-dae 1.0.0-alpha.1", "section": "3.3", "word": "it should"}
TABLE = {"code": "DAE999", "name": "a-rule", "stage": "static", "drafts": ["*"],
         "spec": "MS-1", "summary": "  One line.\n", "rationale": "\nWhy.\n ",
         "bad": "\n<bad/>\n", "good": "\n<good/>\n", "basis": BASIS}


def _table(**changes):
    table = copy.deepcopy(TABLE)
    for key, value in changes.items():
        if value is None:
            table.pop(key, None)
        else:
            table[key] = value
    return table


def test_a_rule_table_becomes_its_spec_field_by_field():
    rule = _rule(_table(needs=["manifest"], aliases=["old-name"], options={"b": 2, "a": 1.5},
                        fix="safe:   add  the\nattribute", parts=[PART]), "x.toml")
    assert rule == RuleSpec(
        code="DAE999", name="a-rule", severity=Severity.ERROR, stage="static", drafts=("*",),
        needs=("manifest",), spec="MS-1", summary="One line.", rationale="Why.",
        bad="<bad/>", good="<good/>", aliases=("old-name",), options=(("a", 1.5), ("b", 2)),
        source="x.toml", fix="safe: add the attribute",
        basis=Basis("must", "FMI 3.0.2", "2.4.8 Model Structure", "The FMU must do it."),
        parts=(Basis("should", "fmi-ls-dae 1.0.0-alpha.1", "3.3", "it should", "dae-mode",
                     "DAE mode"),))
    assert rule.severity_of("dae-mode") == Severity.WARNING
    assert rule.severity_of(None) == Severity.ERROR
    assert rule.fix_kind == "safe"


def test_a_rule_without_the_optional_fields_has_their_defaults():
    rule = _rule(_table(), "x.toml")
    assert (rule.needs, rule.aliases, rule.options, rule.parts, rule.fix) == ((), (), (), (),
                                                                               None)
    assert rule.basis is not None and rule.severity == rule.basis.severity == Severity.ERROR


@pytest.mark.parametrize("changes, says", [
    ({"summary": None}, "x.toml: rule DAE999 lacks summary"),
    ({"stage": "later"}, "x.toml: rule DAE999 has unknown stage 'later'"),
    ({"needs": ["coffee"]}, "x.toml: rule DAE999 has unknown need 'coffee'"),
    ({"severity": "error"}, "x.toml: rule DAE999 sets 'severity'; the severity follows"),
    ({"force": True}, "x.toml: rule DAE999 sets 'force'"),
    ({"force_spec": "x"}, "x.toml: rule DAE999 sets 'force_spec'"),
    ({"parts": [PART, PART]}, "x.toml: rule DAE999 names a part twice"),
    ({"fix": "maybe: later"}, "x.toml: rule DAE999 has fix 'maybe: later'; write"),
    ({"fix": "safe:  "}, "x.toml: rule DAE999 has fix 'safe:  '"),
    ({"fix": 3}, "x.toml: rule DAE999 has fix 3"),
    ({"basis": "must"}, "x.toml: rule DAE999: basis must be a table"),
    ({"parts": [BASIS]}, "x.toml: rule DAE999 part: basis lacks part, what"),
])
def test_a_rule_table_is_refused_with_what_is_wrong(changes, says):
    with pytest.raises(CatalogueError) as caught:
        _rule(_table(**changes), "x.toml")
    assert str(caught.value).startswith(says)


def _refusal(where="w", *, part=False, **changes) -> str:
    table = dict(PART if part else BASIS, **changes)
    table = {k: v for k, v in table.items() if v is not None}
    with pytest.raises(CatalogueError) as caught:
        _basis(table, where, part=part)
    return str(caught.value)


def test_a_basis_is_refused_with_what_is_wrong():
    assert _refusal(word=None) == "w: basis lacks word"
    assert _refusal(kind=None, document=3) == "w: basis lacks kind, document"
    assert _refusal(colour="red", size="1") == "w: basis lacks -; unknown colour, size"
    assert _refusal(part=True, what=None, extra="1") == "w: basis lacks what; unknown extra"
    assert _refusal(kind="may") == ("w: basis kind 'may'; use one of must, definition, "
                                    "contradiction, should, interop, limit, advice")
    assert _refusal(document="FMI 2.0") == ("w: basis document 'FMI 2.0'; use one of "
                                            "FMI 3.0.2, fmi-ls-dae 1.0.0-alpha.1, fmi-ls-dae "
                                            "1.0.0-alpha.1 schema, paper 2026, importers, "
                                            "lsdae, none")
    assert _refusal(word="  ") == "w: basis gives no word (the text as written, or why none)"
    assert _refusal(section="") == "w: a must basis names the original's section"
    for document in ("importers", "lsdae", "none"):
        assert _refusal(document=document) == "w: a must basis names the original's section"
    assert _refusal(kind="definition", document="none") == (
        "w: a definition basis names the original's section")
    assert _refusal(word="it may") == ("w: a must basis quotes its keyword (must or shall or "
                                       "required or has to); it reads 'it may'")
    assert _refusal(part=True, word="it may") == ("w: a should basis quotes its keyword "
                                                  "(should or recommended); it reads 'it may'")
    assert _refusal(kind="interop", document="lsdae") == (
        "w: an interop basis names the importers")
    assert _refusal(kind="limit", document="importers") == (
        "w: a limit is lsdae's own (document \"lsdae\")")


def test_a_basis_takes_what_its_kind_allows():
    """The documents that are no original need no section where the kind allows it; the
    keyword check reads the word in any case."""
    assert _basis(dict(BASIS, word="It SHALL"), "w").word == "It SHALL"
    assert _basis({"kind": "limit", "document": "lsdae", "section": "", "word": "raise it"},
                  "w").severity == Severity.WARNING
    assert _basis({"kind": "interop", "document": "importers", "section": "", "word": "x"},
                  "w").severity == Severity.WARNING
    assert _basis({"kind": "advice", "document": "none", "section": "", "word": "no text"},
                  "w").severity == Severity.INFO
    assert _basis({"kind": "contradiction", "document": "lsdae", "section": "", "word": "x"},
                  "w").severity == Severity.ERROR
    part = _basis(PART, "w", part=True)
    assert (part.part, part.what) == ("dae-mode", "DAE mode")


def test_a_basis_cites_document_section_and_words():
    basis = Basis("must", "FMI 3.0.2", "2.4", "must")
    assert basis.cite() == "FMI 3.0.2, 2.4: \u201cmust\u201d"
    assert basis.describe() == "must (the text requires it); FMI 3.0.2, 2.4: \u201cmust\u201d"
    assert Basis("advice", "none", "", "no text").cite() == "no text"
    assert Basis("advice", "none", "3.1", "a note").cite() == "3.1: \u201ca note\u201d"
    assert Basis("limit", "lsdae", "", "raise it").cite() == "lsdae: \u201craise it\u201d"


def _spec(code: str, name: str, *parts: Basis, aliases=()) -> RuleSpec:
    return _rule(_table(code=code, name=name, aliases=list(aliases),
                        parts=[{"part": p.part, "what": p.what, "kind": p.kind,
                                "document": p.document, "section": p.section, "word": p.word}
                               for p in parts]), "x.toml")


def test_a_part_has_its_own_basis_and_severity_and_others_the_rules():
    advice = Basis("advice", "none", "", "no text", "robustness", "a call")
    limit = Basis("limit", "lsdae", "", "raise it", "budget", "time")
    rule = _spec("DAE998", "parts", advice, limit)
    assert rule.part("budget") is rule.parts[1] and rule.part("robustness") is rule.parts[0]
    assert rule.part("other") is rule.basis and rule.part(None) is rule.basis
    assert [rule.severity_of(p) for p in ("robustness", "budget", "other", None)] == [
        Severity.INFO, Severity.WARNING, Severity.ERROR, Severity.ERROR]


def test_the_catalogue_finds_rules_by_code_name_alias_and_prefix():
    rules = [_spec("DAE102", "b-rule"), _spec("DAE201", "c-rule"),
             _spec("DAE101", "a-rule", aliases=["old-a"])]
    catalogue = Catalogue(rules)
    assert [r.code for r in catalogue] == ["DAE101", "DAE102", "DAE201"]
    assert len(catalogue) == 3
    assert catalogue["dae102"] is rules[0] and catalogue["OLD-A"] is rules[2]
    assert catalogue["c-rule"] is rules[1]
    with pytest.raises(KeyError):
        catalogue["nothing"]
    assert catalogue.matching("a-rule") == [rules[2]]
    assert catalogue.matching("dae1") == [rules[2], rules[0]]
    assert catalogue.matching("DAE") == [rules[2], rules[0], rules[1]]
    assert catalogue.matching("") == [] and catalogue.matching("DAE3") == []
    with pytest.raises(CatalogueError, match="duplicate rule code DAE101"):
        Catalogue([*rules, _spec("DAE101", "other")])
    with pytest.raises(CatalogueError, match="duplicate rule name old-a"):
        Catalogue([*rules, _spec("DAE301", "old-a")])


def test_the_catalogue_is_read_from_every_toml_file_of_the_folder(tmp_path: Path):
    (tmp_path / "b.toml").write_text(
        '[[rule]]\ncode = "DAE002"\nname = "second"\nstage = "xml"\ndrafts = ["*"]\n'
        'spec = "s"\nsummary = "s"\nrationale = "r"\nbad = "b"\ngood = "g"\n'
        '[rule.basis]\nkind = "advice"\ndocument = "none"\nsection = ""\nword = "no text"\n'
        '[rule.options]\nlimit = 3\n')
    (tmp_path / "a.toml").write_text((tmp_path / "b.toml").read_text()
                                     .replace("DAE002", "DAE001").replace("second", "first"))
    (tmp_path / "notes.txt").write_text("[[rule]]\ncode = 'DAE003'\n")
    (tmp_path / "empty.toml").write_text("title = 'no rules'\n")
    catalogue = load_catalogue(tmp_path)
    assert [(r.code, r.source, r.option_values) for r in catalogue] == [
        ("DAE001", "a.toml", {"limit": 3}), ("DAE002", "b.toml", {"limit": 3})]


def test_the_default_catalogue_is_the_rules_folder_of_the_checkout():
    assert (rules_dir() / "core.toml").is_file()
    assert [r.code for r in load_catalogue()] == [r.code for r in default_catalogue()]
    assert len(default_catalogue()) > 50


def test_rule_options_are_overridden_by_type():
    catalogue = Catalogue([_rule(_table(code="DAE001", name="one",
                                        options={"rtol": 1e-8, "points": 3, "on": True,
                                                 "name": "x"}), "x.toml"),
                           _rule(_table(code="DAE002", name="two"), "x.toml")])
    assert with_options(catalogue, {}) is catalogue
    changed = with_options(catalogue, {"one": {"rtol": 1, "points": 5, "on": False}})
    assert changed["DAE001"].option_values == {"rtol": 1.0, "points": 5, "on": False,
                                               "name": "x"}
    assert [type(v) for _, v in changed["DAE001"].options] == [str, bool, int, float]
    assert changed["DAE002"] is catalogue["DAE002"]
    assert catalogue["DAE001"].option_values["rtol"] == 1e-8      # the original is unchanged
    with pytest.raises(ValueError) as caught:
        with_options(catalogue, {"nine": {"rtol": 1.0}})
    assert str(caught.value) == "no rule 'nine' (see `lsdae rules`)"
    with pytest.raises(ValueError) as caught:
        with_options(catalogue, {"DAE001": {"atol": 1.0}})
    assert str(caught.value) == "DAE001 one has no option 'atol' (its options: name, on, " \
                                "points, rtol)"
    with pytest.raises(ValueError) as caught:
        with_options(catalogue, {"DAE002": {"atol": 1.0}})
    assert str(caught.value) == "DAE002 two has no option 'atol' (its options: none)"
    for name, value in (("rtol", True), ("points", 1.5), ("on", 1), ("name", 2),
                        ("points", False)):
        with pytest.raises(ValueError, match=f"DAE001 one: option {name} takes a "):
            with_options(catalogue, {"DAE001": {name: value}})
