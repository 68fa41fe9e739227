"""Unit tests of the algebraic-variable rules (DAE30x) and the residual basics (DAE401-DAE405)."""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.checks import REGISTRY, algebraic, residual
from conformance.checks.context import CheckContext
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description

# The HelloWorldDAE model of draft-shapes.md, plus a few extra variables to point at.
VARIABLES = """
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Boolean name="dae" valueReference="1" causality="structuralParameter" variability="fixed"
             start="false"/>
    <Float64 name="x" valueReference="2" start="1" initial="exact"/>
    <Float64 name="der(x)" valueReference="3" derivative="2"/>
    <Float64 name="y" valueReference="4"/>
    <Float64 name="z" valueReference="5"/>
    <Float64 name="g1" valueReference="6"/>
    <Float64 name="g2" valueReference="7"/>
    <Float64 name="k" valueReference="8" causality="parameter" variability="fixed" start="2"/>
    <Float64 name="u" valueReference="9" causality="input" start="0"/>
    <Int32 name="n" valueReference="10"/>
    <Float64 name="c" valueReference="11" variability="constant" start="3"/>
    <Float64 name="d" valueReference="12" variability="discrete" initial="exact" start="0"/>
    <Float64 name="w" valueReference="13"><Dimension start="3"/></Float64>
    <Float64 name="v" valueReference="14"><Dimension valueReference="15"/></Float64>
    <UInt64 name="m" valueReference="15" causality="structuralParameter" variability="fixed"
            start="2"/>
    <Float64 name="q" valueReference="16"><Dimension valueReference="99"/></Float64>
    <Float64 name="x2" valueReference="17" start="0" initial="exact"/>
    <Float64 name="der(x2)" valueReference="18" derivative="17"/>
    <Float64 name="cp" valueReference="19" causality="calculatedParameter" variability="fixed"/>
    <Float64 name="yo" valueReference="20" causality="output"/>
"""


def _model(md_structure: str = '<ContinuousStateDerivative valueReference="3"/>'):
    xml = f"""<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">
  <ModelExchange modelIdentifier="M"/>
  <ModelVariables>{VARIABLES}</ModelVariables>
  <ModelStructure>{md_structure}</ModelStructure>
</fmiModelDescription>"""
    return read_model_description(etree.ElementTree(etree.fromstring(xml)))


def _alpha1(algebraic_vrs=("4", "5"), residual_vrs=("6", "7"), extra_structure=""):
    alg = "\n".join(f'    <AlgebraicVariable valueReference="{v}"/>' for v in algebraic_vrs)
    res = "\n".join(f'    <Residual valueReference="{v}" dependencies="2 4 5"/>'
                    for v in residual_vrs)
    xml = f"""<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">
  <EnableDAEParameter valueReference="1"/>
  <AlgebraicVariables>
{alg}
  </AlgebraicVariables>
  <ModelStructure>
    <ContinuousStateDerivative valueReference="3" dependencies="4"/>
{extra_structure}
{res}
  </ModelStructure>
</fmiDAEManifest>"""
    return read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="alpha1")


def _ctx(manifest, model=None) -> CheckContext:
    return CheckContext(model=model or _model(), manifest=manifest, draft=manifest.draft)


ALL_CODES = sorted({**algebraic.CHECKS, **residual.CHECKS})


def _fired(ctx: CheckContext) -> dict[str, list]:
    """Code -> violations, for every rule of both families that fired."""
    out = {}
    for code in ALL_CODES:
        found = list(REGISTRY[code](ctx))
        if found:
            out[code] = found
    return out


def test_registered_under_their_codes():
    for code in ALL_CODES:
        assert REGISTRY[code] is {**algebraic.CHECKS, **residual.CHECKS}[code]
    assert all(c.startswith("DAE30") for c in algebraic.CHECKS)
    assert all("DAE401" <= c <= "DAE419" for c in residual.CHECKS)


def test_clean_model_fires_nothing():
    assert _fired(_ctx(_alpha1())) == {}


def test_no_model_or_manifest_fires_nothing():
    manifest = _alpha1(("99", "4"), ("6",))
    for ctx in (CheckContext(model=None, manifest=manifest, draft="alpha1"),
                CheckContext(model=_model(), manifest=None, draft=None)):
        assert _fired(ctx) == {}


# ---- algebraic variables: one fixture, one rule -------------------------------------------

@pytest.mark.parametrize("vrs, code, subject", [
    (("4", "99"), "DAE301", "99"),
    (("4", "5", "4"), "DAE302", "y"),
    (("4", "10"), "DAE303", "n"),
    (("4", "1"), "DAE303", "dae"),          # a Boolean parameter: type first
    (("4", "12"), "DAE304", "d"),           # discrete local
    (("4", "11"), "DAE304", "c"),           # constant local
    (("4", "2"), "DAE305", "x"),            # state (modelDescription and manifest)
    (("4", "3"), "DAE305", "der(x)"),       # a derivative
    (("4", "8"), "DAE306", "k"),            # parameter, not also not-continuous
    (("4", "9"), "DAE306", "u"),            # input
    (("4", "0"), "DAE306", "time"),         # independent
    (("4", "19"), "DAE306", "cp"),          # calculated parameter
])
def test_algebraic_exactly_one_rule(vrs, code, subject):
    residuals = tuple(str(6 + i) for i in range(len(set(vrs))))
    fired = _fired(_ctx(_alpha1(vrs, residuals)))
    assert set(fired) == {code}, fired
    assert [v.subject for v in fired[code]] == [subject]


def test_algebraic_is_residual_reported_once():
    fired = _fired(_ctx(_alpha1(("4", "6"), ("6", "7"))))
    assert set(fired) == {"DAE307"}
    (v,) = fired["DAE307"]
    assert v.subject == "g1"
    assert v.location.file.endswith("fmi-ls-manifest.xml")


def test_output_algebraic_variable_is_fine():
    assert _fired(_ctx(_alpha1(("4", "20"), ("6", "7")))) == {}


def test_state_only_in_manifest_counts():
    """x2 is a state only in DAE mode (listed in the manifest, not in modelDescription)."""
    manifest = _alpha1(("4", "17"), ("6", "7"),
                       extra_structure='<ContinuousStateDerivative valueReference="18"/>')
    fired = _fired(_ctx(manifest))
    assert set(fired) == {"DAE305"}
    assert dict(fired["DAE305"][0].evidence)["role"] == "continuous state"


def test_state_only_in_model_description_counts():
    model = _model('<ContinuousStateDerivative valueReference="3"/>'
                   '<ContinuousStateDerivative valueReference="18"/>')
    fired = _fired(_ctx(_alpha1(("4", "17"), ("6", "7")), model))
    assert set(fired) == {"DAE305"}


def test_unknown_vr_not_an_integer_and_missing():
    manifest = _alpha1(("4", "y"), ("6", "7"))
    fired = _fired(_ctx(manifest))
    assert set(fired) == {"DAE301"}
    (v,) = fired["DAE301"]
    assert v.subject == "y"
    assert dict(v.evidence)["reason"] == "not an unsigned integer"
    assert v.location.line == manifest.algebraic[1].line
    xml = ('<fmiDAEManifest><AlgebraicVariables><AlgebraicVariable/></AlgebraicVariables>'
           '</fmiDAEManifest>')
    bare = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="alpha1")
    (v,) = algebraic.algebraic_unknown_vr(_ctx(bare))
    assert dict(v.evidence) == {"value_reference": None, "reason": "missing"}
    assert (v.subject, v.part) == (None, "missing-or-not-integer")
    assert (v.location.file, v.location.line, v.location.path) == (
        bare.file, 1, "/fmiDAEManifest/AlgebraicVariables/AlgebraicVariable[1]")


def test_duplicate_points_at_the_repeat():
    manifest = _alpha1(("4", "5", "4"), ("6", "7"))
    (v,) = algebraic.algebraic_duplicate(_ctx(manifest))
    assert v.location.line == manifest.algebraic[2].line
    assert dict(v.evidence)["first_listed_at_line"] == manifest.algebraic[0].line


@pytest.mark.parametrize("vrs, codes", [
    (("99", "10"), {"DAE301": ["99"], "DAE303": ["n"]}),   # the unresolved entry comes first
    (("10", "10"), {"DAE302": ["n"], "DAE303": ["n"]}),    # a repeat is classified once
    (("99", "4", "4", "10"), {"DAE301": ["99"], "DAE302": ["y"], "DAE303": ["n"]}),
])
def test_classified_past_unresolved_and_repeated_entries(vrs, codes):
    residuals = tuple(str(6 + i) for i in range(len(set(vrs)) - ("99" in vrs)))
    fired = _fired(_ctx(_alpha1(vrs, residuals)))
    assert {code: [v.subject for v in found] for code, found in fired.items()
            if code != "DAE405"} == codes


def test_unresolved_repeat_is_only_unknown_vr():
    fired = _fired(_ctx(_alpha1(("4", "99", "99"), ("6",))))
    assert set(fired) == {"DAE301"}
    assert len(fired["DAE301"]) == 2


def test_type_rules_point_at_the_variable_role_rules_at_the_manifest():
    ctx = _ctx(_alpha1(("4", "10"), ("6", "7")))
    (v,) = algebraic.algebraic_not_float(ctx)
    assert v.location.file == "modelDescription.xml"
    assert v.location.line == ctx.model.by_vr[10].line
    assert v.location.path == "/fmiModelDescription/ModelVariables/Int32[@name='n']"
    assert dict(v.evidence)["type"] == "Int32"
    ctx = _ctx(_alpha1(("4", "8"), ("6", "7")))
    (v,) = algebraic.algebraic_is_input_or_parameter(ctx)
    assert v.location.line == ctx.manifest.algebraic[1].line
    assert dict(v.evidence)["causality"] == "parameter"


# ---- residuals ----------------------------------------------------------------------------

@pytest.mark.parametrize("res, code, subject", [
    (("6", "77"), "DAE401", "77"),
    (("6", "6"), "DAE402", "g1"),
    (("6", "10"), "DAE403", "n"),            # integer
    (("6", "12"), "DAE403", "d"),            # discrete
    (("6", "8"), "DAE403", "k"),             # parameter: reported by variability
    (("6", "11"), "DAE403", "c"),            # constant
    (("6", "1"), "DAE403", "dae"),           # Boolean structural parameter
    (("6", "2"), "DAE404", "x"),             # state
    (("6", "3"), "DAE404", "der(x)"),        # derivative
    (("6", "9"), "DAE404", "u"),             # continuous input
    (("6", "0"), "DAE404", "time"),          # independent
])
def test_residual_exactly_one_rule(res, code, subject):
    fired = _fired(_ctx(_alpha1(("4", "5"), res)))
    assert set(fired) == {code}, fired
    assert [v.subject for v in fired[code]] == [subject]


def test_residual_unknown_vr_not_an_integer():
    fired = _fired(_ctx(_alpha1(("4", "5"), ("6", "g2"))))
    assert set(fired) == {"DAE401"}
    (v,) = fired["DAE401"]
    assert v.subject is None
    assert v.location.path.endswith("Residual[2]")
    assert dict(v.evidence) == {"value_reference": None, "reason": "missing or not an integer"}


def test_residual_that_is_also_algebraic_is_left_to_the_algebraic_rule():
    # y is both: algebraic-is-residual says so; the other residual, d, is still classified
    fired = _fired(_ctx(_alpha1(("4", "5"), ("4", "12"))))
    assert {code: [v.subject for v in found] for code, found in fired.items()} == {
        "DAE307": ["y"], "DAE403": ["d"]}


def test_residual_output_is_fine():
    assert _fired(_ctx(_alpha1(("4", "5"), ("6", "20")))) == {}


def test_residual_not_float_points_at_variable():
    ctx = _ctx(_alpha1(("4", "5"), ("6", "12")))
    (v,) = residual.residual_not_float_continuous(ctx)
    assert v.location.file == "modelDescription.xml"
    assert v.location.path == "/fmiModelDescription/ModelVariables/Float64[@name='d']"
    assert v.location.line == 17
    assert dict(v.evidence)["variability"] == "discrete"


def test_residual_role_evidence():
    for vr, role in (("2", "continuous state"), ("3", "state derivative"), ("9", "input"),
                     ("0", "independent")):
        ctx = _ctx(_alpha1(("4", "5"), ("6", vr)))
        (v,) = residual.residual_is_state_derivative_or_input(ctx)
        assert dict(v.evidence)["role"] == role
        assert v.location.file.endswith("fmi-ls-manifest.xml")


# ---- counting -----------------------------------------------------------------------------

def test_count_mismatch_evidence():
    ctx = _ctx(_alpha1(("4", "5"), ("6",)))
    (v,) = residual.residual_count_mismatch(ctx)
    ev = dict(v.evidence)
    assert (ev["algebraic_count"], ev["residual_count"]) == (2, 1)
    assert ev["algebraic_variables"] == ("y", "z")
    assert ev["residuals"] == ("g1",)
    assert v.location.line == ctx.manifest.algebraic_line


def test_count_uses_array_sizes():
    # w has 3 elements, v has m = 2 elements
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("13",), ("6", "7", "20")))))
    (v,) = residual.residual_count_mismatch(_ctx(_alpha1(("13",), ("6", "7"))))
    assert dict(v.evidence)["algebraic_count"] == 3
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("14",), ("6", "7")))))
    assert list(residual.residual_count_mismatch(_ctx(_alpha1(("14",), ("6",)))))


def test_count_skipped_when_size_unknown_unresolved_or_repeated():
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("4", "5"), ("6", "7", "6")))))
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("4", "4"), ("6",)))))
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("16",), ("6", "7")))))
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("4", "99"), ("6",)))))
    assert not list(residual.residual_count_mismatch(_ctx(_alpha1(("4", "5"), ("6", "77", "7")))))


def test_count_mismatch_points_at_the_algebraic_variables():
    (v,) = residual.residual_count_mismatch(_ctx(_alpha1(("4", "5"), ("6",))))
    assert (v.subject, v.location.file, v.location.line, v.location.path) == (
        None, "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml", 5,
        "/fmiDAEManifest/AlgebraicVariables")


def test_count_without_algebraic_variables_points_at_first_residual():
    xml = """<fmiDAEManifest><ModelStructure>
      <Residual valueReference="6"/></ModelStructure></fmiDAEManifest>"""
    manifest = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="alpha1")
    (v,) = residual.residual_count_mismatch(_ctx(manifest))
    assert v.location.path == manifest.residuals[0].path
    assert (v.location.file, v.location.line) == (manifest.file, 2)


def test_formulation_residual_counts_once():
    xml = """<fmiLayeredStandardManifest xmlns="http://fmi-standard.org/fmi-ls-manifest">
  <EnableDAE valueReference="1"/>
  <AlgebraicVariables>
    <AlgebraicVariable valueReference="4"/>
    <AlgebraicVariable valueReference="5"/>
  </AlgebraicVariables>
  <ModelStructure>
    <Residual>
      <Formulation index="1" valueReference="6" dependencies="2 4 5"/>
      <Formulation index="2" valueReference="12" dependencies="2 4 5"/>
    </Residual>
    <Residual><Formulation index="1" valueReference="7" dependencies="2 4 5"/></Residual>
  </ModelStructure>
</fmiLayeredStandardManifest>"""
    manifest = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="formulation")
    assert _fired(_ctx(manifest)) == {}
    bad = xml.replace('<Residual><Formulation index="1" valueReference="7" dependencies="2 4 5"/>'
                      '</Residual>', "")
    manifest = read_manifest(etree.ElementTree(etree.fromstring(bad)), draft="formulation")
    fired = _fired(_ctx(manifest))
    assert set(fired) == {"DAE405"}
    assert dict(fired["DAE405"][0].evidence)["residual_count"] == 1


def test_element_count():
    model = _model()
    assert algebraic.element_count(model, model.by_vr[4]) == 1
    assert algebraic.element_count(model, model.by_vr[13]) == 3
    assert algebraic.element_count(model, model.by_vr[14]) == 2
    assert algebraic.element_count(model, model.by_vr[16]) is None


# ---- parts (catalogue [[rule.parts]]): the sub-check a violation is -------------------------

# modelDescription.xml also lists der(x2) (vr 18), the manifest only der(x) (vr 3): x2 (vr 17)
# is a state of ODE mode only
_ODE_ONLY = '<ContinuousStateDerivative valueReference="3"/><ContinuousStateDerivative ' \
            'valueReference="18"/>'


@pytest.mark.parametrize("alg, res, md_structure, code, part", [
    (("4", "99"), ("6", "7"), None, "DAE301", None),                       # no such variable
    (("4", "y"), ("6", "7"), None, "DAE301", "missing-or-not-integer"),
    (("4", "2"), ("6", "7"), None, "DAE305", None),                        # DAE-mode state
    (("4", "3"), ("6", "7"), None, "DAE305", None),                        # DAE-mode derivative
    (("4", "17"), ("6", "7"), _ODE_ONLY, "DAE305", "not-a-dae-mode-state-or-derivative"),
    (("4", "18"), ("6", "7"), None, "DAE305", "not-a-dae-mode-state-or-derivative"),  # unlisted
    (("4", "18"), ("6", "7"), _ODE_ONLY, "DAE305", "not-a-dae-mode-state-or-derivative"),
    (("4", "8"), ("6", "7"), None, "DAE306", None),                        # parameter
    (("4", "9"), ("6", "7"), None, "DAE306", None),                        # input
    (("4", "19"), ("6", "7"), None, "DAE306", "structural-or-calculated-parameter"),
    (("4", "5"), ("6", "77"), None, "DAE401", None),                       # no such variable
    (("4", "5"), ("6", "g2"), None, "DAE401", "missing-or-not-integer"),
    (("4", "5"), ("6", "2"), None, "DAE404", None),                        # DAE-mode state
    (("4", "5"), ("6", "9"), None, "DAE404", None),                        # input
    (("4", "5"), ("6", "0"), None, "DAE404", None),                        # independent
    (("4", "5"), ("6", "3"), None, "DAE404", "state-derivative"),
    (("4", "5"), ("6", "17"), _ODE_ONLY, "DAE404", "ode-only-state"),
])
def test_part_of_violation(alg, res, md_structure, code, part):
    model = _model(md_structure) if md_structure else None
    fired = _fired(_ctx(_alpha1(alg, res), model))
    assert set(fired) == {code}, fired
    assert [v.part for v in fired[code]] == [part]


def test_part_of_missing_algebraic_value_reference():
    xml = ('<fmiDAEManifest><AlgebraicVariables><AlgebraicVariable/></AlgebraicVariables>'
           '</fmiDAEManifest>')
    bare = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="alpha1")
    (v,) = algebraic.algebraic_unknown_vr(_ctx(bare))
    assert v.part == "missing-or-not-integer"
