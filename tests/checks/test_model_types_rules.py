"""Unit tests of the rules that make lsdae a superset of fmpy validate (DAE530-DAE537):
conformance/checks/model_types.py, model_names.py and model_references.py.

The fixtures (tests/fixtures/DAE53x) show each rule failing and passing on a scene; these tests
pin the first-cause decisions (which rule stays quiet when another explains the fault), the
evidence a finding carries, and the fast paths on a large model.
"""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.checks import model_names, model_references, model_types
from conformance.checks.context import CheckContext
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description

CHECKS = {**model_types.CHECKS, **model_names.CHECKS, **model_references.CHECKS}

BASE = """
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Boolean name="dae" valueReference="1" causality="structuralParameter" variability="fixed"
             start="false"/>
"""
MANIFEST = """<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">
  <EnableDAEParameter valueReference="1"/>
  <AlgebraicVariables/>
  <ModelStructure/>
</fmiDAEManifest>"""
UNITS = """<UnitDefinitions>
  <Unit name="m"><BaseUnit m="1"/><DisplayUnit name="mm" factor="1000"/></Unit>
  <Unit name="s"><BaseUnit s="1"/></Unit>
</UnitDefinitions>"""


def ctx_of(variables: str = "", *, definitions: str = "", structure: str = "",
           naming: str = "structured", manifest: bool = False) -> CheckContext:
    text = (f'<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t" '
            f'variableNamingConvention="{naming}"><ModelExchange modelIdentifier="M"/>'
            f"{definitions}<ModelVariables>{BASE}{variables}</ModelVariables>"
            f"<ModelStructure>{structure}</ModelStructure></fmiModelDescription>")
    model = read_model_description(etree.ElementTree(etree.fromstring(text)))
    man = read_manifest(etree.ElementTree(etree.fromstring(MANIFEST)), draft="alpha1") \
        if manifest else None
    return CheckContext(model=model, manifest=man, draft="alpha1" if man else None)


def found(ctx: CheckContext) -> dict[str, list]:
    out: dict[str, list] = {}
    for code, check in CHECKS.items():
        violations = list(check(ctx))
        if violations:
            out[code] = violations
    return out


def codes(ctx: CheckContext) -> set[str]:
    return set(found(ctx))


# -- declared types and units ---------------------------------------------------------------

def test_declared_type_resolves_or_is_reported():
    var = '<Float64 name="x" valueReference="2" declaredType="Length"/>'
    assert codes(ctx_of(var)) == {"DAE530"}
    defined = '<TypeDefinitions><Float64Type name="Length"/></TypeDefinitions>'
    assert codes(ctx_of(var, definitions=defined)) == set()


def test_type_of_another_kind_still_resolves():
    # Only undefined names are reported; the rule does not judge which type a variable may use.
    defined = '<TypeDefinitions><Int32Type name="Count"/></TypeDefinitions>'
    var = '<Int32 name="n" valueReference="2" declaredType="Count"/>'
    assert codes(ctx_of(var, definitions=defined)) == set()


def test_unit_of_a_type_is_reported_once_at_the_type():
    defined = UNITS + '<TypeDefinitions><Float64Type name="T" unit="K"/></TypeDefinitions>'
    variables = "".join(f'<Float64 name="t{i}" valueReference="{i + 2}" declaredType="T"/>'
                        for i in range(5))
    result = found(ctx_of(variables, definitions=defined))
    assert set(result) == {"DAE531"}
    (violation,) = result["DAE531"]
    assert violation.subject == "T"
    assert violation.location.path.endswith("Float64Type[@name='T']")


def test_display_unit_first_cause():
    # An undefined unit is unit-undefined's, not display-unit-undefined's as well.
    var = '<Float64 name="x" valueReference="2" unit="km" displayUnit="mm"/>'
    assert codes(ctx_of(var, definitions=UNITS)) == {"DAE531"}
    # An undefined declared type hides the unit in effect: only declared-type-undefined.
    var = '<Float64 name="x" valueReference="2" declaredType="Nope" displayUnit="mm"/>'
    assert codes(ctx_of(var, definitions=UNITS)) == {"DAE530"}


def test_display_unit_uses_the_unit_in_effect():
    defined = UNITS + '<TypeDefinitions><Float64Type name="L" unit="m"/></TypeDefinitions>'
    ok = '<Float64 name="x" valueReference="2" declaredType="L" displayUnit="mm"/>'
    assert codes(ctx_of(ok, definitions=defined)) == set()
    # the variable's own unit overrides the type's: "mm" is no display unit of "s"
    own = '<Float64 name="x" valueReference="2" declaredType="L" unit="s" displayUnit="mm"/>'
    (violation,) = found(ctx_of(own, definitions=defined))["DAE532"]
    assert dict(violation.evidence)["unit"] == "s"
    no_unit = '<Float64 name="x" valueReference="2" displayUnit="mm"/>'
    assert codes(ctx_of(no_unit, definitions=UNITS)) == {"DAE532"}


def test_alias_display_unit():
    var = ('<Float64 name="x" valueReference="2" unit="m"><Alias name="xa" displayUnit="mm"/>'
           '<Alias name="xb" displayUnit="km"/></Float64>')
    (violation,) = found(ctx_of(var, definitions=UNITS))["DAE532"]
    assert violation.subject == "xb"
    assert dict(violation.evidence)["alias"] is True


# -- names ----------------------------------------------------------------------------------

def test_forbidden_characters_are_reported_once_under_either_convention():
    var = '<Float64 name="a&#9;b" valueReference="2"/>'
    assert codes(ctx_of(var, naming="structured")) == {"DAE533"}
    assert codes(ctx_of(var, naming="flat")) == {"DAE533"}
    (violation,) = found(ctx_of(var))["DAE533"]
    assert violation.subject == "a\\tb"   # shown escaped: a report stays one line per finding
    assert "\t" not in (violation.location.path or "")


def test_empty_names():
    assert codes(ctx_of('<Float64 name="" valueReference="2"/>', naming="flat")) == {"DAE533"}
    alias = '<Float64 name="x" valueReference="2"><Alias name=""/></Float64>'
    assert codes(ctx_of(alias, naming="flat")) == {"DAE533"}


def test_flat_names_may_hold_anything_else():
    var = '<Float64 name="2 x (é) [1]" valueReference="2"><Alias name="\'q"/></Float64>'
    assert codes(ctx_of(var, naming="flat")) == set()
    assert codes(ctx_of(var, naming="structured")) == {"DAE534"}


def test_structured_name_evidence_points_at_the_fault():
    var = '<Float64 name="x" valueReference="2"><Alias name="body.2nd"/></Float64>'
    (violation,) = found(ctx_of(var))["DAE534"]
    ev = dict(violation.evidence)
    assert violation.subject == "body.2nd"
    assert (ev["alias"], ev["position"], ev["found"]) == (True, 6, "2")
    (violation,) = found(ctx_of('<Float64 name="a." valueReference="2"/>'))["DAE534"]
    ev = dict(violation.evidence)
    assert (ev["position"], ev["found"], ev["expected"]) == (
        3, "(end of name)", "a letter or '_' starting a name part, or a quoted name '...'")


# -- dependenciesKind, Dimension, clocks ------------------------------------------------------

def test_dependencies_kind_length_counts_every_token():
    variables = ('<Float64 name="x" valueReference="2" initial="exact" start="1"/>'
                 '<Float64 name="der(x)" valueReference="3" derivative="2"/>')
    ok = '<ContinuousStateDerivative valueReference="3" dependencies="2" dependenciesKind="constant"/>'
    assert codes(ctx_of(variables, structure=ok)) == set()
    bad = ('<ContinuousStateDerivative valueReference="3" dependencies="2 two" '
           'dependenciesKind="constant"/>')  # "two" is the schema's, but it is still an entry
    assert codes(ctx_of(variables, structure=bad)) == {"DAE535"}
    empty = '<ContinuousStateDerivative valueReference="3" dependencies="" dependenciesKind=""/>'
    assert codes(ctx_of(variables, structure=empty)) == set()
    # an element without dependenciesKind before the faulty one is passed over, not the end
    after = ('<ContinuousStateDerivative valueReference="3" dependencies="2"/>'
             '<InitialUnknown valueReference="3" dependencies="2" '
             'dependenciesKind="constant constant"/>')
    (violation,) = found(ctx_of(variables, structure=after))["DAE535"]
    assert violation.subject == "der(x)"
    assert dict(violation.evidence) == {"kind": "InitialUnknown", "dependencies": 1, "kinds": 2}
    # kinds without dependencies on one element, too many kinds on the next: both
    both = ('<ContinuousStateDerivative valueReference="3" dependenciesKind="constant"/>'
            '<InitialUnknown valueReference="3" dependencies="2" '
            'dependenciesKind="constant constant"/>')
    assert [(v.text, dict(v.evidence)) for v in found(ctx_of(variables, structure=both))[
        "DAE535"]] == [
        ("dependenciesKind without dependencies, on the ModelStructure element of 'der(x)'; list "
         "the dependencies the kinds describe, or remove dependenciesKind",
         {"kind": "ContinuousStateDerivative", "kinds": 1}),
        ("dependenciesKind with a different number of entries than dependencies, on the "
         "ModelStructure element of 'der(x)'; give exactly one kind per dependency",
         {"kind": "InitialUnknown", "dependencies": 1, "kinds": 2})]


def test_dimension_on_the_enable_parameter_is_left_to_the_enable_rule():
    var = ('<Float64 name="v" valueReference="2"><Dimension valueReference="1"/></Float64>')
    assert codes(ctx_of(var, manifest=True)) == set()    # enable-parameter-not-scalar's
    assert codes(ctx_of(var)) == {"DAE536"}              # no manifest: a Boolean size


def test_dimension_size_variable_without_start_is_start_missings():
    var = ('<UInt64 name="n" valueReference="2" causality="structuralParameter" '
           'variability="fixed"/><Float64 name="v" valueReference="3"><Dimension '
           'valueReference="2"/></Float64>')
    assert codes(ctx_of(var)) == set()


def test_malformed_dimension_reference_is_the_schemas():
    var = '<Float64 name="v" valueReference="2"><Dimension valueReference="x1"/></Float64>'
    assert codes(ctx_of(var)) == set()
    var = '<Float64 name="v" valueReference="2"><Dimension/></Float64>'
    assert codes(ctx_of(var)) == {"DAE536"}


def test_dimension_fault_after_a_good_dimension_of_the_same_array():
    var = ('<Float64 name="v" valueReference="2"><Dimension start="2"/></Float64>'
           '<Float64 name="u" valueReference="3"><Dimension start="2"/><Dimension start="0"/>'
           '</Float64>')
    (violation,) = found(ctx_of(var))["DAE536"]
    assert violation.subject == "u" and dict(violation.evidence)["fault"] == "zero"


def test_huge_numbers_are_no_internal_error():
    digits = "9" * 5000
    var = (f'<Float64 name="s" valueReference="2" variability="discrete" clocks="{digits}"/>'
           f'<Float64 name="v" valueReference="3"><Dimension start="{digits}"/></Float64>')
    assert codes(ctx_of(var)) == set()   # out of range: the schema stage's to report


def test_clock_reference_of_twenty_digits_is_read():
    # the largest UInt64 has 20 digits: read, and named as no variable; one digit more is the
    # schema stage's
    var = '<Float64 name="s" valueReference="3" variability="discrete" clocks="{}"/>'
    (violation,) = found(ctx_of(var.format("18446744073709551615")))["DAE537"]
    assert dict(violation.evidence)["clock_value_reference"] == 18446744073709551615
    assert codes(ctx_of(var.format("184467440737095516150"))) == set()


def test_clock_references():
    clock = '<Clock name="c" valueReference="2" causality="input" intervalVariability="triggered"/>'
    ok = clock + '<Float64 name="s" valueReference="3" variability="discrete" clocks="2"/>'
    assert codes(ctx_of(ok)) == set()
    bad = clock + '<Float64 name="s" valueReference="3" variability="discrete" clocks="2 3 9"/>'
    result = found(ctx_of(bad))
    assert set(result) == {"DAE537"}
    assert [dict(v.evidence)["clock_value_reference"] for v in result["DAE537"]] == [3, 9]


# -- cost -----------------------------------------------------------------------------------

@pytest.mark.parametrize("naming", ["structured", "flat"])
def test_large_model_is_clean(naming):
    # (speed is what make bench measures; this keeps the fast paths honest about their result)
    defined = UNITS + '<TypeDefinitions><Float64Type name="L" unit="m"/></TypeDefinitions>'
    variables = "".join(
        f'<Float64 name="block{i}.x[{i % 3}]" valueReference="{i + 2}" declaredType="L" '
        f'displayUnit="mm"><Alias name="der(block{i}.y)"/></Float64>' for i in range(20_000))
    ctx = ctx_of(variables, definitions=defined, naming=naming)
    assert found(ctx) == {}
    # ... and they still find the one fault among the 20,000
    bad = variables.replace('name="block7.x[1]"', 'name="block7.x[1"')
    bad = bad.replace('displayUnit="mm"><Alias name="der(block9.y)"',
                      'displayUnit="km"><Alias name="der(block9.y)"')
    result = found(ctx_of(bad, definitions=defined, naming=naming))
    assert set(result) == ({"DAE532", "DAE534"} if naming == "structured" else {"DAE532"})


# -- parts: the sub-checks whose basis differs carry their catalogue part ----------------------

def parts(ctx: CheckContext, code: str) -> dict:
    return {v.subject: v.part for v in found(ctx).get(code, ())}


def test_unit_and_display_unit_parts():
    defined = UNITS + ('<TypeDefinitions><Float64Type name="T" unit="K"/>'
                       '<Float64Type name="U" unit="m" displayUnit="km"/>'
                       '<Float64Type name="V" displayUnit="mm"/></TypeDefinitions>')
    var = ('<Float64 name="x" valueReference="2" unit="K"/>'
           '<Float64 name="y" valueReference="3" unit="m" displayUnit="km">'
           '<Alias name="ya" displayUnit="cm"/></Float64>'
           '<Float64 name="z" valueReference="4" displayUnit="mm"><Alias name="za" '
           'displayUnit="mm"/></Float64>')
    ctx = ctx_of(var, definitions=defined)
    assert parts(ctx, "DAE531") == {"T": "type-definition-unit", "x": None}
    assert parts(ctx, "DAE532") == {"U": "type-definition", "V": "no-unit", "y": None,
                                    "ya": "alias", "z": "no-unit", "za": "alias"}


def test_empty_name_part():
    var = ('<Float64 name="" valueReference="2"/><Float64 name="a&#9;b" valueReference="3">'
           '<Alias name=""/></Float64>')
    assert [v.part for v in found(ctx_of(var, naming="flat"))["DAE533"]] == [
        "empty", None, "empty"]


@pytest.mark.parametrize("var, part", [
    ('<Float64 name="v" valueReference="2"><Dimension start="0"/></Float64>', None),
    ('<Float64 name="v" valueReference="2"><Dimension start="2" valueReference="0"/></Float64>',
     "both"),
    ('<Float64 name="v" valueReference="2"><Dimension/></Float64>', "neither"),
    ('<Float64 name="v" valueReference="2"><Dimension valueReference="99"/></Float64>',
     "unknown-vr"),
    ('<Float64 name="v" valueReference="2"><Dimension valueReference="1"/></Float64>', "target"),
])
def test_dimension_parts(var, part):
    assert parts(ctx_of(var), "DAE536") == {"v": part}
