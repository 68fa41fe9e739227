"""The catalogue says which rules `lsdae fix` repairs, and it says so where users look."""
from __future__ import annotations

import json

import pytest

from conformance.report.catalogue import CatalogueError, _rule, default_catalogue
from conformance.commands.cli import main
from conformance.run.engine import check_fmu
from conformance.report.findings import Report
from conformance.fixes.fixers import UNSAFE_FIXERS
from conformance.reporters import json_report
from tests.fixes.conftest import FIXABLE, STATIC
from tests.fixtures import all_cases, materialise


def test_the_fixes_in_the_catalogue_are_the_fixers():
    safe = sorted(r.code for r in default_catalogue() if r.fix_kind == "safe")
    unsafe = sorted(r.code for r in default_catalogue() if r.fix_kind == "unsafe")
    assert safe == FIXABLE
    assert unsafe == sorted({c for codes, _ in UNSAFE_FIXERS.values() for c in codes})


def test_a_fix_entry_names_its_kind():
    table = {k: "x" for k in ("code", "name", "stage", "spec", "summary", "rationale", "bad",
                              "good")}
    table.update(code="DAE999", stage="static", drafts=["*"],
                 basis={"kind": "must", "document": "FMI 3.0.2", "section": "2.4.7",
                        "word": "it must"})
    assert _rule({**table, "fix": "safe: do it"}, "t.toml").fix_kind == "safe"
    assert _rule({**table, "fix": "unsafe: observed"}, "t.toml").fix_kind == "unsafe"
    assert _rule(table, "t.toml").fix_kind is None
    assert _rule({**table, "fix": "none: the binary must"}, "t.toml").fix_kind is None
    for bad in ("maybe: x", "safe:", "safe: ", "none:", 3):
        with pytest.raises(CatalogueError):
            _rule({**table, "fix": bad}, "t.toml")


def test_json_findings_say_whether_a_fix_exists(tmp_path):
    case = next(c for c in all_cases() if c.id == "DAE010/fail-2")
    fmu = check_fmu(materialise(case, tmp_path), options=STATIC)
    data = json.loads(json_report.render(Report("x", (fmu,)), default_catalogue()))
    fixes = {f["code"]: f["fix"] for f in data["fmus"][0]["findings"]}
    assert fixes["DAE010"] == "safe"
    assert fixes["DAE401"] is None


@pytest.mark.parametrize("code,mark", [("DAE104", "fix"), ("DAE742", "fix?"), ("DAE401", ""),
                                       ("DAE402", "")])
def test_explain_and_rules_show_the_fix(code, mark, capsys):
    rule = default_catalogue()[code]
    assert main(["explain", code]) == 0
    if rule.fix:
        assert rule.fix in capsys.readouterr().out
    assert main(["rules"]) == 0
    line = next(l for l in capsys.readouterr().out.splitlines() if l.startswith(code))
    assert line.split()[3] == mark if mark else line.split()[3] not in ("fix", "fix?")
