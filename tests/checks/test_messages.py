"""The text a user reads for a static rule's finding, exactly.

``Violation.text`` is the message with its subject filled in, as every reporter shows it. The
family tests pin what decides a finding (code, subject, location, evidence); these pin the
words, which no reporter test sees for the static rules: mutation testing of conformance/checks
(docs/mutation-self.md) changed these texts (a clause upper-cased, an element name misspelt, a
message emptied) and no test failed. One case per message, on the family tests' in-memory XML.
"""
from __future__ import annotations

import re
from typing import Callable

import pytest
from lxml import etree

from conformance.checks import REGISTRY
from conformance.checks.context import CheckContext
from conformance.model.manifest import read_manifest
from tests.checks import test_algebraic_residual as alg
from tests.checks import test_core_rules as core
from tests.checks import test_header_enable as hdr
from tests.checks import test_model_types_rules as types
from tests.checks import test_structure_rules as struct

# an AlgebraicVariable and a Residual without valueReference
_NO_VR = """<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">
  <EnableDAEParameter valueReference="1"/>
  <AlgebraicVariables>
    <AlgebraicVariable valueReference="4"/>
    <AlgebraicVariable/>
  </AlgebraicVariables>
  <ModelStructure>
    <ContinuousStateDerivative valueReference="3" dependencies="4"/>
    <Residual valueReference="6" dependencies="2 4"/>
    <Residual/>
  </ModelStructure>
</fmiDAEManifest>"""


def _no_vr() -> CheckContext:
    return alg._ctx(read_manifest(etree.ElementTree(etree.fromstring(_NO_VR)), draft="alpha1"))


def _enable_variable(old: str, new: str) -> CheckContext:
    return hdr.ctx(hdr.alpha1(), hdr.model(dae_var=hdr.DAE_VAR.replace(old, new)))


CASES: list[tuple[str, Callable[[], CheckContext], list[str]]] = [
    ("DAE101", lambda: CheckContext(None, None, None,
                                    names=("modelDescription.xml", "fmi-ls-manifest.xml")), [
        "an fmi-ls-dae manifest is stored as 'fmi-ls-manifest.xml', where importers do not look "
        "for it, so the FMU is treated as a plain Model Exchange FMU; move it to "
        "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"]),
    ("DAE102", lambda: hdr.ctx(hdr.alpha1(name='fmi-ls:fmi-ls-name="fmi-ls-dae"')), [
        "the manifest's 'fmi-ls-name' is not \"org.fmi-standard.fmi-ls-dae\"; importers "
        "recognise the layered standard by this exact reverse-DNS name"]),
    ("DAE103", lambda: hdr.ctx(hdr.alpha1(version='fmi-ls:fmi-ls-version="0.1"')), [
        "the manifest's 'fmi-ls-version' names a draft older than 1.0.0-alpha.1 although the "
        'manifest has the 1.0.0-alpha.1 shape; set it to "1.0.0-alpha.1"']),
    ("DAE103", lambda: hdr.ctx(hdr.formulation(version='fmi-ls:fmi-ls-version="draft"'),
                               draft="formulation"), [
        "the manifest's 'fmi-ls-version' is not a version number (MAJOR.MINOR.PATCH); the "
        'current version is "1.0.0-alpha.1"']),
    ("DAE105", lambda: hdr.ctx(hdr.alpha1(version='fmi-ls:fmi-ls-version="1.0.0"')), [
        'the manifest declares fmi-ls-version "1.0.0", a version lsdae does not know: it was '
        "checked against 1.0.0-alpha.1, the normative draft, and is labelled so in this report; "
        'fmi-rs and fmusim accept exactly "1.0.0-alpha.1" and reject the manifest']),
    ("DAE201", lambda: hdr.ctx(hdr.alpha1(enable_xml="")), [
        "the manifest names no enable parameter, so an importer cannot switch DAE mode on, nor "
        "tell a DAE-only FMU from one that starts in ODE mode; add <EnableDAEParameter "
        'valueReference=".."/> naming a Boolean structuralParameter with start="false"']),
    ("DAE202", lambda: hdr.ctx(hdr.alpha1(enable_xml='<EnableDAEParameter valueReference="99"/>')),
     ["the enable parameter's valueReference '99' names no variable of modelDescription.xml"]),
    ("DAE202", lambda: hdr.ctx(hdr.formulation(root_attrs='enableDAEModeVariable="Switch"'),
                               draft="formulation"), [
        "the enable parameter is given by the name 'Switch', which names no variable of "
        'modelDescription.xml; use <EnableDAEParameter valueReference=".."/>']),
    ("DAE202", lambda: hdr.ctx(hdr.alpha1(enable_xml="<EnableDAEParameter/>")), [
        "<'EnableDAEParameter'> has no valueReference; point it at the Boolean structural "
        "parameter that switches DAE mode on"]),
    ("DAE204", lambda: _enable_variable('causality="structuralParameter"',
                                        'causality="parameter"'), [
        "enable parameter 'dae' must have causality=\"structuralParameter\", so it can be set "
        "in Configuration Mode"]),
    ("DAE205", lambda: _enable_variable('variability="fixed"', 'variability="discrete"'), [
        "enable parameter 'dae' has a variability that a structural parameter cannot have; "
        'set variability="fixed" or "tunable"']),
    ("DAE206", lambda: _enable_variable(' start="false"', ''), [
        "enable parameter 'dae' has no start value; set start=\"false\""]),
    ("DAE206", lambda: _enable_variable('start="false"', 'start="true"'), [
        "enable parameter 'dae' does not start as false, so the FMU would not start in ODE "
        'mode; set start="false"']),
    ("DAE207", lambda: _enable_variable('start="false"/>',
                                        'start="false"><Dimension start="2"/></Boolean>'), [
        "enable parameter 'dae' is an array; remove its <Dimension> elements"]),
    ("DAE207", lambda: hdr.ctx(hdr.alpha1(), hdr.model(
        extra='<Float64 name="w" valueReference="9"><Dimension valueReference="1"/></Float64>')), [
        "enable parameter 'dae' gives the size of an array <Dimension>; use a separate UInt64 "
        "structural parameter for array sizes"]),
    ("DAE208", lambda: hdr.ctx(hdr.alpha1(enable_xml=hdr.ENABLE + hdr.ENABLE)), [
        "the manifest names a second enable parameter ('EnableDAEParameter'); keep exactly one "
        "<EnableDAEParameter>"]),
    ("DAE104", lambda: hdr.ctx(hdr.alpha1(description="")), [
        "the manifest root has no 'fmi-ls-description' attribute; add "
        'fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI."']),
    ("DAE103", lambda: hdr.ctx(hdr.alpha1(version='fmi-ls:fmi-ls-version="1.0"')), [
        "the manifest's 'fmi-ls-version' is not a semantic version (MAJOR.MINOR.PATCH); this "
        'manifest has the 1.0.0-alpha.1 shape, so set it to "1.0.0-alpha.1"']),
    ("DAE301", _no_vr, [
        "an AlgebraicVariable has no valueReference attribute; give the valueReference of the "
        "variable the importer solves for"]),
    ("DAE301", lambda: alg._ctx(alg._alpha1(("4", "99"))), [
        "AlgebraicVariable valueReference '99' names no variable of modelDescription.xml; use "
        "the valueReference of an existing Float64 variable"]),
    ("DAE303", lambda: alg._ctx(alg._alpha1(("4", "10"))), [
        "algebraic variable 'n' is not a Float32 or Float64; the importer sets algebraic "
        "variables with fmi3SetFloat64/32 and iterates on them, so list only floating-point "
        "variables"]),
    ("DAE304", lambda: alg._ctx(alg._alpha1(("4", "12"))), [
        "algebraic variable 'd' is not continuous; the importer changes it at every solver "
        'iteration in Continuous-Time Mode, so declare variability="continuous" or remove it '
        "from <AlgebraicVariables>"]),
    ("DAE306", lambda: alg._ctx(alg._alpha1(("4", "9"))), [
        "algebraic variable 'u' is an input, a parameter or the independent variable, a known "
        "that the environment provides; list only local or output variables that the residuals "
        "determine"]),
    ("DAE401", _no_vr, [
        "a Residual has no valueReference, or one that is not an unsigned integer; give the "
        "valueReference of the variable that holds the residual"]),
    ("DAE401", lambda: alg._ctx(alg._alpha1(("4", "5"), ("6", "77"))), [
        "Residual valueReference '77' names no variable of modelDescription.xml; use the "
        "valueReference of the Float64 variable that holds the residual"]),
    ("DAE402", lambda: alg._ctx(alg._alpha1(("4", "5"), ("6", "6"))), [
        "residual 'g1' is listed in more than one Residual element; list each residual once"]),
    ("DAE405", lambda: alg._ctx(alg._alpha1(("4", "5"), ("6",))), [
        "the manifest has 1 residual element(s) for 2 algebraic variable element(s); the "
        "Jacobian of the residuals with respect to the algebraic variables cannot be square, so "
        "list one residual per algebraic variable"]),
    ("DAE403", lambda: alg._ctx(alg._alpha1(("4", "5"), ("6", "12"))), [
        "residual 'd' is not a continuous Float32 or Float64 variable; the importer reads "
        "residuals with fmi3GetFloat64/32 at every solver iteration, so declare it as a "
        "continuous floating-point variable"]),
    ("DAE404", lambda: alg._ctx(alg._alpha1(("4", "5"), ("6", "9"))), [
        "residual 'u' is a continuous state, a state derivative, an input or the independent "
        "variable; a residual must be a local or output variable that the FMU computes from the "
        "algebraic variables"]),
    ("DAE406", lambda: struct._ctx('<Residual valueReference="6" dependencies="3 2"/>',
                                   algebraic=()), [
        "the manifest describes the fully implicit form 0 = F(der(x), x, w, t): 1 residuals for "
        "1 states and 0 algebraic variables, and no <ContinuousStateDerivative>; fmi-ls-dae "
        "1.0.0-alpha.1 §2.2 supports only the semi-explicit form der(x) = f(x, w, t), "
        "0 = g(x, w, t). Rewrite it as the standard does: add one algebraic variable v_i per "
        "state derivative, let each der(x_i) be computed as v_i and list it as "
        "<ContinuousStateDerivative>, and keep the residuals F(v, x, w, t) = 0, which then "
        "determine v and w together (as many residuals as algebraic variables)"]),
    ("DAE407", lambda: struct._ctx("", algebraic=("4",)), [
        "the manifest's <ModelStructure> lists no <ContinuousStateDerivative>, although the "
        "model has 1 continuous state(s); in DAE mode the manifest's structure replaces "
        "modelDescription's, and importers disagree on what an empty list means: one reads the "
        "manifest as the fully implicit form and refuses the FMU, another builds a DAE without "
        "states. List every <ContinuousStateDerivative> (with its DAE-mode dependencies) in the "
        "manifest"]),
    ("DAE420", lambda: struct._ctx(
        '<Residual><Formulation index="1" valueReference="6" dependencies="3 4 99"/></Residual>'
        '<Residual><Formulation index="1" valueReference="7" dependencies="3 4"/></Residual>',
        draft="formulation", legacy=True), [
        "the dependencies of <Formulation> 'g1' list valueReference 99, which names no "
        "variable in modelDescription.xml"]),
    ("DAE422", lambda: struct._ctx('<Residual valueReference="6" dependenciesKind="constant"/>'
                                   '<Residual valueReference="7"/>'), [
        "<Residual> 'g1' has dependenciesKind but no dependencies attribute; remove "
        "dependenciesKind or list the dependencies it describes"]),
    ("DAE423", lambda: struct._ctx(
        '<InitialUnknown valueReference="4" dependencies="2" dependenciesKind="fixed"/>'), [
        "<InitialUnknown> 'y' uses dependenciesKind 'fixed'; an initial unknown allows only "
        "'dependent' or 'constant'"]),
    ("DAE424", lambda: struct._ctx('<InitialUnknown valueReference="55"/>'), [
        "<InitialUnknown> 'valueReference 55' names no variable in modelDescription.xml"]),
    ("DAE424", lambda: struct._ctx('<InitialUnknown valueReference="12"/>'), [
        "'loc' is listed as <InitialUnknown> but is a local variable with initial=\"calculated\"; "
        'initial unknowns are outputs, continuous states and state derivatives with '
        'initial="approx" or "calculated", calculated parameters, and algebraic variables']),
    ("DAE424", lambda: struct._ctx('<Residual valueReference="6"/>'
                                   '<InitialUnknown valueReference="6"/>'), [
        "residual 'g1' is listed as <InitialUnknown>; list the algebraic variable it determines "
        "instead, not the residual"]),
    ("DAE425", lambda: struct._ctx('<ContinuousStateDerivative valueReference="19"/>'), [
        "'der2' is a <ContinuousStateDerivative> in the manifest but not in "
        "modelDescription.xml, so DAE and ODE mode have different state derivative vectors",
        "'der(x)' is a <ContinuousStateDerivative> in modelDescription.xml but not in the "
        "manifest, so DAE and ODE mode have different state derivative vectors"]),
    ("DAE425", lambda: struct._ctx('<ContinuousStateDerivative valueReference="12"/>'), [
        "<ContinuousStateDerivative> 'loc' has no derivative attribute, so it names no state; "
        'add derivative="<valueReference of the state>" to the variable',
        "'der(x)' is a <ContinuousStateDerivative> in modelDescription.xml but not in the "
        "manifest, so DAE and ODE mode have different state derivative vectors"]),
    ("DAE426", lambda: struct._ctx('<Output valueReference="10"/><Output valueReference="14"/>'),
     ["output 'ye' is missing from the manifest's <Output> list; in DAE mode the manifest "
      "list replaces modelDescription.xml's, so add an <Output> for it"]),
    ("DAE426", lambda: struct._ctx('<Output valueReference="10"/><Output valueReference="14"/>'
                                   '<Output valueReference="15"/><Output valueReference="8"/>'),
     ["<Output> 'k' is a parameter, not a causality=\"output\" variable; list only outputs"]),
    ("DAE426", lambda: struct._ctx('<Output valueReference="10"/><Output valueReference="14"/>'
                                   '<Output valueReference="15"/><Output valueReference="0"/>'),
     ["<Output> 'time' is the independent variable, not a causality=\"output\" variable; list "
      "only outputs"]),
    ("DAE426", lambda: struct._ctx('<Output valueReference="10"/><Output valueReference="14"/>'
                                   '<Output valueReference="15"/><Output valueReference="11"/>'),
     ["<Output> 'c' is a constant, not a causality=\"output\" variable; list only outputs"]),
    ("DAE427", lambda: struct._ctx('<Invariant valueReference="6"/>'), [
        "the manifest's <ModelStructure> has an <Invariant>, which only the working group's "
        '"ODE with invariants" text defines, not 1.0.0-alpha.1: lsdae accepts it (and probes '
        "it, invariant-drift), but fmi-rs and fmusim validate the manifest against the alpha.1 "
        "XSD they vendor, which has no <Invariant>, and reject the whole manifest"]),
    ("DAE501", lambda: core.ctx_of(me='<CoSimulation modelIdentifier="M"/>'), [
        "modelDescription.xml has no <ModelExchange> element; fmi-ls-dae applies to Model "
        'Exchange FMUs only, so add <ModelExchange modelIdentifier="..."/> and export the Model '
        "Exchange interface"]),
    ("DAE502", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="w" valueReference="4"/>')), [
        "valueReference already used by an earlier variable, reused by 'w'; give every variable "
        "its own valueReference (FMI 3.0 aliases are <Alias> children)"]),
    ("DAE503", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="y" valueReference="9"/>')), [
        "name used by more than one variable or alias: 'y'; rename so that every variable and "
        "alias name is unique"]),
    ("DAE505", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="p" valueReference="9" causality="input" initial="approx" start="1"/>')), [
        "initial not allowed for the causality and variability of 'p'; use an allowed value "
        "(see the evidence) or remove the attribute"]),
    ("DAE508", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="t2" valueReference="9" causality="independent"/>')), [
        "causality=\"independent\" on 't2' besides the first independent variable; FMI 3.0 "
        "allows exactly one, make the others local"]),
    ("DAE508", lambda: core.ctx_of(variables=core.VARIABLES.replace(
        'causality="independent" variability="continuous"', "")), [
        'modelDescription.xml has no variable with causality="independent"; FMI 3.0 requires '
        'exactly one, add e.g. <Float64 name="time" causality="independent" '
        'variability="continuous" .../>']),
    ("DAE508", lambda: core.ctx_of(variables=core.VARIABLES.replace(
        'causality="independent" variability="continuous"',
        'causality="independent" variability="continuous" start="0"')), [
        "independent variable 'time' must be a continuous Float32/Float64 without start or "
        "initial attributes; fix the attributes listed in the evidence"]),
    ("DAE509", lambda: core.ctx_of(
        variables=core.VARIABLES.replace('derivative="2"', 'derivative="1"')), [
        "derivative attribute naming a variable that is not a Float32/Float64, on 'der(x)'; "
        "derivatives can only be of floating-point variables"]),
    ("DAE509", lambda: core.ctx_of(variables=core.VARIABLES.replace(' derivative="2"', "")), [
        "<ContinuousStateDerivative> without a derivative attribute: 'der(x)'; add "
        'derivative="<valueReference of its state>"']),
    ("DAE509", lambda: core.ctx_of(variables=core.VARIABLES.replace(
        'initial="exact" start="1"', 'variability="discrete" initial="exact" start="1"')), [
        "<ContinuousStateDerivative> that is, or whose state is, not continuous: 'der(x)'; "
        "states and their derivatives must be continuous floats"]),
    ("DAE509", lambda: core.ctx_of(
        variables=core.VARIABLES.replace('derivative="2"', 'derivative="99"')), [
        "derivative attribute naming a valueReference that no variable has, on 'der(x)'; point "
        "it at the variable this one is the derivative of"]),
    ("DAE510", lambda: core.ctx_of(
        structure=core.STRUCTURE + '<Output valueReference="8" dependencies="2 99"/>'), [
        "dependencies naming value references that no variable has, in the ModelStructure "
        "element of 'v'; list only existing variables"]),
    ("DAE510", lambda: core.ctx_of(
        structure=core.STRUCTURE + '<InitialUnknown valueReference="99"/>'),
     ["ModelStructure element naming a valueReference that no variable has: 'InitialUnknown "
      "valueReference=99'; list only existing variables"]),
    ("DAE511", lambda: core.ctx_of(variables=core.VARIABLES.replace(
        'name="v" valueReference="8" causality="output"', 'name="v" valueReference="8"')), [
        "<Output> naming a variable whose causality is not \"output\": 'v'; list only outputs "
        "under <Output>"]),
    ("DAE511", lambda: core.ctx_of(structure=core.STRUCTURE.replace(
        '<Output valueReference="8" dependencies="2"/>', '')), [
        "output missing from the <Output> list: 'v'; add <Output valueReference=\"...\"/> for "
        "every output"]),
    ("DAE512", lambda: core.ctx_of(structure=core.STRUCTURE.replace(
        '<ContinuousStateDerivative valueReference="3" dependencies="2"/>', '')), [
        "state derivative not listed as <ContinuousStateDerivative>: 'der(x)'; Model Exchange "
        "must list every state derivative in the ModelStructure"]),
    ("DAE513", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="cp" valueReference="9" causality="calculatedParameter"/>')), [
        "missing from the <InitialUnknown> list: 'cp'; outputs, calculated parameters, states "
        "and derivatives with initial approx or calculated must be listed, add it"]),
    ("DAE509", lambda: core.ctx_of(
        structure=core.STRUCTURE + '<ContinuousStateDerivative valueReference="3"/>'), [
        "<ContinuousStateDerivative> naming a state that an earlier one already names: "
        "'der(x)'; list every state exactly once"]),
    ("DAE513", lambda: core.ctx_of(
        structure=core.STRUCTURE + '<InitialUnknown valueReference="8"/>'), [
        "<InitialUnknown> listed twice: 'v'; list every initial unknown exactly once"]),
    ("DAE513", lambda: core.ctx_of(
        structure=core.STRUCTURE + '<InitialUnknown valueReference="2"/>'), [
        "<InitialUnknown> naming neither an output, calculated parameter, state or state "
        "derivative with initial approx or calculated, nor a clocked variable: 'x'; remove it"]),
    ("DAE522", lambda: core.ctx_of(variables=core.VARIABLES + (
        '<Float64 name="p" valueReference="9" min="2" max="1"/>')), [
        "'p': min > max = '2 > 1'; no value lies in the range: swap or correct the bounds"]),
    ("DAE515", lambda: core.ctx_of(
        variables=core.VARIABLES.replace('derivative="2"', 'derivative="9"'),
        structure=core.STRUCTURE + '<Output valueReference="9" dependencies="2"/>'), [
        "the output '9' is itself a continuous state and its dependencies (\"2\") do not name "
        "it; FMI 3.0 does not say whether they should (open question, Reference-FMUs issue "
        "657): importers must not rely on a self-dependency, and lsdae does not probe this "
        "output's own entry"]),
    ("DAE531", lambda: types.ctx_of('<Float64 name="v" valueReference="5" unit="km"/>',
                                    definitions=types.UNITS), [
        "unit naming no <Unit> of <UnitDefinitions>, on 'v'; define <Unit name=\"...\"> under "
        "<UnitDefinitions> or correct the name"]),
    ("DAE532", lambda: types.ctx_of('<Float64 name="v" valueReference="5" displayUnit="mm"/>',
                                    definitions=types.UNITS), [
        "displayUnit without a unit, on 'v'; a display unit converts from a unit, so add the "
        "unit attribute (or remove displayUnit)"]),
    ("DAE537", lambda: types.ctx_of('<Float64 name="c" valueReference="2"/>'
                                    '<Float64 name="s" valueReference="3" variability="discrete" '
                                    'clocks="2"/>'), [
        "clocks entry naming a variable that is not a Clock, on 's'; list only the value "
        "references of <Clock> variables"]),
    ("DAE532", lambda: types.ctx_of(
        '<Float64 name="v" valueReference="5" unit="m" displayUnit="km"/>',
        definitions=types.UNITS), [
        "displayUnit naming no <DisplayUnit> of its unit, on 'v'; add <DisplayUnit "
        'name="..."> to that <Unit> or correct the name']),
    ("DAE537", lambda: types.ctx_of(
        '<Float64 name="s" valueReference="3" variability="discrete" clocks="9"/>'), [
        "clocks entry naming no variable, on 's'; list the value references of the Clock "
        "variables this variable is clocked by"]),
    ("DAE533", lambda: types.ctx_of('<Float64 name="" valueReference="2"/>', naming="flat"), [
        "name that is empty or contains a carriage return, line feed or tab: '(empty variable "
        "name)'; give every variable and alias a non-empty name without these characters"]),
    ("DAE534", lambda: types.ctx_of('<Float64 name="a b" valueReference="5"/>'), [
        "name that breaks the structured naming convention: 'a b'; write it as dotted parts of "
        "letters, digits and '_' (not starting with a digit), quote any other part as '...', "
        "and use [i,j] for array elements and der(name) for derivatives, or declare "
        'variableNamingConvention="flat"']),
]


def _case_id(code: str, texts: list[str]) -> str:
    """The code and the first words of the text: an id that stays with its case."""
    words = re.findall(r"[a-z0-9]+", texts[0].lower())[:10]
    return "-".join([code, *words])


@pytest.mark.parametrize("code, context, texts", CASES,
                         ids=[_case_id(code, texts) for code, _, texts in CASES])
def test_text(code, context, texts):
    ctx = context()
    assert [v.text for v in REGISTRY[code](ctx)] == texts
