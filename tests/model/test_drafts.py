"""Draft recognition, migration hints and the legacy/unrecognised violations
(conformance/model/drafts/)."""
from __future__ import annotations


import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lxml import etree

from conformance.model.drafts import detect, migrate
from tests.fixtures import MANIFESTS

DATA = MANIFESTS

EXPECTED_DRAFT = {
    "alpha1.xml": detect.ALPHA1,
    "formulation-default-ns.xml": detect.FORMULATION,
    "formulation-unqualified.xml": detect.FORMULATION,
    "formulation-no-enable.xml": detect.FORMULATION,
    "formulation-enable-attribute.xml": detect.FORMULATION,
    "formulation-nominal.xml": detect.FORMULATION,
    "formulation-higher-index.xml": detect.FORMULATION,
    "ls-dae-root-prefixed.xml": detect.LS_DAE_ROOT,
    "ls-dae-root-mixed.xml": detect.LS_DAE_ROOT,
    "ls-dae-root-default-ns.xml": detect.LS_DAE_ROOT,
    "attributes-only.xml": detect.ATTRIBUTES_ONLY,
    "flat-index.xml": detect.FLAT_INDEX,
    "flat-index-no-index.xml": detect.FLAT_INDEX,
    "unknown-root.xml": detect.UNKNOWN,
}


def load(name: str) -> etree._Element:
    return etree.parse(str(DATA / name)).getroot()


def from_text(text: str) -> etree._Element:
    return etree.fromstring(text.encode())


def hints_of(name: str) -> tuple[str, ...]:
    root = load(name)
    return migrate.migration_hints(root, detect.detect_draft(root))


def test_every_data_file_has_an_expectation() -> None:
    assert sorted(p.name for p in DATA.glob("*.xml")) == sorted(EXPECTED_DRAFT)


@pytest.mark.parametrize("name", sorted(EXPECTED_DRAFT))
def test_detect_draft(name: str) -> None:
    assert detect.detect_draft(load(name)) == EXPECTED_DRAFT[name]


def test_shared_root_without_residuals_is_formulation() -> None:
    root = from_text(
        '<fmiLayeredStandardManifest xmlns="http://fmi-standard.org/fmi-ls-manifest">'
        "<AlgebraicVariables/><ModelStructure/></fmiLayeredStandardManifest>"
    )
    assert detect.detect_draft(root) == detect.FORMULATION


@pytest.mark.parametrize(
    "text",
    [
        '<fmiDAEManifest xmlns="urn:somebody-else"/>',
        '<fmiLayeredStandardManifest xmlns="urn:somebody-else"/>',
        "<fmiModelDescription/>",
    ],
)
def test_foreign_roots_are_unknown(text: str) -> None:
    assert detect.detect_draft(from_text(text)) == detect.UNKNOWN


def test_alpha1_root_in_ls_namespace_is_still_alpha1() -> None:
    # Recognised by name; the alpha.1 schema then reports the namespace as a schema violation.
    root = from_text('<fmiDAEManifest xmlns="http://fmi-standard.org/fmi-ls-manifest"/>')
    assert detect.detect_draft(root) == detect.ALPHA1


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("auto", "auto"),
        ("alpha1", detect.ALPHA1),
        (" Alpha.1 ", detect.ALPHA1),
        ("1.0.0-alpha.1", detect.ALPHA1),
        ("formulation", detect.FORMULATION),
        ("ls_dae_root", detect.LS_DAE_ROOT),
        ("fmi-dae", detect.ATTRIBUTES_ONLY),
        ("flat-index", detect.FLAT_INDEX),
        ("attributes-only", detect.ATTRIBUTES_ONLY),
    ],
)
def test_parse_draft_option(text: str, expected: str) -> None:
    assert detect.parse_draft_option(text) == expected


@pytest.mark.parametrize("text", ["", "alpha2", "unknown", "legacy"])
def test_parse_draft_option_rejects(text: str) -> None:
    # the message is what `lsdae check --draft` prints: it lists the ids a user may give
    with pytest.raises(ValueError) as raised:
        detect.parse_draft_option(text)
    assert str(raised.value) == (
        f"unknown draft {text!r}; use one of: auto, alpha1, formulation, ls-dae-root, "
        "flat-index, attributes-only")


def test_labels_cover_every_draft() -> None:
    assert set(detect.DRAFT_LABELS) == set(detect.ALL_DRAFTS) | {detect.UNKNOWN}


# --------------------------------------------------------------------------------------------
# legacy-draft-shape


@pytest.mark.parametrize("name", sorted(EXPECTED_DRAFT))
def test_one_legacy_violation_per_legacy_manifest(name: str) -> None:
    root = load(name)
    draft = detect.detect_draft(root)
    found = list(migrate.legacy_violations(root, draft, file="extra/m.xml"))
    if draft not in detect.LEGACY_DRAFTS:
        assert found == []
        return
    assert len(found) == 1
    violation = found[0]
    assert violation.rule == "legacy-draft-shape"
    assert violation.location.file == "extra/m.xml"
    assert violation.location.line == root.sourceline
    ev = dict(violation.evidence)
    assert ev["draft"] == draft
    assert ev["draft_label"] == detect.DRAFT_LABELS[draft]
    assert ev["hints"] == migrate.migration_hints(root, draft)
    assert ev["hints"], "a legacy manifest always needs at least the root rename"
    # The hints are repeated in the message so a console user sees them.
    assert all(hint in violation.message for hint in ev["hints"])


def test_shape_b_hints_are_exact_and_name_the_value_references() -> None:
    hints = hints_of("formulation-default-ns.xml")
    assert any("rename the root `<fmiLayeredStandardManifest>` to `<fmiDAEManifest>`" in h for h in hints)
    assert any('xmlns="http://fmi-standard.org/fmi-ls-manifest"' in h for h in hints)
    assert "rename `<EnableDAE>` to `<EnableDAEParameter>` (`<EnableDAEParameter valueReference=\"1\"/>`)" in hints
    assert (
        'flatten `<Residual><Formulation index="1" valueReference="6" dependencies="2 4 5"/></Residual>` '
        'into `<Residual valueReference="6" dependencies="2 4 5"/>`; drop `index`'
    ) in hints
    assert (
        'flatten `<Residual><Formulation index="1" valueReference="7" dependencies="2 4 5"/></Residual>` '
        'into `<Residual valueReference="7" dependencies="2 4 5"/>`; drop `index`'
    ) in hints
    assert 'set `fmi-ls:fmi-ls-version` to "1.0.0-alpha.1" (found "0.1")' in hints
    assert any(h.startswith("set `fmi-ls:fmi-ls-description`") for h in hints)
    assert not any("order" in h for h in hints)


def test_unqualified_shape_b_needs_no_namespace_removal() -> None:
    hints = hints_of("formulation-unqualified.xml")
    assert "rename the root `<fmiLayeredStandardManifest>` to `<fmiDAEManifest>`" in hints


def test_missing_enable_switch_asks_for_parameter_and_variable() -> None:
    hints = hints_of("formulation-no-enable.xml")
    (enable,) = [h for h in hints if "EnableDAEParameter" in h]
    assert enable == (
        "add an `<EnableDAEParameter valueReference=\"…\"/>` as the root's first child and the "
        "Boolean structural parameter it points to in modelDescription.xml "
        "(causality=\"structuralParameter\", variability=\"fixed\" or \"tunable\", "
        "start=\"false\")")
    # No index in the file, so nothing to drop.
    assert not any("drop `index`" in h for h in hints)


def test_enable_root_attribute_by_name() -> None:
    hints = hints_of("formulation-enable-attribute.xml")
    (enable,) = [h for h in hints if "enableDAEModeVariable" in h]
    assert 'enableDAEModeVariable="dae"' in enable and "`dae`" in enable


def test_enable_root_attribute_by_value_reference() -> None:
    text = (DATA / "formulation-enable-attribute.xml").read_text()
    root = from_text(text.replace('enableDAEModeVariable="dae"', 'enableDAEModeVariable="1"').split("?>", 1)[1])
    hints = migrate.migration_hints(root, detect.FORMULATION)
    assert (
        'replace the root attribute `enableDAEModeVariable="1"` by '
        '`<EnableDAEParameter valueReference="1"/>` as the root\'s first child'
    ) in hints


def test_order_hint() -> None:
    hints = hints_of("formulation-enable-attribute.xml")
    (order,) = [h for h in hints if "order" in h]
    assert "found ContinuousStateDerivative, Residual, Output" in order
    assert "move `Residual` after `Output`" in order
    # Residual after InitialUnknown is already in alpha.1 order.
    assert not any("order" in h for h in hints_of("formulation-nominal.xml"))


def test_nominal_and_header_hints() -> None:
    hints = hints_of("formulation-nominal.xml")
    (nominal,) = [h for h in hints if "nominal" in h]
    assert nominal.startswith("drop `nominal` from AlgebraicVariable")
    assert 'valueReference 4: `nominal="8"`' in nominal
    assert 'set `fmi-ls:fmi-ls-name` to "org.fmi-standard.fmi-ls-dae" (found "fmi-ls-dae")' in hints
    assert 'set `fmi-ls:fmi-ls-version` to "1.0.0-alpha.1" (found "")' in hints


def test_higher_index_residual_is_not_a_rename() -> None:
    root = load("formulation-higher-index.xml")
    hints = migrate.migration_hints(root, detect.FORMULATION)
    (higher,) = [h for h in hints if "higher-index" in h]
    assert higher == (
        "the `<Residual>` at line 16 has 2 Formulations (value references 6, 8): a higher-index "
        "constraint, which has no alpha.1 form (alpha.1 covers semi-explicit index-1 DAEs only); "
        "reduce the model's index so that it is described by index-1 residuals")
    assert not any('valueReference="6"' in h and h.startswith("flatten") for h in hints)
    assert any('valueReference="7"' in h and h.startswith("flatten") for h in hints)
    (violation,) = migrate.legacy_violations(root, detect.FORMULATION, file="m.xml")
    assert dict(violation.evidence)["higher_index_residual_lines"] == (16,)


def test_many_residuals_are_summarised() -> None:
    residuals = "".join(
        f'<Residual><Formulation index="1" valueReference="{100 + i}"/></Residual>' for i in range(10)
    )
    root = from_text(
        '<fmiLayeredStandardManifest><EnableDAE valueReference="1"/><AlgebraicVariables/>'
        f"<ModelStructure>{residuals}</ModelStructure></fmiLayeredStandardManifest>"
    )
    hints = migrate.migration_hints(root, detect.FORMULATION)
    flatten = [h for h in hints if h.startswith("flatten")]
    assert len(flatten) == 1 and 'valueReference="100"' in flatten[0]
    (rest,) = [h for h in hints if h.startswith("likewise")]
    assert "other 9" in rest and "101, 102" in rest and "109" in rest


def test_three_residuals_are_each_spelled_out() -> None:
    residuals = "".join(
        f'<Residual><Formulation valueReference="{100 + i}"/></Residual>' for i in range(3))
    root = from_text(
        '<fmiLayeredStandardManifest><EnableDAE valueReference="1"/>'
        f"<ModelStructure>{residuals}</ModelStructure></fmiLayeredStandardManifest>")
    hints = migrate.migration_hints(root, detect.FORMULATION)
    assert [h for h in hints if h.startswith("flatten")] == [
        f'flatten `<Residual><Formulation valueReference="{100 + i}"/></Residual>` into '
        f'`<Residual valueReference="{100 + i}"/>`' for i in range(3)]
    assert not any(h.startswith("likewise") for h in hints)


def test_a_nominal_without_value_reference_is_listed_as_unknown() -> None:
    root = from_text(
        '<fmiLayeredStandardManifest><EnableDAE valueReference="1"/><AlgebraicVariables>'
        '<AlgebraicVariable nominal="2"/></AlgebraicVariables></fmiLayeredStandardManifest>')
    (nominal,) = [h for h in migrate.migration_hints(root, detect.FORMULATION) if "nominal" in h]
    assert nominal == ('drop `nominal` from AlgebraicVariable (valueReference ?: `nominal="2"`); '
                       "alpha.1 takes nominal values only from the variables in "
                       "modelDescription.xml")


def test_ls_dae_root_prefix_hints() -> None:
    prefixed = hints_of("ls-dae-root-prefixed.xml")
    assert any(
        h.startswith("rename the root `<fmi-ls:fmi-ls-dae>` to `<fmiDAEManifest>`")
        and "from every child element" in h
        for h in prefixed
    )
    mixed = hints_of("ls-dae-root-mixed.xml")
    assert any("drop the `fmi-ls:` prefix from `<fmi-ls:EnableDAE>`" in h for h in mixed)
    default = hints_of("ls-dae-root-default-ns.xml")
    assert any("remove the default namespace declaration" in h for h in default)


def test_flat_index_hints() -> None:
    hints = hints_of("flat-index.xml")
    assert "drop `index` from `<Residual>` (value references 6, 7)" in hints
    assert not any("drop `index`" in h for h in hints_of("flat-index-no-index.xml"))


def test_attributes_only_hints() -> None:
    root = load("attributes-only.xml")
    hints = migrate.migration_hints(root, detect.ATTRIBUTES_ONLY)
    assert any("rename the root `<fmi-dae>`" in h and 'drop `isDaeFmu="true"`' in h for h in hints)
    assert any(h.startswith("add an `<EnableDAEParameter") for h in hints)
    assert any("<AlgebraicVariables>" in h and "<Residual" in h for h in hints)


def test_attributes_only_violation_says_what_is_missing() -> None:
    root = load("attributes-only.xml")
    (violation,) = migrate.legacy_violations(root, detect.ATTRIBUTES_ONLY, file="m.xml")
    assert violation.message.startswith(
        f"the manifest follows the {detect.DRAFT_LABELS[detect.ATTRIBUTES_ONLY]}, not fmi-ls-dae "
        "1.0.0-alpha.1; it declares the FMU a DAE-FMU but names no algebraic variables, residuals "
        "or enable parameter, so an importer has nothing to use. To migrate: ")


def test_alpha1_and_unknown_have_no_hints() -> None:
    assert migrate.migration_hints(load("alpha1.xml"), detect.ALPHA1) == ()
    assert migrate.migration_hints(load("unknown-root.xml"), detect.UNKNOWN) == ()


# --------------------------------------------------------------------------------------------
# draft-unrecognised


def test_unrecognised_violation() -> None:
    root = load("unknown-root.xml")
    (violation,) = detect.unrecognised_violations(root, file="m.xml")
    assert violation.rule == "draft-unrecognised"
    assert violation.location.line == root.sourceline
    assert dict(violation.evidence)["root"] == "daeManifest"
    assert dict(violation.evidence)["namespace"] == etree.QName(root).namespace
    assert violation.subject == "daeManifest"
    other = from_text('<x:fmiDAEManifest xmlns:x="urn:other"/>')
    (foreign,) = detect.unrecognised_violations(other, file="m.xml")
    assert dict(foreign.evidence) == {
        "root": "x:fmiDAEManifest", "namespace": "urn:other",
        "known_roots": ("fmiDAEManifest", "fmiLayeredStandardManifest", "fmi-ls-dae", "fmi-dae")}
    assert (foreign.subject, foreign.location.path) == ("x:fmiDAEManifest", "/x:fmiDAEManifest")
    for name, draft in EXPECTED_DRAFT.items():
        if draft != detect.UNKNOWN:
            assert list(detect.unrecognised_violations(load(name), file="m.xml")) == []


# --------------------------------------------------------------------------------------------
# Robustness: recognition and hints never raise, whatever the tree looks like.

_NAMES = st.sampled_from([
    "fmiDAEManifest", "fmiLayeredStandardManifest", "fmi-ls-dae", "fmi-dae", "EnableDAE",
    "EnableDAEParameter", "AlgebraicVariables", "AlgebraicVariable", "ModelStructure", "Residual",
    "Formulation", "Output", "InitialUnknown", "Invariant", "Annotations", "x",
])
_NAMESPACES = st.sampled_from([None, detect.LS_NAMESPACE, "urn:other"])
_ATTRIBUTES = st.dictionaries(
    st.sampled_from(["valueReference", "index", "nominal", "dependencies", "enableDAEModeVariable",
                     "isDaeFmu", "{http://fmi-standard.org/fmi-ls-manifest}fmi-ls-version"]),
    st.text(alphabet="0123456789 {}<>&\"ab", max_size=6),
    max_size=3,
)


@st.composite
def _trees(draw: st.DrawFn, depth: int = 0) -> etree._Element:
    namespace, name = draw(_NAMESPACES), draw(_NAMES)
    element = etree.Element(f"{{{namespace}}}{name}" if namespace else name, draw(_ATTRIBUTES))
    if depth < 3:
        for child in draw(st.lists(_trees(depth + 1), max_size=3)):
            element.append(child)
    return element


@settings(max_examples=200, deadline=None)
@given(_trees())
def test_never_raises(root: etree._Element) -> None:
    draft = detect.detect_draft(root)
    assert draft in detect.ALL_DRAFTS + (detect.UNKNOWN,)
    for candidate in detect.ALL_DRAFTS + (detect.UNKNOWN,):
        migrate.migration_hints(root, candidate)
        for violation in migrate.legacy_violations(root, candidate, file="m.xml"):
            assert violation.rule == "legacy-draft-shape" and violation.message
    list(detect.unrecognised_violations(root, file="m.xml"))
