"""Schema validation of manifests and modelDescription.xml (conformance/intake/schemas.py), and
loading the schemas offline (conformance/intake/schema_loader.py)."""
from __future__ import annotations

import socket
from pathlib import Path

import pytest
from lxml import etree

from conformance.intake import schema_loader, schemas
from conformance.model.drafts import detect, migrate
from conformance.report.findings import Location, Violation, evidence
from conformance.intake.schema_messages import clean_message
from tests.fixtures import MANIFESTS

DATA = MANIFESTS
SHAPES = sorted(p.name for p in DATA.glob("*.xml") if p.name != "unknown-root.xml")

# (file, text to replace, replacement): each breaks the structure on one line of the file; the
# expected line is the line on which the replacement ends up.
BROKEN = [
    ("alpha1.xml", '<AlgebraicVariable valueReference="5"/>', '<AlgebraicVariable valueReference="five"/>'),
    ("alpha1.xml", '<InitialUnknown valueReference="4"/>', '<InitialUnknown valueReference="4"/><Bogus/>'),
    ("alpha1.xml", '<EnableDAEParameter valueReference="1"/>', '<EnableDAE valueReference="1"/>'),
    ("alpha1.xml", '<AlgebraicVariable valueReference="4"/>', '<AlgebraicVariable valueReference="4" nominal="8"/>'),
    ("alpha1.xml", '<InitialUnknown valueReference="3"/>',
     '<Residual valueReference="9"/><InitialUnknown valueReference="3"/>'),
    ("alpha1.xml", '<ContinuousStateDerivative valueReference="3" dependencies="4" dependenciesKind="constant"/>',
     '<ContinuousStateDerivative valueReference="3" dependencies="4" dependenciesKind="linear"/>'),
    ("formulation-default-ns.xml", '<AlgebraicVariable valueReference="5"/>',
     '<AlgebraicVariable valueReference="-5"/>'),
    ("formulation-default-ns.xml", '<Formulation index="1" valueReference="7" dependencies="2 4 5"/>',
     '<Formulation index="first" valueReference="7" dependencies="2 4 5"/>'),
    ("formulation-unqualified.xml", '<ContinuousStateDerivative valueReference="3" dependencies="4"/>',
     '<ContinuousStateDerivative dependencies="4"/>'),
    ("formulation-no-enable.xml", '<ContinuousStateDerivative valueReference="3" dependencies="4"/>',
     '<ContinuousStateDerivative valueReference="3" dependencies="4"/><Bogus/>'),
    ("formulation-enable-attribute.xml", '<Output valueReference="4" dependencies="2 4"/>',
     '<Output valueReference="4" dependencies="2 x"/>'),
    ("formulation-nominal.xml", '<EnableDAE valueReference="1"/>', '<EnableDAE valueReference="1" extra="yes"/>'),
    ("formulation-higher-index.xml", '<Formulation index="2" valueReference="8" dependencies="2 3 4 5"/>',
     '<Formulation index="2" dependencies="2 3 4 5"/>'),
    ("ls-dae-root-prefixed.xml", '<fmi-ls:AlgebraicVariable valueReference="5"/>',
     '<fmi-ls:AlgebraicVariable valueReference="5"><fmi-ls:Bogus/></fmi-ls:AlgebraicVariable>'),
    ("ls-dae-root-mixed.xml", '<ContinuousStateDerivative valueReference="3" dependencies="4"/>',
     '<ContinuousStateDerivative valueReference="3" dependencies="4"/><Residual valueReference="6"/>'),
    ("ls-dae-root-default-ns.xml", '<EnableDAE valueReference="1" />', '<EnableDAE />'),
    ("attributes-only.xml", 'isDaeFmu="true"/>', 'isDaeFmu="maybe"/>'),
    ("attributes-only.xml", 'isDaeFmu="true"/>', 'isDaeFmu="true"><AlgebraicVariables/></fmi-dae>'),
    ("flat-index.xml", '<Residual valueReference="7" index="1" dependencies="2 4 5"/>',
     '<Residual valueReference="7" index="one" dependencies="2 4 5"/>'),
    ("flat-index-no-index.xml", '<Residual valueReference="6" dependencies="2 4 5" dependenciesKind="dependent dependent dependent"/>',
     '<Residual valueReference="6"><Formulation valueReference="6"/></Residual>'),
]


def parse_file(name: str) -> etree._ElementTree:
    return etree.parse(str(DATA / name))


def parse_text(text: str) -> etree._ElementTree:
    return etree.ElementTree(etree.fromstring(text.encode()))


def manifest_violations(tree: etree._ElementTree, draft: str | None = None) -> list[Violation]:
    root = tree.getroot()
    return list(schemas.validate_manifest(tree, draft or detect.detect_draft(root), file="extra/m.xml"))


def assert_clean_messages(found: list[Violation]) -> None:
    for violation in found:
        assert violation.rule == "schema-violation"
        assert violation.message and "{" not in violation.message and "}" not in violation.message
        assert "http://" not in violation.message or "namespace" in violation.message


def test_every_draft_has_a_schema_file() -> None:
    assert set(schema_loader.SCHEMA_FILES) == set(detect.ALL_DRAFTS)
    for name in schema_loader.SCHEMA_FILES.values():
        assert (schema_loader.schema_dir() / name).is_file()


@pytest.mark.parametrize("draft", detect.ALL_DRAFTS)
def test_every_schema_loads(draft: str) -> None:
    assert isinstance(schema_loader.manifest_schema(draft), etree.XMLSchema)


@pytest.mark.parametrize("name", SHAPES)
def test_each_shape_validates_against_its_own_schema(name: str) -> None:
    assert manifest_violations(parse_file(name)) == []


@pytest.mark.parametrize(("name", "old", "new"), BROKEN)
def test_broken_variant_reports_the_right_line(name: str, old: str, new: str) -> None:
    text = (DATA / name).read_text()
    assert text.count(old) == 1
    broken = text.replace(old, new)
    line = broken.splitlines().index(next(ln for ln in broken.splitlines() if new.splitlines()[0] in ln)) + 1
    tree = etree.ElementTree(etree.fromstring(broken.encode()))
    found = manifest_violations(tree, detect.detect_draft(etree.fromstring(text.encode())))
    assert found, f"{name}: no schema violation for {new!r}"
    assert_clean_messages(found)
    assert {v.location.line for v in found} == {line}, [(v.location.line, v.message) for v in found]
    assert all(v.location.file == "extra/m.xml" and v.location.path for v in found)


def test_alpha1_root_in_a_namespace_is_one_violation() -> None:
    text = (DATA / "alpha1.xml").read_text().replace(
        "<fmiDAEManifest ", '<fmiDAEManifest xmlns="http://fmi-standard.org/fmi-ls-manifest" ')
    found = manifest_violations(parse_text(text.split("?>", 1)[1]))
    assert len(found) == 1 and found[0].location.line is not None
    assert_clean_messages(found)


def test_alpha1_header_and_enable_cardinality_are_left_to_the_semantic_rules() -> None:
    # Unqualified fmi-ls-* attributes (ls-name-mismatch & co. explain them) and a missing or
    # repeated EnableDAEParameter (enable-parameter-missing/-duplicate) are not schema errors.
    text = (DATA / "alpha1.xml").read_text().replace("fmi-ls:fmi-ls-", "fmi-ls-")
    assert manifest_violations(parse_text(text.split("?>", 1)[1])) == []
    text = (DATA / "alpha1.xml").read_text()
    enable = next(line for line in text.splitlines() if "<EnableDAEParameter" in line)
    for variant in (text.replace(enable, ""), text.replace(enable, enable + enable)):
        assert manifest_violations(parse_text(variant.split("?>", 1)[1])) == []
    # An unknown attribute on the root is still a schema violation.
    broken = text.replace("<fmiDAEManifest ", '<fmiDAEManifest bogus="1" ')
    assert len(manifest_violations(parse_text(broken.split("?>", 1)[1]))) == 1


def test_forced_draft_with_another_root() -> None:
    tree = parse_file("alpha1.xml")
    found = manifest_violations(tree, detect.FORMULATION)
    assert len(found) == 1 and found[0].location.line == tree.getroot().sourceline
    assert dict(found[0].evidence)["expected_root"] == "fmiLayeredStandardManifest"
    assert found[0].message == (
        "the root element is <fmiDAEManifest>, but the Formulation draft (spring/summer 2026, "
        "Reference-FMUs) has the root <fmiLayeredStandardManifest>")
    assert (found[0].subject, found[0].location.path) == ("/fmiDAEManifest", "/fmiDAEManifest")
    # a legacy root in another namespace: the evidence names the namespace
    (other,) = manifest_violations(parse_text('<fmi-dae xmlns="urn:other"/>'), detect.ATTRIBUTES_ONLY)
    assert dict(other.evidence) == {"schema": "fmi-ls-dae-attributes-only.xsd", "root": "fmi-dae",
                                    "namespace": "urn:other", "expected_root": "fmi-dae"}
    assert (other.rule, other.part) == ("schema-violation", "legacy-draft-schema")


def test_unknown_draft_yields_nothing() -> None:
    assert manifest_violations(parse_file("unknown-root.xml"), detect.UNKNOWN) == []


def test_validate_accepts_an_element_too() -> None:
    root = parse_file("formulation-default-ns.xml").getroot()
    assert list(schemas.validate_manifest(root, detect.FORMULATION, file="m.xml")) == []


def test_legacy_validation_leaves_the_tree_alone() -> None:
    tree = parse_file("formulation-default-ns.xml")
    before = etree.tostring(tree)
    manifest_violations(tree)
    assert etree.tostring(tree) == before


# --------------------------------------------------------------------------------------------
# modelDescription.xml

MODEL_DESCRIPTION = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="Tiny" instantiationToken="tok">
  <ModelExchange modelIdentifier="Tiny"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Boolean name="dae" valueReference="1" causality="structuralParameter" variability="fixed" start="false"/>
    <Float64 name="x" valueReference="2" causality="local" start="1"/>
    <Float64 name="der(x)" valueReference="3" causality="local" derivative="2"/>
  </ModelVariables>
  <ModelStructure>
    <ContinuousStateDerivative valueReference="3"/>
    <InitialUnknown valueReference="3"/>
  </ModelStructure>
</fmiModelDescription>
"""


def md_violations(text: str) -> list[Violation]:
    return list(schemas.validate_model_description(etree.ElementTree(etree.fromstring(text.encode()))))


def test_model_description_valid() -> None:
    assert md_violations(MODEL_DESCRIPTION) == []


def test_model_description_bad_causality() -> None:
    text = MODEL_DESCRIPTION.replace('name="x" valueReference="2" causality="local"',
                                     'name="x" valueReference="2" causality="inptu"')
    (violation,) = md_violations(text)
    assert violation.rule == "schema-violation"
    assert violation.location.file == "modelDescription.xml"
    assert violation.location.line == 7
    assert violation.location.path == "/fmiModelDescription/ModelVariables/Float64[2]"
    assert violation.subject == violation.location.path
    assert_clean_messages([violation])


def test_model_description_follow_up_errors_are_dropped() -> None:
    # libxml2 reports a bad boolean twice (atomic type, then list type); we keep the first.
    text = MODEL_DESCRIPTION.replace('start="false"', 'start="maybe"')
    (violation,) = md_violations(text)
    assert violation.location.line == 6


def test_model_description_wrong_root() -> None:
    (violation,) = md_violations('<fmiModelDescription xmlns="urn:x" fmiVersion="3.0"/>')
    assert violation.location.line == 1
    assert violation == Violation(
        message="the root element is <fmiModelDescription>; an FMI 3.0 modelDescription.xml has "
                "the root <fmiModelDescription> in no namespace",
        location=Location(file="modelDescription.xml", line=1, path="/fmiModelDescription"),
        evidence=evidence(schema="fmi3ModelDescription.xsd"),
        subject="/fmiModelDescription", rule="schema-violation")
    (build,) = schemas.validate_build_description(etree.fromstring("<x:b xmlns:x='urn:x'/>"))
    assert (build.rule, build.subject, build.location.file) == (
        "build-description-invalid", "/x:b", "sources/buildDescription.xml")


def _big_model_description(count: int, bad_at: int | None = None) -> bytes:
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<fmiModelDescription fmiVersion="3.0" modelName="Big" instantiationToken="tok">\n'
        '<ModelExchange modelIdentifier="Big"/>\n<ModelVariables>\n'
        '<Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>\n'
    ]
    for i in range(1, count):
        causality = "inptu" if i == bad_at else "local"
        parts.append(
            f'<Float64 name="component_{i}.sub.value" valueReference="{i}" causality="{causality}" '
            f'variability="continuous" description="variable number {i} of a large model" start="0.0"/>\n'
        )
    parts.append("</ModelVariables>\n<ModelStructure/>\n</fmiModelDescription>\n")
    return "".join(parts).encode()


def test_model_description_large_file_keeps_big_line_numbers() -> None:
    data = _big_model_description(100_000, bad_at=90_000)
    assert len(data) > 15_000_000
    tree = etree.ElementTree(etree.fromstring(data, etree.XMLParser(huge_tree=True)))
    schema_loader.model_description_schema()  # loading is a one-off cost, not part of the budget
    found = list(schemas.validate_model_description(tree))  # its speed: `make bench`
    (violation,) = found
    # Beyond libxml2's 16-bit line field lines come from a fallback that may land on the next
    # line; the finding must agree with the element's sourceline (what every other rule reports).
    element = tree.getroot()[1][90_000]
    assert element.get("causality") == "inptu"
    assert violation.location.line == element.sourceline
    assert abs(violation.location.line - 90_005) <= 1


# --------------------------------------------------------------------------------------------
# Offline


@pytest.fixture
def no_network(monkeypatch: pytest.MonkeyPatch) -> list[tuple[object, ...]]:
    attempts: list[tuple[object, ...]] = []

    def refuse(*args: object, **kwargs: object) -> None:
        attempts.append(args)
        raise AssertionError("network access attempted")

    monkeypatch.setattr(socket, "socket", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(socket, "getaddrinfo", refuse)
    schema_loader.clear_schema_cache()
    yield attempts
    schema_loader.clear_schema_cache()


def test_loading_and_validating_never_touch_the_network(no_network: list[tuple[object, ...]]) -> None:
    schema_loader.model_description_schema()
    for draft in detect.ALL_DRAFTS:
        schema_loader.manifest_schema(draft)
    for name in SHAPES:  # one of them carries an https xsi:schemaLocation
        assert manifest_violations(parse_file(name)) == []
    assert md_violations(MODEL_DESCRIPTION) == []
    assert no_network == []


def test_remote_schema_location_is_refused(tmp_path: Path, no_network: list[tuple[object, ...]]) -> None:
    for location in ("http://example.com/x.xsd", "https://fmi-standard.org/fmi3VariableDependency.xsd"):
        xsd = tmp_path / "remote.xsd"
        xsd.write_text(
            '<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">'
            f'<xs:include schemaLocation="{location}"/><xs:element name="r"/></xs:schema>'
        )
        with pytest.raises(schema_loader.SchemaLoadError, match="network") as raised:
            schema_loader._load_schema(xsd)
        assert f"refused to fetch {location}" in str(raised.value)
    assert no_network == []


def test_virtual_core_location_resolves_to_fmpy(tmp_path: Path) -> None:
    xsd = tmp_path / "core.xsd"
    xsd.write_text(
        '<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">'
        '<xs:include schemaLocation="fmi-core/fmi3VariableDependency.xsd"/>'
        '<xs:element name="r" type="fmi3Unknown"/></xs:schema>'
    )
    schema = schema_loader._load_schema(xsd)
    assert schema.validate(etree.fromstring(b'<r valueReference="1"/>'))
    missing = tmp_path / "missing.xsd"
    missing.write_text(
        '<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">'
        '<xs:include schemaLocation="fmi-core/fmi3Nothing.xsd"/></xs:schema>'
    )
    with pytest.raises(schema_loader.SchemaLoadError):
        schema_loader._load_schema(missing)


def test_clean_message() -> None:
    message = (
        "Element 'Float64', attribute 'causality': [facet 'enumeration'] The value 'x' is not an "
        "element of the set {'input', 'output'}."
    )
    cleaned = clean_message(message)
    assert "{" not in cleaned and "[facet" not in cleaned and "'input', 'output'" in cleaned
    cleaned = clean_message(
        "Element '{http://fmi-standard.org/fmi-ls-manifest}X': This element is not expected. "
        "Expected is one of ( A, B )."
    )
    assert cleaned.startswith("Element 'fmi-ls:X'") and "expected one of A, B" in cleaned


# --------------------------------------------------------------------------------------------
# The catalogue's examples for this family do what they say.


def _catalogue_examples() -> list[tuple[str, str, str]]:
    import tomllib

    rules = tomllib.loads((Path(__file__).parents[2] / "rules" / "schema.toml").read_text())["rule"]
    return [(rule["name"], kind, rule[kind]) for rule in rules for kind in ("bad", "good")]


@pytest.mark.parametrize(("name", "kind", "text"), _catalogue_examples(), ids=lambda v: str(v)[:24])
def test_catalogue_examples(name: str, kind: str, text: str) -> None:
    root = etree.fromstring(text.strip().encode())
    draft = detect.detect_draft(root)
    fired = {
        "schema-violation": bool(list(schemas.validate_manifest(root, draft, file="m.xml"))),
        "legacy-draft-shape": bool(list(migrate.legacy_violations(root, draft, file="m.xml"))),
        "draft-unrecognised": bool(list(detect.unrecognised_violations(root, file="m.xml"))),
    }
    assert fired == {rule: (rule == name and kind == "bad") for rule in fired}


# --------------------------------------------------------------------------------------------
# parts ([[rule.parts]] of schema-violation)


def test_manifest_errors_carry_the_part_of_their_schema() -> None:
    broken = (DATA / "alpha1.xml").read_text().replace(
        '<AlgebraicVariable valueReference="5"/>', '<AlgebraicVariable valueReference="five"/>')
    assert [v.part for v in manifest_violations(parse_text(broken.split("?>", 1)[1]))] == \
        ["alpha1-manifest"]
    text = (DATA / "alpha1.xml").read_text().replace(
        "<fmiDAEManifest ", '<fmiDAEManifest xmlns="http://fmi-standard.org/fmi-ls-manifest" ')
    assert [v.part for v in manifest_violations(parse_text(text.split("?>", 1)[1]))] == \
        ["alpha1-manifest"]
    assert [v.part for v in manifest_violations(parse_file("alpha1.xml"), detect.FORMULATION)] \
        == ["legacy-draft-schema"]
    legacy = (DATA / "formulation-default-ns.xml").read_text().replace(
        '<AlgebraicVariable valueReference="5"/>', '<AlgebraicVariable valueReference="-5"/>')
    assert {v.part for v in manifest_violations(parse_text(legacy.split("?>", 1)[1]))} == \
        {"legacy-draft-schema"}
    assert {dict(v.evidence)["schema"]
            for v in manifest_violations(parse_text(legacy.split("?>", 1)[1]))} == \
        {"fmi-ls-dae-formulation.xsd"}
    assert {v.part for v in md_violations(MODEL_DESCRIPTION.replace(
        'causality="local" start="1"', 'causality="nonsense" start="1"'))} == {None}


@pytest.mark.parametrize(("old", "new", "part"), [
    ('<EnableDAEParameter valueReference="1"/>',
     '<EnableDAEParameter valueReference="1" dependencies="2"/>', "beyond-published-xsd"),
    ('<AlgebraicVariable valueReference="4"/>',
     '<AlgebraicVariable valueReference="4" dependenciesKind="constant"/>', "beyond-published-xsd"),
    ('<AlgebraicVariable valueReference="4"/>',
     '<AlgebraicVariable valueReference="4"><Annotations/></AlgebraicVariable>',
     "beyond-published-xsd"),
    ('<AlgebraicVariable valueReference="4"/>',
     '<AlgebraicVariable valueReference="4" nominal="8"/>', "alpha1-manifest"),
    ('<AlgebraicVariable valueReference="4"/>',
     '<AlgebraicVariable valueReference="4"><Bogus/></AlgebraicVariable>', "alpha1-manifest"),
])
def test_what_only_lsdaes_stricter_alpha1_schema_rejects_is_a_part(old: str, new: str,
                                                                    part: str) -> None:
    text = (DATA / "alpha1.xml").read_text()
    assert old in text
    found = manifest_violations(parse_text(text.replace(old, new).split("?>", 1)[1]))
    assert [v.part for v in found] == [part]


def test_core_schemas_missing_or_fmpy_absent_say_so(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    import importlib.util
    from types import SimpleNamespace

    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    with pytest.raises(schema_loader.SchemaLoadError) as raised:
        schema_loader.core_schema_dir()
    assert str(raised.value) == ("fmpy is not installed; lsdae reads the FMI 3.0 core schemas "
                                 "from it")
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name: SimpleNamespace(submodule_search_locations=[str(tmp_path)]))
    with pytest.raises(schema_loader.SchemaLoadError) as raised:
        schema_loader.core_schema_dir()
    assert str(raised.value) == ("the FMI 3.0 core schemas are missing from "
                                 f"{tmp_path / 'schema' / 'fmi3'}")
