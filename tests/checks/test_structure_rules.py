"""Unit tests of the DAE model-structure rules (DAE420-DAE426) and index 1 (DAE601)."""
from __future__ import annotations

import logging
import sys

import pytest
from lxml import etree

from bench.generate import manifest_xml, model_description_xml
from conformance.report.catalogue import default_catalogue
from conformance.checks import REGISTRY, index1, manifest_dependencies, manifest_lists
from conformance.checks.context import CheckContext
from conformance.model.manifest import MANIFEST, Manifest, VrRef, read_manifest
from conformance.model.description import ModelDescription, Variable, read_model_description
from conformance.model.unknowns import Unknown

# The HelloWorldDAE model of draft-shapes.md plus variables of every other kind to point at.
VARIABLES = """
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Boolean name="dae" valueReference="1" causality="structuralParameter" variability="fixed"
             start="false"/>
    <Float64 name="x" valueReference="2" start="1" initial="exact"/>
    <Float64 name="der(x)" valueReference="3" derivative="2"/>
    <Float64 name="y" valueReference="4" initial="approx" start="0"/>
    <Float64 name="z" valueReference="5" initial="approx" start="0"/>
    <Float64 name="g1" valueReference="6"/>
    <Float64 name="g2" valueReference="7"/>
    <Float64 name="k" valueReference="8" causality="parameter" variability="fixed" start="2"/>
    <Float64 name="u" valueReference="9" causality="input" start="0"/>
    <Int32 name="n" valueReference="10" causality="output"/>
    <Float64 name="c" valueReference="11" variability="constant" start="3"/>
    <Float64 name="loc" valueReference="12"/>
    <Float64 name="cp" valueReference="13" causality="calculatedParameter" variability="fixed"/>
    <Float64 name="yo" valueReference="14" causality="output"/>
    <Float64 name="ye" valueReference="15" causality="output" initial="exact" start="0"/>
    <Float64 name="w" valueReference="16" initial="approx" start="0">
      <Dimension start="2"/></Float64>
    <Float64 name="r" valueReference="17"><Dimension valueReference="18"/></Float64>
    <UInt64 name="nr" valueReference="18" causality="structuralParameter" variability="fixed"
            start="2"/>
    <Float64 name="der2" valueReference="19" derivative="2"/>
"""
MD_STRUCTURE = """
    <Output valueReference="10"/>
    <Output valueReference="14"/>
    <Output valueReference="15"/>
    <ContinuousStateDerivative valueReference="3"/>
"""


def _ctx(manifest_structure: str, *, algebraic=("4", "5"), draft="alpha1",
         md_structure: str = MD_STRUCTURE, legacy: bool = False) -> CheckContext:
    md = f"""<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">
  <ModelExchange modelIdentifier="M"/>
  <ModelVariables>{VARIABLES}</ModelVariables>
  <ModelStructure>{md_structure}</ModelStructure>
</fmiModelDescription>"""
    alg = "".join(f'<AlgebraicVariable valueReference="{v}"/>' for v in algebraic)
    if legacy:
        root = ('<fmiLayeredStandardManifest xmlns="http://fmi-standard.org/fmi-ls-manifest" '
                'xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest">'
                '<EnableDAE valueReference="1"/>')
        end = "</fmiLayeredStandardManifest>"
    else:
        root = ('<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest">'
                '<EnableDAEParameter valueReference="1"/>')
        end = "</fmiDAEManifest>"
    man = (f"{root}\n<AlgebraicVariables>{alg}</AlgebraicVariables>\n"
           f"<ModelStructure>\n{manifest_structure}\n</ModelStructure>\n{end}")
    model = read_model_description(etree.ElementTree(etree.fromstring(md)))
    manifest = read_manifest(etree.ElementTree(etree.fromstring(man)), draft=draft)
    return CheckContext(model=model, manifest=manifest, draft=draft)


def _run(code: str, ctx: CheckContext):
    rule = default_catalogue()[code]
    return list(REGISTRY[code](ctx, **rule.option_values))


GOOD = """
<ContinuousStateDerivative valueReference="3" dependencies="4" dependenciesKind="constant"/>
<InitialUnknown valueReference="3"/>
<InitialUnknown valueReference="4"/>
<InitialUnknown valueReference="5"/>
<Residual valueReference="6" dependencies="2 4 5" dependenciesKind="constant constant constant"/>
<Residual valueReference="7" dependencies="2 4 5" dependenciesKind="constant constant constant"/>
"""


# The manifest ModelStructure rules: dependencies (DAE420-DAE423) and lists (DAE424-DAE426).
MANIFEST_STRUCTURE = {**manifest_dependencies.CHECKS, **manifest_lists.CHECKS}


def test_registry_holds_the_family():
    assert set(MANIFEST_STRUCTURE) == {f"DAE42{i}" for i in range(7)}
    assert set(index1.CHECKS) == {"DAE601"}
    for code in (*MANIFEST_STRUCTURE, *index1.CHECKS):
        assert REGISTRY[code] is ({**MANIFEST_STRUCTURE, **index1.CHECKS})[code]


@pytest.mark.parametrize("code", [*MANIFEST_STRUCTURE, *index1.CHECKS])
def test_good_model_is_clean(code):
    assert _run(code, _ctx(GOOD)) == []


# --- DAE420 dependency-unknown-vr --------------------------------------------------------------

def test_unknown_dependency_is_reported_once_per_entry_with_location():
    ctx = _ctx('<ContinuousStateDerivative valueReference="3" dependencies="4 99 99"/>\n'
               '<EventIndicator valueReference="12" dependencies="98"/>')
    found = _run("DAE420", ctx)
    assert [(v.subject, dict(v.evidence)["value_reference"]) for v in found] == \
        [("der(x)", 99), ("loc", 98)]
    assert found[0].location.file == ctx.manifest.file
    assert found[0].location.line == 4
    assert found[0].location.path.endswith("ContinuousStateDerivative[1]")


def test_bad_tokens_are_left_to_the_schema():
    ctx = _ctx('<Residual valueReference="6" dependencies="4 five 5"/>\n'
               '<Residual valueReference="7" dependencies="4 5"/>')
    assert ctx.manifest.residuals[0].bad_tokens == ("five",)
    assert _run("DAE420", ctx) == []


def test_unknown_dependency_of_unresolved_element_names_the_reference():
    found = _run("DAE420", _ctx('<Output valueReference="77" dependencies="66"/>'))
    assert [v.subject for v in found] == ["valueReference 77"]


# --- DAE421 dependency-not-allowed-known -------------------------------------------------------

@pytest.mark.parametrize("deps, bad", [
    ("3", "der(x)"),           # state derivative: not a known of an alpha.1 residual
    ("12", "loc"),             # local
    ("7", "g2"),               # residual
    ("13", "cp"),              # calculated parameter
    ("1", "dae"),              # structural parameter
    ("11", "c"),               # constant
    ("14", "yo"),              # output
])
def test_residual_knowns_alpha1(deps, bad):
    ctx = _ctx(f'<Residual valueReference="6" dependencies="4 5 {deps}"/>'
               '<Residual valueReference="7" dependencies="4 5"/>')
    found = _run("DAE421", ctx)
    assert [(v.subject, dict(v.evidence)["known"]) for v in found] == [("g1", bad)]
    assert found[0].location.path.endswith("Residual[1]")


def test_residual_knowns_allowed():
    ctx = _ctx('<Residual valueReference="6" dependencies="0 2 4 5 8 9"/>'
               '<Residual valueReference="7" dependencies=""/><Residual valueReference="6"/>')
    assert _run("DAE421", ctx) == []


@pytest.mark.parametrize("draft, expected", [("alpha1", ["der(x)"]), ("flat-index", ["der(x)"]),
                                             ("formulation", []), ("ls-dae-root", [])])
def test_state_derivative_is_a_known_only_for_formulation_residuals(draft, expected):
    structure_xml = ('<Residual><Formulation index="1" valueReference="6" dependencies="2 3 4 5"/>'
                     '</Residual>') if draft in ("formulation", "ls-dae-root") else \
        '<Residual valueReference="6" dependencies="2 3 4 5"/>'
    ctx = _ctx(structure_xml, draft=draft, legacy=draft != "alpha1")
    found = _run("DAE421", ctx)
    assert [dict(v.evidence)["known"] for v in found] == expected
    if draft == "formulation":
        # a derivative is still not a known of a ContinuousStateDerivative in any draft
        ctx = _ctx('<ContinuousStateDerivative valueReference="3" dependencies="3"/>',
                   draft=draft, legacy=True)
        assert [v.subject for v in _run("DAE421", ctx)] == ["der(x)"]


def test_initial_unknown_knowns():
    ctx = _ctx('<InitialUnknown valueReference="4" dependencies="0 2 5 8 9 11 15"/>'
               '<InitialUnknown valueReference="5" dependencies="3 14 13"/>')
    found = _run("DAE421", ctx)
    assert [(v.subject, dict(v.evidence)["known"]) for v in found] == \
        [("z", "der(x)"), ("z", "yo"), ("z", "cp")]
    assert all('initial="calculated"' in dict(v.evidence)["known_is"] for v in found)


def test_output_knowns_and_state_from_manifest_list():
    # the manifest's CSD list names der2 -> x, so x is a state; modelDescription's would too
    ctx = _ctx('<Output valueReference="14" dependencies="2 4 15"/>'
               '<ContinuousStateDerivative valueReference="19" dependencies="4"/>')
    found = _run("DAE421", ctx)
    assert [dict(v.evidence)["known"] for v in found] == ["ye"]


def test_states_fall_back_to_model_description():
    ctx = _ctx('<Output valueReference="14" dependencies="2"/>', md_structure=MD_STRUCTURE)
    assert _run("DAE421", ctx) == []
    ctx = _ctx('<Output valueReference="14" dependencies="2"/>', md_structure="")
    assert [dict(v.evidence)["known"] for v in _run("DAE421", ctx)] == ["x"]


def test_event_indicator_dependencies_are_not_checked():
    assert _run("DAE421", _ctx('<EventIndicator valueReference="12" dependencies="3 7"/>')) == []


def test_unresolved_dependency_is_not_also_not_allowed():
    assert _run("DAE421", _ctx('<Residual valueReference="6" dependencies="4 99"/>')) == []


# --- DAE422 dependencies-kind-length -----------------------------------------------------------

def test_kind_length():
    ctx = _ctx('<Residual valueReference="6" dependencies="2 4 5" dependenciesKind="constant"/>'
               '<Residual valueReference="7" dependenciesKind="dependent"/>'
               '<InitialUnknown valueReference="4" dependencies="" dependenciesKind=""/>'
               '<InitialUnknown valueReference="5" dependencies="2" dependenciesKind="constant"/>')
    found = _run("DAE422", ctx)
    assert [v.subject for v in found] == ["g1", "g2"]
    assert dict(found[0].evidence) == {"element": "Residual", "dependencies": 3, "kinds": 1}


def test_kind_length_counts_bad_tokens():
    ctx = _ctx('<Residual valueReference="6" dependencies="2 x" '
               'dependenciesKind="dependent dependent"/>')
    assert _run("DAE422", ctx) == []


# --- DAE423 dependencies-kind-invalid ----------------------------------------------------------

def test_kind_invalid():
    ctx = _ctx('<InitialUnknown valueReference="4" dependencies="2 5 8" '
               'dependenciesKind="fixed constant discrete"/>'
               '<Output valueReference="10" dependencies="9" dependenciesKind="constant"/>'
               '<Output valueReference="14" dependencies="9 2" dependenciesKind="tunable fixed"/>'
               '<Residual valueReference="6" dependencies="4" dependenciesKind="bogus"/>')
    found = _run("DAE423", ctx)
    assert [(v.subject, dict(v.evidence)["kind"]) for v in found] == \
        [("y", "fixed"), ("y", "discrete"), ("n", "constant")]


def test_non_float_dependent_is_fine():
    ctx = _ctx('<Output valueReference="10" dependencies="9" dependenciesKind="dependent"/>')
    assert _run("DAE423", ctx) == []


def test_dependencies_kind_invalid_goes_past_a_kind_the_schema_reports():
    # 'bogus' is the schema stage's (fmi3Unknown enumerates the kinds); 'fixed' is this rule's
    found = _run("DAE423", _ctx('<InitialUnknown valueReference="4" dependencies="2 5" '
                                'dependenciesKind="bogus fixed"/>'))
    assert [(v.subject, dict(v.evidence)) for v in found] == [
        ("y", {"element": "InitialUnknown", "kind": "fixed"})]


def test_dependencies_kind_of_a_non_float_unknown():
    # an Int32 unknown may use 'dependent' only: 'constant' beside it is reported, alone
    found = _run("DAE423", _ctx('<Output valueReference="10" dependencies="2 4" '
                                'dependenciesKind="dependent constant"/>'))
    assert [(v.subject, dict(v.evidence)) for v in found] == [
        ("n", {"element": "Output", "kind": "constant", "type": "Int32"})]
    assert found[0].text == (
        "<Output> 'n' is a <Int32> and uses dependenciesKind 'constant'; a non-floating-point "
        "unknown allows only 'dependent'")


def test_dependencies_kind_of_an_unresolved_element_is_left_alone():
    # the Output of the Int32 n takes the rule past its fast path; the Residual 99 names no
    # variable (residual-unknown-vr's), so its kinds are not judged against a type
    assert _run("DAE423", _ctx('<Output valueReference="10"/>'
                               '<Residual valueReference="99" dependencies="2" '
                               'dependenciesKind="fixed"/>')) == []


def test_dependency_not_allowed_goes_past_event_indicators():
    # EventIndicator dependencies are for debugging (MS-12) and not judged; the residuals after
    # it are
    found = _run("DAE421", _ctx('<EventIndicator valueReference="12" dependencies="12"/>'
                                '<Residual valueReference="6" dependencies="4 5 13"/>'
                                '<Residual valueReference="7" dependencies="4 5 12"/>'))
    assert [(v.subject, dict(v.evidence)["known_is"]) for v in found] == [
        ("g1", "a calculated parameter"), ("g2", "a local variable")]
    assert found[1].text == (
        "<Residual> 'g2' depends on 'loc', a local variable; its allowed knowns are inputs, "
        "continuous states, parameters, algebraic variables and the independent variable")


def test_initial_unknown_may_not_depend_on_a_state_that_is_not_exact(monkeypatch):
    # a continuous state is a known of the continuous-time elements, but an InitialUnknown's
    # knowns are inputs, initial="exact" variables and algebraic variables
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES.replace(
        '<Float64 name="x" valueReference="2" start="1" initial="exact"/>',
        '<Float64 name="x" valueReference="2" start="1" initial="approx"/>'))
    [v] = _run("DAE421", _ctx('<InitialUnknown valueReference="4" dependencies="2"/>'))
    assert (v.subject, v.part) == ("y", "initial-unknown-known")
    assert dict(v.evidence) == {
        "element": "InitialUnknown", "known": "x", "known_value_reference": 2,
        "known_is": 'a continuous state with initial="approx"',
        "allowed": 'inputs, variables with initial="exact", algebraic variables and the '
                   "independent variable"}
    assert _run("DAE421", _ctx('<Output valueReference="14" dependencies="2"/>')) == []


def test_dependency_not_allowed_goes_past_elements_already_decided():
    # g1's dependencies are all usual knowns; g2's input u was found allowed for g1 already:
    # both are passed over, and the Output after them is still judged
    found = _run("DAE421", _ctx('<Residual valueReference="6" dependencies="4 5"/>'
                                '<Residual valueReference="6" dependencies="4 5 9"/>'
                                '<Residual valueReference="7" dependencies="4 5 9"/>'
                                '<Output valueReference="14" dependencies="12"/>'))
    assert [(v.subject, v.part) for v in found] == [("yo", "output-or-derivative-known")]


def test_dependency_on_a_discrete_time_state(monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES + _DISCRETE)
    [v] = _run("DAE421", _ctx('<Output valueReference="14" dependencies="30"/>'))
    assert (v.subject, v.part) == ("yo", "discrete-time-state-known")
    assert dict(v.evidence)["known"] == "xd"
    assert dict(v.evidence)["known_value_reference"] == 30


def test_dependency_not_allowed_names_the_knowns_of_the_draft():
    # the fully implicit drafts allow state derivatives as knowns of a residual, and say so
    ctx = _ctx('<Residual><Formulation index="1" valueReference="6" dependencies="3 4 12"/>'
               '</Residual><Residual><Formulation index="1" valueReference="7" '
               'dependencies="3 4"/></Residual>', draft="formulation", legacy=True)
    [v] = _run("DAE421", ctx)
    assert v.subject == "g1" and dict(v.evidence)["allowed"] == (
        "inputs, continuous states, continuous state derivatives, parameters, algebraic "
        "variables and the independent variable")
    [v] = _run("DAE421", _ctx('<Residual valueReference="6" dependencies="4 5 12"/>'))
    assert dict(v.evidence)["allowed"] == (
        "inputs, continuous states, parameters, algebraic variables and the independent variable")


# --- DAE424 initial-unknown-not-allowed --------------------------------------------------------

def test_initial_unknowns():
    ctx = _ctx('<InitialUnknown valueReference="3"/>'      # derivative, calculated: ok
               '<InitialUnknown valueReference="4"/>'      # algebraic: ok (D-10)
               '<InitialUnknown valueReference="13"/>'     # calculatedParameter: ok
               '<InitialUnknown valueReference="14"/>'     # output, calculated: ok
               '<InitialUnknown valueReference="15"/>'     # output, exact: not ok
               '<InitialUnknown valueReference="2"/>'      # state, exact: not ok
               '<InitialUnknown valueReference="8"/>'      # parameter: not ok
               '<InitialUnknown valueReference="12"/>'     # local (not a state): not ok
               '<InitialUnknown valueReference="6"/>'      # residual: not ok
               '<InitialUnknown valueReference="55"/>'     # no such variable
               '<Residual valueReference="6" dependencies="4 5"/>'
               '<Residual valueReference="7" dependencies="4 5"/>')
    found = _run("DAE424", ctx)
    assert [v.subject for v in found] == ["ye", "x", "k", "loc", "g1", "valueReference 55"]
    assert dict(found[4].evidence)["is_residual"] is True
    assert all(v.location.file == ctx.manifest.file for v in found)


# --- DAE425 state-derivative-mismatch ----------------------------------------------------------

def test_state_derivatives_equal_or_absent():
    assert _run("DAE425", _ctx('<ContinuousStateDerivative valueReference="3"/>')) == []
    assert _run("DAE425", _ctx('<InitialUnknown valueReference="4"/>')) == []


def test_state_derivative_mismatch_both_ways():
    ctx = _ctx('<ContinuousStateDerivative valueReference="19"/>')
    found = _run("DAE425", ctx)
    assert [(v.subject, v.location.file) for v in found] == [
        ("der2", ctx.manifest.file), ("der(x)", ctx.model.file)]


def test_state_derivative_without_derivative_attribute():
    ctx = _ctx('<ContinuousStateDerivative valueReference="3"/>'
               '<ContinuousStateDerivative valueReference="12"/>'
               '<ContinuousStateDerivative valueReference="88"/>')
    found = _run("DAE425", ctx)
    assert [v.subject for v in found] == ["loc", "valueReference 88"]
    unresolved = found[1]
    assert (unresolved.location.file, unresolved.location.line, unresolved.location.path) == (
        ctx.manifest.file, 4, "/fmiDAEManifest/ModelStructure/ContinuousStateDerivative[3]")
    assert dict(unresolved.evidence) == {"element": "ContinuousStateDerivative",
                                         "value_reference": 88}


# --- DAE426 output-set-mismatch ----------------------------------------------------------------

def test_outputs_absent_are_inherited():
    assert _run("DAE426", _ctx('<Residual valueReference="6"/>')) == []


def test_outputs_complete():
    ctx = _ctx('<Output valueReference="10"/><Output valueReference="14"/>'
               '<Output valueReference="15"/>')
    assert _run("DAE426", ctx) == []


def test_outputs_missing_and_extra():
    ctx = _ctx('<Output valueReference="14"/><Output valueReference="4"/>'
               '<Output valueReference="44"/>')
    found = _run("DAE426", ctx)
    assert [v.subject for v in found] == ["y", "valueReference 44", "n", "ye"]
    assert found[2].location.path.endswith("Output[3]")   # the missing ones point at the list
    assert dict(found[2].evidence)["value_reference"] == 10


# --- DAE601 index1-structurally-singular -------------------------------------------------------

def _dm(found):
    assert len(found) == 1
    return dict(found[0].evidence)


def test_index1_perfect_matching_is_clean():
    ctx = _ctx('<Residual valueReference="6" dependencies="4"/>'
               '<Residual valueReference="7"/>')   # absent: depends on every algebraic variable
    assert _run("DAE601", ctx) == []


def test_index1_redundant_and_undetermined():
    ctx = _ctx('<Residual valueReference="6" dependencies="2 4"/>'
               '<Residual valueReference="7" dependencies="4 9"/>')
    found = _run("DAE601", ctx)
    ev = _dm(found)
    assert ev["structural_rank"] == 1
    assert ev["over_determined_residuals"] == ("g1", "g2")
    assert ev["over_determined_variables"] == ("y",)
    assert ev["under_determined_variables"] == ("z",)
    assert ev["under_determined_residuals"] == ()
    assert found[0].subject == "g1"
    assert found[0].location.path.endswith("Residual[1]")
    assert "'g1'" in found[0].message and "'z'" in found[0].message
    # the text a user reads: counts agree with their nouns and verbs
    assert found[0].text == (
        "the Jacobian dg/dw of the residuals with respect to the algebraic variables is "
        "structurally singular (structural rank 1 of 2): 2 residuals 'g1', 'g2' together depend "
        "only on 1 algebraic variable 'y', so 1 of them is structurally redundant; 1 algebraic "
        "variable 'z' appears in no residual; give each algebraic variable a residual that "
        "determines it, or correct the residual dependencies")


def test_index1_empty_dependencies_mean_none():
    found = _run("DAE601", _ctx('<Residual valueReference="6"/>'
                                '<Residual valueReference="7" dependencies=""/>'))
    ev = _dm(found)
    assert ev["over_determined_residuals"] == ("g2",)
    assert ev["over_determined_variables"] == ()
    assert found[0].text == (
        "the Jacobian dg/dw of the residuals with respect to the algebraic variables is "
        "structurally singular (structural rank 1 of 2): 1 residual 'g2' depends on no "
        "algebraic variable; 2 algebraic variables 'y', 'z' together appear only in 1 residual "
        "'g1', so 1 of them is determined by no residual; give each algebraic variable a "
        "residual that determines it, or correct the residual dependencies")


def test_index1_only_undetermined_points_at_the_algebraic_variable():
    # three residuals, two algebraic variables: count mismatch is DAE405's, but the rank (1) is
    # below min(3, 2), and the extra residual alone would not explain it
    ctx = _ctx('<Residual valueReference="6" dependencies="4"/>'
               '<Residual valueReference="7" dependencies="4"/>'
               '<Residual valueReference="12" dependencies="4"/>')
    ev = _dm(_run("DAE601", ctx))
    assert ev["structural_rank"] == 1
    ctx = _ctx('<Residual valueReference="6" dependencies="4"/>', algebraic=("4", "5"))
    assert _run("DAE601", ctx) == []   # rank 1 == min(1, 2): only residual-count-mismatch


def test_index1_location_for_undetermined_only():
    # 1 residual, 2 algebraic variables, residual depends on nothing algebraic: rank 0 < 1
    found = _run("DAE601", _ctx('<Residual valueReference="6" dependencies="2"/>'))
    assert found[0].subject == "g1"
    found = _run("DAE601", _ctx('<Residual valueReference="6" dependencies="4"/>'
                                '<Residual valueReference="7" dependencies="4 9"/>',
                                algebraic=("4", "5", "12")))
    # over part {g1, g2} x {y}; under part {} x {z, loc}
    ev = _dm(found)
    assert ev["under_determined_variables"] == ("z", "loc")


def test_index1_arrays_are_expanded():
    # w has 2 elements, r has 2 (from the structural parameter nr): r depends on w: full block
    ctx = _ctx('<Residual valueReference="17" dependencies="16"/>', algebraic=("16",))
    assert _run("DAE601", ctx) == []
    ctx = _ctx('<Residual valueReference="17" dependencies="16"/>'
               '<Residual valueReference="6" dependencies="16"/>', algebraic=("16", "4"))
    ev = _dm(_run("DAE601", ctx))
    assert ev["residuals"] == 3 and ev["algebraic_variables"] == 3
    assert ev["over_determined_residuals"] == ("r[1]", "r[2]", "g1")
    assert ev["over_determined_variables"] == ("w[1]", "w[2]")
    assert ev["under_determined_variables"] == ("y",)


def test_index1_array_size_of_a_dimension_with_start_and_value_reference(monkeypatch):
    # a <Dimension> giving both start and valueReference has start's size, as
    # residual-count-mismatch counts it (algebraic.element_count): wb has 2 elements, not 3
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES + """
    <UInt64 name="n3" valueReference="40" causality="structuralParameter" variability="fixed"
            start="3"/>
    <Float64 name="wb" valueReference="41"><Dimension start="2" valueReference="40"/></Float64>
""")
    ctx = _ctx('<Residual valueReference="17" dependencies="41"/>'
               '<Residual valueReference="6" dependencies="41"/>', algebraic=("41", "4"))
    ev = _dm(_run("DAE601", ctx))
    assert (ev["residuals"], ev["algebraic_variables"]) == (3, 3)
    assert ev["over_determined_variables"] == ("wb[1]", "wb[2]")
    assert ev["under_determined_variables"] == ("y",)


def _index1_with_edges(ctx: CheckContext, max_edges: int) -> list:
    options = {**default_catalogue()["DAE601"].option_values, "max_edges": max_edges}
    return list(index1.index1_structurally_singular(ctx, **options))


def test_index1_skipped_above_max_edges_scalars(caplog):
    # g1 and g2 each list y (2 edges), and z appears in no residual: singular
    ctx = _ctx('<Residual valueReference="6" dependencies="2 4"/>'
               '<Residual valueReference="7" dependencies="4 9"/>')
    with caplog.at_level(logging.WARNING, logger="conformance.checks.index1"):
        assert _index1_with_edges(ctx, 1) == []
    assert caplog.messages == ["index-1 check skipped: more than 1 element edges"]
    caplog.clear()
    assert len(_index1_with_edges(ctx, 2)) == 1
    assert caplog.messages == []


def test_index1_skipped_above_max_edges_arrays(caplog):
    # the element edges of all residuals add up: r (2 elements) x w (2) = 4, g1 x w = 2
    ctx = _ctx('<Residual valueReference="17" dependencies="16"/>'
               '<Residual valueReference="6" dependencies="16"/>', algebraic=("16", "4"))
    with caplog.at_level(logging.WARNING, logger="conformance.checks.index1"):
        assert _index1_with_edges(ctx, 5) == []
    assert caplog.messages == ["index-1 check skipped: more than 5 element edges"]
    caplog.clear()
    [v] = _index1_with_edges(ctx, 6)
    assert v.subject == "r[1]" and dict(v.evidence)["structural_rank"] == 2
    assert caplog.messages == []


def test_index1_full_rank_that_a_greedy_matching_misses_is_clean():
    # greedy: g1 takes y, g2 finds y taken (1 of 2); the maximum matching g1-z, g2-y has 2
    ctx = _ctx('<Residual valueReference="6" dependencies="4 5"/>'
               '<Residual valueReference="7" dependencies="4"/>')
    assert _run("DAE601", ctx) == []


def test_index1_edges_of_a_residual_without_dependencies_are_not_counted(monkeypatch):
    # r (2 elements) depends on every algebraic variable (no dependencies attribute): those
    # edges are not counted against max_edges; g1 x w[1..2] are 2, g3 depends on nothing
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES",
                        VARIABLES + '<Float64 name="g3" valueReference="40"/>')
    ctx = _ctx('<Residual valueReference="17"/><Residual valueReference="6" dependencies="16"/>'
               '<Residual valueReference="40" dependencies=""/>', algebraic=("16", "4", "5"))
    [v] = _index1_with_edges(ctx, 2)
    assert v.subject == "g3"
    assert dict(v.evidence)["under_determined_residuals"] == ("r[1]", "r[2]", "g1")


def test_index1_scalar_residuals_of_array_variables():
    # w has 2 elements: g1 and g2 hold w[1], w[2], loc holds y (a column index per element,
    # not per variable)
    ctx = _ctx('<Residual valueReference="6" dependencies="16"/>'
               '<Residual valueReference="7" dependencies="16"/>'
               '<Residual valueReference="12" dependencies="4"/>', algebraic=("16", "4"))
    assert _run("DAE601", ctx) == []


def test_index1_skipped_when_a_residual_size_is_not_known(monkeypatch, caplog):
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES + (
        '<Float64 name="rq" valueReference="42"><Dimension valueReference="99"/></Float64>'))
    ctx = _ctx('<Residual valueReference="42" dependencies="16"/>', algebraic=("16",))
    with caplog.at_level(logging.INFO, logger="conformance.checks.index1"):
        assert _run("DAE601", ctx) == []
    assert caplog.messages == ["index-1 check skipped: size of rq is not known"]


def test_index1_skipped_when_a_size_is_not_known(monkeypatch, caplog):
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES + (
        '<Float64 name="wq" valueReference="42"><Dimension valueReference="99"/></Float64>'))
    ctx = _ctx('<Residual valueReference="6" dependencies="42"/>', algebraic=("42",))
    with caplog.at_level(logging.INFO, logger="conformance.checks.index1"):
        assert _run("DAE601", ctx) == []
    assert caplog.messages == ["index-1 check skipped: size of wq is not known"]


def test_index1_skipped_when_a_reference_does_not_resolve():
    ctx = _ctx('<Residual valueReference="6" dependencies="4"/>'
               '<Residual valueReference="99" dependencies="4"/>')
    assert _run("DAE601", ctx) == []
    ctx = _ctx('<Residual valueReference="6" dependencies="4"/>'
               '<Residual valueReference="7" dependencies="4"/>', algebraic=("4", "98"))
    assert _run("DAE601", ctx) == []


def test_index1_duplicates_counted_once():
    ctx = _ctx('<Residual valueReference="6" dependencies="4 4"/>'
               '<Residual valueReference="7" dependencies="5"/>'
               '<Residual valueReference="7" dependencies="5"/>', algebraic=("4", "5", "5"))
    assert _run("DAE601", ctx) == []


def test_index1_duplicates_keep_each_distinct_variable():
    # z is listed twice: still two algebraic variables (y, z), and g1 depends on neither
    ctx = _ctx('<Residual valueReference="6" dependencies="2"/>'
               '<Residual valueReference="7" dependencies="4"/>', algebraic=("4", "5", "5"))
    ev = _dm(_run("DAE601", ctx))
    assert (ev["structural_rank"], ev["residuals"], ev["algebraic_variables"]) == (1, 2, 2)
    assert ev["over_determined_residuals"] == ("g1",)
    assert ev["under_determined_variables"] == ("z",)


def test_index1_legacy_formulation():
    ctx = _ctx('<Residual><Formulation index="1" valueReference="6" dependencies="3 4"/></Residual>'
               '<Residual><Formulation index="1" valueReference="7" dependencies="3 4"/>'
               '</Residual>',
               draft="formulation", legacy=True)
    ev = _dm(_run("DAE601", ctx))
    assert ev["under_determined_variables"] == ("z",)


def test_index1_message_lists_few_names_evidence_many():
    n = 30
    variables = "".join(f'<Float64 name="a{i}" valueReference="{100 + i}"/>'
                        f'<Float64 name="g{i}" valueReference="{200 + i}"/>' for i in range(n))
    md = f"""<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">
  <ModelVariables>{variables}</ModelVariables></fmiModelDescription>"""
    alg = "".join(f'<AlgebraicVariable valueReference="{100 + i}"/>' for i in range(n))
    res = "".join(f'<Residual valueReference="{200 + i}" dependencies="100"/>' for i in range(n))
    man = (f'<fmiDAEManifest><EnableDAEParameter valueReference="1"/><AlgebraicVariables>{alg}'
           f'</AlgebraicVariables><ModelStructure>{res}</ModelStructure></fmiDAEManifest>')
    ctx = CheckContext(read_model_description(etree.ElementTree(etree.fromstring(md))),
                       read_manifest(etree.ElementTree(etree.fromstring(man)), draft="alpha1"),
                       "alpha1")
    options = {**default_catalogue()["DAE601"].option_values, "max_names": 3, "max_evidence": 10}
    found = list(index1.index1_structurally_singular(ctx, **options))
    ev = _dm(found)
    assert len(ev["over_determined_residuals"]) == 10
    assert ev["over_determined_size"] == (30, 1)
    assert ev["under_determined_size"] == (0, 29)
    assert "and 27 more" in found[0].message


def _chain(m: int, *, broken: int | None = None) -> CheckContext:
    """A chain DAE built directly as dataclasses (parsing 100k XML elements is the slow part):
    residual r[k] depends on x[k], w[k-1] and w[k]; ``broken`` drops w[k] from r[k]."""
    def var(name, vr, **kw):
        return Variable(name=name, vr=vr, type="Float64", causality="local",
                        variability="continuous", initial=None, declared_variability=None,
                        declared_initial=None, start=None, derivative=kw.get("derivative"),
                        line=None)
    variables = []
    for k in range(m):
        variables += [var(f"x[{k}]", 4 * k + 10), var(f"der(x[{k}])", 4 * k + 11,
                                                           derivative=4 * k + 10),
                      var(f"w[{k}]", 4 * k + 12), var(f"r[{k}]", 4 * k + 13)]
    md = ModelDescription(file="modelDescription.xml", fmi_version="3.0", model_name="chain",
                          instantiation_token="t", naming_convention="structured",
                          model_exchange=None, variables=tuple(variables), structure=())
    residuals = []
    for k in range(m):
        deps = [4 * k + 10] + ([4 * k + 8] if k else []) + ([] if k == broken else [4 * k + 12])
        residuals.append(Unknown(kind="Residual", vr=4 * k + 13, dependencies=tuple(deps),
                                 dependencies_kind=None, line=k + 3, file=MANIFEST,
                                 where=f"/fmiDAEManifest/ModelStructure/Residual[{k + 1}]"))
    algebraic = tuple(VrRef(vr=4 * k + 12, line=None, where="", element="AlgebraicVariable")
                      for k in range(m))
    manifest = Manifest(file=MANIFEST, root_name="fmiDAEManifest", root_namespace=None,
                        root_line=1, ls_name=None, ls_version=None, ls_description=None,
                        unqualified_ls_attributes=(), enables=(), algebraic=algebraic,
                        algebraic_line=2, structure=tuple(residuals), has_model_structure=True,
                        is_dae_fmu=None, draft="alpha1")
    return CheckContext(md, manifest, "alpha1")


def test_index1_large_chain():
    # speed is measured by `make bench` (reports/bench/static.md), never by a timed test
    ctx = _chain(25_000)
    assert _run("DAE601", ctx) == []
    ctx = _chain(25_000, broken=12_500)
    found = _run("DAE601", ctx)
    ev = _dm(found)
    # r[12500] depends on w[12499] only: r[0..12500] (12501 residuals) hold w[0..12499]
    assert ev["structural_rank"] == 24_999
    assert ev["over_determined_size"] == (12_501, 12_500)
    assert ev["under_determined_size"] == (12_499, 12_500)
    assert found[0].subject == "r[0]"


def test_index1_matches_the_bench_generator():
    m = 50
    md = read_model_description(etree.ElementTree(etree.fromstring(
        model_description_xml(m).encode())))
    man = read_manifest(etree.ElementTree(etree.fromstring(manifest_xml(m).encode())),
                        draft="alpha1")
    assert _run("DAE601", CheckContext(md, man, "alpha1")) == []


# --- parts (catalogue [[rule.parts]]): the sub-check a violation is ---------------------------

# a discrete local (a discrete-time state of FMI 3.0.2 §2.1) and a discrete output
_DISCRETE = """
    <Float64 name="xd" valueReference="30" variability="discrete" initial="exact" start="0"/>
    <Float64 name="yd" valueReference="31" causality="output" variability="discrete"/>
"""


@pytest.mark.parametrize("code, structure, parts", [
    ("DAE420", '<Residual valueReference="6" dependencies="4 99"/>', [None]),
    ("DAE420", '<Output valueReference="14" dependencies="99"/>'
               '<ContinuousStateDerivative valueReference="3" dependencies="98"/>'
               '<InitialUnknown valueReference="4" dependencies="97"/>'
               '<EventIndicator valueReference="12" dependencies="96"/>',
     ["core-element-dependency"] * 4),
    ("DAE421", '<Residual valueReference="6" dependencies="4 5 12"/>', [None]),
    ("DAE421", '<Residual valueReference="6" dependencies="4 5 30"/>', [None]),
    ("DAE421", '<Output valueReference="14" dependencies="12"/>', ["output-or-derivative-known"]),
    ("DAE421", '<Output valueReference="14" dependencies="31"/>', ["output-or-derivative-known"]),
    ("DAE421", '<ContinuousStateDerivative valueReference="3" dependencies="3"/>',
     ["output-or-derivative-known"]),
    ("DAE421", '<Output valueReference="14" dependencies="30"/>', ["discrete-time-state-known"]),
    ("DAE421", '<ContinuousStateDerivative valueReference="3" dependencies="30"/>',
     ["discrete-time-state-known"]),
    ("DAE421", '<InitialUnknown valueReference="4" dependencies="3 12"/>',
     ["initial-unknown-known"] * 2),
    ("DAE424", '<InitialUnknown valueReference="12"/><InitialUnknown valueReference="8"/>',
     [None, None]),
    ("DAE424", '<EventIndicator valueReference="12"/><InitialUnknown valueReference="12"/>',
     ["event-indicator"]),
    ("DAE424", '<Residual valueReference="6"/><InitialUnknown valueReference="6"/>', [None]),
    ("DAE424", '<Residual valueReference="14"/><InitialUnknown valueReference="14"/>',
     ["output-residual"]),
    ("DAE424", '<Residual valueReference="15"/><InitialUnknown valueReference="15"/>', [None]),
    ("DAE424", '<InitialUnknown valueReference="55"/>', ["unresolved"]),
    ("DAE425", '<ContinuousStateDerivative valueReference="19"/>', [None, None]),
    ("DAE425", '<ContinuousStateDerivative valueReference="3"/>'
               '<ContinuousStateDerivative valueReference="12"/>'
               '<ContinuousStateDerivative valueReference="88"/>',
     ["no-derivative-attribute", "unresolved"]),
    ("DAE426", '<Output valueReference="10"/><Output valueReference="14"/>'
               '<Output valueReference="15"/><Output valueReference="31"/>'
               '<Output valueReference="44"/>', [None]),
])
def test_part_of_violation(code, structure, parts, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "VARIABLES", VARIABLES + _DISCRETE)
    assert [v.part for v in _run(code, _ctx(structure))] == parts


def test_event_indicator_of_model_description_when_the_manifest_lists_none():
    ctx = _ctx('<InitialUnknown valueReference="12"/>',
               md_structure=MD_STRUCTURE + '<EventIndicator valueReference="12"/>')
    assert [v.part for v in _run("DAE424", ctx)] == ["event-indicator"]
