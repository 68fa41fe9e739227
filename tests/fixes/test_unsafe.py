"""Unsafe fixes from the probes' observations: they only widen a claim, and only on request."""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from conformance.commands.cli import main
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Finding, FmuReport, Location, Severity, evidence, thaw
from conformance.commands.fix import fix_fmu
from conformance.fixes.apply import fix, keys
from conformance.fixes.archive import Package
from conformance.fixes.edits import apply_edits
from conformance.fixes.fixers import UNSAFE_FIXERS
from conformance.fixes.observed import add_observed_dependencies, find_path, observed_kinds
from conformance.fixes.xmltext import element_tree
from conformance.intake.fmu import default_limits
from tests.checkkit import by_content, checked
from tests.fixtures import DEFECTS, build_defect, variant

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
    source = build_defect(defect)
    assert not fix_fmu(source, options=DYNAMIC).package.modified   # only when asked
    outcome = fix_fmu(source, options=DYNAMIC, unsafe=True)
    assert [c.fixer for c in outcome.applied] and not outcome.refused
    out = tmp_path / "fixed.fmu"
    outcome.package.write(out)
    before = check_fmu(source, options=DYNAMIC).findings
    # the fixes of these defects give the same FMU (the scene as it was): checked once
    after = checked(by_content(out), options=DYNAMIC).findings
    assert defect.code in {f.code for f in before}
    assert defect.code not in {f.code for f in after}
    assert not keys(after) - keys(before)


def test_unsafe_fixes_need_the_probes(tmp_path):
    source = build_defect(XML_DEFECTS[0])
    assert main(["fix", str(source), "--diff", "--unsafe-fixes", "--no-probes"]) == 2


MANIFEST_PATH = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
RESIDUAL = "/fmiDAEManifest/ModelStructure/Residual[1]"


def _seen(vr: int) -> Finding:
    return Finding("DAE744", "dependencies-kind-violated", Severity.ERROR, "m",
                   Location(file=MANIFEST_PATH, path=RESIDUAL),
                   evidence(known_value_reference=vr), subject=f"d(r)/d({vr})")


def _report(*findings: Finding) -> FmuReport:
    return FmuReport("fmu", "alpha1", findings, rules_run=("DAE744",))


@pytest.mark.parametrize("rounds, applied", [(1, 0), (3, 2)])
def test_a_fixer_goes_on_to_a_fixpoint_when_its_repair_reveals_more_of_its_kind(
        rounds, applied, fmu):
    """The re-check after the first repair (d(r)/d(2)) observes another false kind (d(r)/d(4)):
    one round refuses the fix as adding a finding, a fixpoint repairs both."""
    source = fmu("HelloWorldDAE")
    rechecks = iter([_report(_seen(4)), _report()])
    outcome = fix(source, Package(source, default_limits()), _report(_seen(2)),
                  lambda _: next(rechecks), UNSAFE_FIXERS, rounds=rounds)
    assert len(outcome.applied) == applied
    if applied:
        text = outcome.package.read(MANIFEST_PATH).decode()
        assert 'dependencies="2 4 5" dependenciesKind="dependent dependent constant"' in text
        assert not outcome.refused
    else:
        assert "it would add a finding (DAE744" in outcome.refused[0][1]


def _codes(findings) -> set[str]:
    """The rules of ``findings`` and of the places folded into them."""
    return {f.code for f in findings} | {a["rule"] for f in findings
                                         for a in thaw(f.evidence_dict().get("also", ()))}


def _robertson_false_kinds(derivatives: int, initial: bool) -> Path:
    """Robertson declaring ``constant`` what is not: the first ``derivatives`` of the four
    partials of der(y1), der(y2) in y2 and y3 (1e4 y3, 1e4 y2, ... vary), and with ``initial``
    der(y1)'s InitialUnknown in y1 and y2 too."""
    kinds = [["constant", "dependent", "dependent"], ["constant", "dependent", "dependent"]]
    for k in range(derivatives):
        kinds[k // 2][1 + k % 2] = "constant"
    edits = [(f'<ContinuousStateDerivative valueReference="{vr}" dependencies="2 4 6" '
              'dependenciesKind="constant dependent dependent"/>',
              f'<ContinuousStateDerivative valueReference="{vr}" dependencies="2 4 6" '
              f'dependenciesKind="{" ".join(kinds[n])}"/>') for n, vr in enumerate((3, 5))]
    if initial:
        edits.append(('<InitialUnknown valueReference="3" dependencies="2 4" '
                      'dependenciesKind="dependent dependent"/>',
                      '<InitialUnknown valueReference="3" dependencies="2 4" '
                      'dependenciesKind="constant constant"/>'))
    return variant("Robertson", manifest_edits=edits)


@pytest.mark.parametrize("derivatives, initial", [(1, False), (4, False), (4, True)],
                         ids=["one-kind", "four-kinds-grouped", "four-kinds-and-initial"])
def test_every_false_constant_kind_is_repaired_and_the_result_is_a_fixpoint(
        derivatives, initial, tmp_path):
    """One false kind, or so many that the check groups them into one finding (a fixer needs
    each one's evidence), in Continuous-Time and in Initialization Mode: all come out
    ``dependent``, the check is clean of both rules, the binary is untouched, and fixing the
    result again changes nothing."""
    source = _robertson_false_kinds(derivatives, initial)
    before = check_fmu(source, options=DYNAMIC)
    assert "DAE744" in {f.code for f in before.findings}
    # Initialization Mode's false kind of der(y1) shares its unknown with Continuous-Time
    # Mode's: one cause, DAE744's finding, with DAE751's place in its evidence (issue 29)
    assert ("DAE751" in _codes(before.findings)) == initial
    outcome = fix_fmu(source, options=DYNAMIC, unsafe=True)
    assert not outcome.refused, outcome.refused
    out = tmp_path / "fixed.fmu"
    outcome.package.write(out)
    after = check_fmu(out, options=DYNAMIC)
    assert not {"DAE744", "DAE751"} & _codes(after.findings)
    assert not keys(after.findings) - keys(before.findings)
    with zipfile.ZipFile(source) as a, zipfile.ZipFile(out) as b:
        binaries = [n for n in a.namelist() if n.startswith("binaries/")]
        assert binaries and all(a.read(n) == b.read(n) for n in binaries)
    assert not fix_fmu(out, options=DYNAMIC, unsafe=True).package.modified


def test_find_path_reads_indices_of_more_than_one_digit():
    residuals = "".join(f'<Residual valueReference="{vr}"/>' for vr in range(100, 112))
    root = element_tree(f"<m><ModelStructure>{residuals}</ModelStructure></m>".encode())
    assert find_path(root, "/m/ModelStructure/Residual[10]").tag.attribute(
        "valueReference").value == "109"
    assert find_path(root, "/m/ModelStructure/Residual[12]").tag.attribute(
        "valueReference").value == "111"


def test_an_observed_kind_keeps_the_attribute_quote_and_the_other_tokens_as_written():
    doc = (b"<m>\n <ModelStructure>\n  <Residual valueReference='6' dependencies='1 4' "
           b"dependenciesKind='constant x\"y'/>\n </ModelStructure>\n</m>\n")
    change = observed_kinds(_Files(doc), [_finding("DAE744", 1,
                                                   "/m/ModelStructure/Residual[1]")])
    assert apply_edits(doc, change.edits) == doc.replace(b"'constant x", b"'dependent x")
