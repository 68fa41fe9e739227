"""Unsafe fixes from the probes' observations: they only widen a claim, and only on request."""
from __future__ import annotations

import pytest

from conformance.commands.cli import main
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Finding, Location, Severity, evidence
from conformance.commands.fix import fix_fmu
from conformance.fixes.apply import keys
from conformance.fixes.edits import apply_edits
from conformance.fixes.fixers import UNSAFE_FIXERS
from conformance.fixes.observed import add_observed_dependencies, find_path, observed_kinds
from conformance.fixes.xmltext import element_tree
from tests.fixtures.defects import DEFECTS, build

DYNAMIC = EngineOptions(probes=True, endurance="off")
UNSAFE = sorted({c for codes, _ in UNSAFE_FIXERS.values() for c in codes})
PATH = "/m/ModelStructure/Residual[2]"
DOC = (b'<m>\n <ModelStructure>\n  <Residual valueReference="5" dependencies="1 2"/>\n'
       b'  <Residual valueReference="6" dependencies="1 4 9" '
       b'dependenciesKind="dependent constant tunable"/>\n </ModelStructure>\n</m>\n')


class _Files:
    """The least of a Package the observed fixers use."""

    def __init__(self, data: bytes):
        self.data = data

    def read(self, name: str) -> bytes:
        return self.data


def _finding(code: str, vr: int, path: str = PATH) -> Finding:
    return Finding(code, "x", Severity.ERROR, "m", Location(file="f.xml", path=path),
                   evidence(known_value_reference=vr), subject=f"d/d{vr}")


def _apply(change) -> bytes:
    return apply_edits(DOC, change.edits)


def test_find_path_follows_the_location_path():
    root = element_tree(DOC)
    assert find_path(root, PATH).tag.attribute("valueReference").value == "6"
    assert find_path(root, "/m/ModelStructure/Residual").tag.attribute(
        "valueReference").value == "5"
    assert find_path(root, "/m/ModelStructure/Residual[3]") is None
    assert find_path(root, "/other/ModelStructure") is None


def test_an_observed_dependency_is_added_in_order_as_dependent():
    change = add_observed_dependencies(_Files(DOC), [_finding("DAE742", 3),
                                                     _finding("DAE742", 12)])
    out = _apply(change)
    assert b'dependencies="1 3 4 9 12" dependenciesKind="dependent dependent constant tunable ' \
           b'dependent"' in out
    assert len(change.fixes) == 2


def test_a_missing_dependencies_attribute_already_means_everything():
    path = "/m/ModelStructure/Residual[1]"
    doc = DOC.replace(b' dependencies="1 2"', b"")
    change = add_observed_dependencies(_Files(doc), [_finding("DAE742", 3, path)])
    assert change is None


def test_an_observed_kind_becomes_dependent_and_nothing_becomes_constant():
    change = observed_kinds(_Files(DOC), [_finding("DAE744", 4)])
    out = _apply(change)
    assert b'dependenciesKind="dependent dependent tunable"' in out
    assert out.count(b"constant") == 0 and out.count(b"dependencies=") == DOC.count(
        b"dependencies=")


XML_DEFECTS = [d for d in DEFECTS if d.code in UNSAFE and not d.defines]


def test_every_unsafe_rule_with_an_xml_defect_is_covered():
    assert {d.code for d in XML_DEFECTS} == set(UNSAFE)


@pytest.mark.parametrize("defect", XML_DEFECTS, ids=lambda d: d.id)
def test_unsafe_fixes_remove_the_observed_fault_and_nothing_gets_worse(defect, tmp_path):
    source = build(defect)
    assert not fix_fmu(source, options=DYNAMIC).package.modified   # only when asked
    outcome = fix_fmu(source, options=DYNAMIC, unsafe=True)
    assert [c.fixer for c in outcome.applied] and not outcome.refused
    out = tmp_path / "fixed.fmu"
    outcome.package.write(out)
    before = check_fmu(source, options=DYNAMIC).findings
    after = check_fmu(out, options=DYNAMIC).findings
    assert defect.code in {f.code for f in before}
    assert defect.code not in {f.code for f in after}
    assert not keys(after) - keys(before)


def test_unsafe_fixes_need_the_probes(tmp_path):
    source = build(XML_DEFECTS[0])
    assert main(["fix", str(source), "--diff", "--unsafe-fixes", "--no-probes"]) == 2
