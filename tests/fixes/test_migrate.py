"""The migration of legacy manifests: alpha.1-shaped, XSD-valid, and meaning the same."""
from __future__ import annotations


import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conformance.model.drafts.detect import ALPHA1, LEGACY_DRAFTS, LS_NAMESPACE, detect_draft
from conformance.fixes.change import NoFix
from conformance.fixes.edits import apply_edits
from conformance.fixes.migrate import _Migration, migrate_manifest
from conformance.model.manifest import MANIFEST, read_manifest
from conformance.intake.schemas import validate_manifest
from conformance.intake.xmlsafe import parse_xml
from conformance.report.findings import Finding, Location, Severity, evidence
from tests.fixtures import MANIFESTS, scene_xml

DATA = MANIFESTS
MODEL = scene_xml("HelloWorldDAE")["modelDescription.xml"].read_bytes()
NOT_MIGRATABLE = {"attributes-only.xml", "formulation-higher-index.xml"}


def _read(data: bytes):
    tree = parse_xml(data, file=MANIFEST)[0]
    assert tree is not None
    draft = detect_draft(tree.getroot())
    return tree, draft, read_manifest(tree, draft=draft, file=MANIFEST)


def _meaning(manifest) -> tuple:
    structure = sorted((u.kind, u.vr, u.dependencies, u.dependencies_kind)
                       for u in manifest.structure)
    return structure, sorted(a.vr for a in manifest.algebraic)


def _migrate(data: bytes) -> bytes:
    _, draft, _ = _read(data)
    assert draft in LEGACY_DRAFTS
    return apply_edits(data, _Migration(MANIFEST, data, draft, MODEL).run())


def _assert_migrated(before: bytes, after: bytes) -> None:
    tree, draft, manifest = _read(after)
    assert draft == ALPHA1
    assert list(validate_manifest(tree, ALPHA1, file=MANIFEST)) == []
    assert _meaning(manifest) == _meaning(_read(before)[2])


LEGACY = sorted(p.name for p in DATA.glob("*.xml")
                if _read(p.read_bytes())[1] in LEGACY_DRAFTS)


@pytest.mark.parametrize("name", LEGACY)
def test_stored_legacy_manifests_migrate_or_say_why_not(name):
    data = (DATA / name).read_bytes()
    if name in NOT_MIGRATABLE:
        with pytest.raises(NoFix):
            _migrate(data)
        return
    after = _migrate(data)
    _assert_migrated(data, after)
    before_enable = [e.vr for e in _read(data)[2].enables]
    after_enable = [e.vr for e in _read(after)[2].enables]
    assert after_enable == [v for v in before_enable if v is not None] or \
        (after_enable == [1] and before_enable == [None])   # by name: dae is vr 1
    assert _migrate(after) == after if _read(after)[1] in LEGACY_DRAFTS else True


# --------------------------------------------------------------------------------------------
KINDS = ("dependent", "constant", "fixed", "tunable", "discrete")


@st.composite
def _unknown(draw, element: str, vr: int) -> str:
    deps = draw(st.lists(st.integers(1, 12), max_size=4, unique=True))
    text = f'valueReference="{vr}"'
    if deps or draw(st.booleans()):
        text += f' dependencies="{" ".join(map(str, deps))}"'
        if draw(st.booleans()):
            text += f' dependenciesKind="{" ".join(draw(st.sampled_from(KINDS)) for _ in deps)}"'
    return f"<{element} {text}/>"


@st.composite
def legacy_manifests(draw) -> bytes:
    shape = draw(st.sampled_from(("formulation", "flat", "ls-dae-root")))
    style = draw(st.sampled_from(("default", "none", "prefixed")))
    p = "fmi-ls:" if style == "prefixed" else ""
    root = "fmi-ls-dae" if shape == "ls-dae-root" else "fmiLayeredStandardManifest"
    enable = draw(st.sampled_from(("element", "attribute", "none")))
    version = draw(st.sampled_from(("0.1", "0.0.1", "", "0.1.0")))
    name = draw(st.sampled_from(("org.fmi-standard.fmi-ls-dae", "fmi-ls-dae")))
    period = draw(st.sampled_from((".", "")))
    attrs = [f'xmlns:fmi-ls="{LS_NAMESPACE}"']
    if style == "default":
        attrs.insert(0, f'xmlns="{LS_NAMESPACE}"')
    attrs += [f'fmi-ls:fmi-ls-name="{name}"', f'fmi-ls:fmi-ls-version="{version}"',
              f'fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI{period}"']
    if enable == "attribute":
        attrs.append('enableDAEModeVariable="1"')
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', f"<{p}{root}", *("  " + a for a in attrs)]
    lines[-1] += ">"
    if enable == "element":
        lines.append(f'  <{p}EnableDAE valueReference="1"/>')
    algebraic = draw(st.lists(st.integers(20, 40), min_size=1, max_size=3, unique=True))
    lines.append(f"  <{p}AlgebraicVariables>")
    for vr in algebraic:
        nominal = f' nominal="{draw(st.integers(1, 9))}"' if draw(st.booleans()) else ""
        lines.append(f'    <{p}AlgebraicVariable valueReference="{vr}"{nominal}/>')
    lines.append(f"  </{p}AlgebraicVariables>")
    children = []
    for vr in draw(st.lists(st.integers(50, 60), max_size=3, unique=True)):
        kind = draw(st.sampled_from(("Output", "ContinuousStateDerivative", "InitialUnknown")))
        children.append([draw(_unknown(p + kind, vr))])
    for vr in draw(st.lists(st.integers(100, 120), min_size=1, max_size=4, unique=True)):
        unknown = draw(_unknown("X", vr))[3:-2]
        index = ' index="1"' if draw(st.booleans()) else ""
        if shape == "flat":
            children.append([f"<{p}Residual {unknown}{index}/>"])
        else:
            children.append([f"<{p}Residual>", f"  <{p}Formulation{index} {unknown}/>",
                             f"</{p}Residual>"])
        if draw(st.booleans()):
            children[-1].insert(0, "<!-- a residual -->")
    order = draw(st.permutations(range(len(children))))
    lines.append(f"  <{p}ModelStructure>")
    for i in order:
        lines += ["    " + line for line in children[i]]
    lines += [f"  </{p}ModelStructure>", f"</{p}{root}>", ""]
    return "\n".join(lines).encode()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(legacy_manifests())
def test_generated_legacy_manifests_migrate_to_valid_alpha1_with_the_same_meaning(data):
    after = _migrate(data)
    _assert_migrated(data, after)
    assert [e.vr for e in _read(after)[2].enables] == \
        ([1] if b"EnableDAE " in data or b"enableDAEModeVariable" in data else [])


# --- the exact bytes of a migration, and the reasons given when there is none ----------------

HEADER = (f'xmlns:fmi-ls="{LS_NAMESPACE}" fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" '
          'fmi-ls:fmi-ls-version="{version}" '
          'fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI."')


def _flat(root_attributes: str, children: str) -> bytes:
    return (f'<fmiLayeredStandardManifest {HEADER.format(version="0.1")}{root_attributes}>'
            f"{children}</fmiLayeredStandardManifest>\n").encode()


def _edit(data: bytes, draft: str = "flat-index") -> bytes:
    return apply_edits(data, _Migration(MANIFEST, data, draft, MODEL).run())


def test_migration_writes_exactly_the_alpha1_text_and_keeps_the_rest():
    data = _flat(' enableDAEModeVariable="1"',
                 '<AlgebraicVariables>\n    <AlgebraicVariable valueReference="4"/>\n'
                 "  </AlgebraicVariables>\n  <ModelStructure>\n"
                 '    <Residual valueReference="7" index="1"/>\n'
                 '    <Output valueReference="4"/>\n  </ModelStructure>\n')
    # the enable parameter goes before the first child, on the root's line: no indentation
    assert _edit(data).decode() == (
        f'<fmiDAEManifest {HEADER.format(version="1.0.0-alpha.1")}>'
        '<EnableDAEParameter valueReference="1"/>\n<AlgebraicVariables>\n'
        '    <AlgebraicVariable valueReference="4"/>\n  </AlgebraicVariables>\n'
        "  <ModelStructure>\n"
        '    <Output valueReference="4"/>\n'
        '    <Residual valueReference="7"/>\n'
        "  </ModelStructure>\n</fmiDAEManifest>\n")


@pytest.mark.parametrize("children, reason", [
    ('<AlgebraicVariables/><EnableDAE valueReference="1"/>',
     "<EnableDAE> is not the root's first child"),
    ('<ModelStructure><Output valueReference="1"/><Other/></ModelStructure>',
     "<ModelStructure> holds an element alpha.1 does not know"),
])
def test_what_has_no_alpha1_form_says_why(children, reason):
    with pytest.raises(NoFix) as raised:
        _edit(_flat("", children))
    assert str(raised.value) == reason


def test_a_manifest_that_cannot_be_read_is_no_fix():
    class _Nothing:
        def read(self, name: str) -> None:
            return None

    finding = Finding("DAE021", "legacy-draft-shape", Severity.WARNING, "m",
                      Location(file=MANIFEST), evidence(draft="formulation"), "formulation")
    with pytest.raises(NoFix) as raised:
        migrate_manifest(_Nothing(), [finding])
    assert str(raised.value) == f"{MANIFEST} cannot be read"
