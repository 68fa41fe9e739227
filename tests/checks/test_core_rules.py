"""Unit tests of the core modelDescription checks (conformance/checks/model_variables.py and
model_structure.py, DAE5xx)."""
from __future__ import annotations


import pytest
from lxml import etree

from conformance.checks import model_structure, model_variables
from conformance.checks.context import CheckContext
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description

# HelloWorldDAE-like: time 0, dae 1, x 2, der(x) 3, y 4, z 5, g1 6, g2 7, plus an output v 8.
VARIABLES = """
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Boolean name="dae" valueReference="1" causality="structuralParameter" variability="fixed"
             start="false"/>
    <Float64 name="x" valueReference="2" initial="exact" start="1"/>
    <Float64 name="der(x)" valueReference="3" derivative="2"/>
    <Float64 name="y" valueReference="4" initial="approx" start="0"/>
    <Float64 name="z" valueReference="5" initial="approx" start="0"/>
    <Float64 name="g1" valueReference="6"/>
    <Float64 name="g2" valueReference="7"/>
    <Float64 name="v" valueReference="8" causality="output"/>
"""
STRUCTURE = """
    <Output valueReference="8" dependencies="2"/>
    <ContinuousStateDerivative valueReference="3" dependencies="2"/>
    <InitialUnknown valueReference="8" dependencies="2"/>
    <InitialUnknown valueReference="3" dependencies="2"/>
"""
ME = '<ModelExchange modelIdentifier="M" providesDirectionalDerivatives="true"/>'
MANIFEST = """<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">
  <EnableDAEParameter valueReference="1"/>
  <AlgebraicVariables><AlgebraicVariable valueReference="4"/></AlgebraicVariables>
  <ModelStructure/>
</fmiDAEManifest>"""


def md_xml(variables: str = VARIABLES, structure: str = STRUCTURE, me: str = ME) -> str:
    return (f'<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">{me}'
            f"<ModelVariables>{variables}</ModelVariables>"
            f"<ModelStructure>{structure}</ModelStructure></fmiModelDescription>")


def ctx_of(xml: str | None = None, *, manifest: str | None = None, **parts: str) -> CheckContext:
    text = xml if xml is not None else md_xml(**parts)
    model = read_model_description(etree.ElementTree(etree.fromstring(text)))
    man = None
    if manifest is not None:
        man = read_manifest(etree.ElementTree(etree.fromstring(manifest)), draft="alpha1")
    return CheckContext(model=model, manifest=man, draft="alpha1" if man else None)


CHECKS = {**model_variables.CHECKS, **model_structure.CHECKS}


def run(code: str, ctx: CheckContext) -> list:
    return list(CHECKS[code](ctx))


def subjects(code: str, ctx: CheckContext) -> list:
    return [v.subject for v in run(code, ctx)]


def ev(violation) -> dict:
    return dict(violation.evidence)


def test_base_model_is_clean():
    ctx = ctx_of(manifest=MANIFEST)
    for code in CHECKS:
        assert run(code, ctx) == [], code


def test_no_model_no_findings():
    ctx = CheckContext(model=None, manifest=None, draft=None)
    for code in CHECKS:
        assert run(code, ctx) == []


def test_same_fault_gives_the_same_message_template():
    # Grouping relies on the message being the same for the same fault class.
    ctx = ctx_of(variables=VARIABLES.replace('"g1" valueReference="6"', '"g1" valueReference="5"')
                 + '<Float64 name="q" valueReference="5"/>')
    found = run("DAE502", ctx)
    assert len(found) == 2 and len({v.message for v in found}) == 1
    assert all("{subject}" in v.message for v in found)


# --- DAE501 model-exchange-missing -----------------------------------------------------------

def test_model_exchange_missing():
    ctx = ctx_of(me='<CoSimulation modelIdentifier="M"/>')
    [v] = run("DAE501", ctx)
    assert v.location.path == "/fmiModelDescription" and v.location.line == 1
    assert ev(v)["has_co_simulation"] is True


# --- DAE502 value-reference-duplicate ---------------------------------------------------------

def test_value_reference_duplicate_points_at_the_second():
    ctx = ctx_of(variables=VARIABLES + '<Float64 name="w" valueReference="4"/>')
    [v] = run("DAE502", ctx)
    assert v.subject == "w" and ev(v)["first_variable"] == "y" and ev(v)["value_reference"] == 4
    assert v.location.path.endswith("[@name='w']")


# --- DAE503 variable-name-duplicate -----------------------------------------------------------

def test_variable_name_duplicate():
    ctx = ctx_of(variables=VARIABLES + '<Float64 name="y" valueReference="9"/>')
    [v] = run("DAE503", ctx)
    assert v.subject == "y" and ev(v)["value_reference"] == 9 and ev(v)["alias"] is False
    assert (v.location.line, v.location.path) == (
        12, "/fmiModelDescription/ModelVariables/Float64[@name='y']")


def test_alias_names_take_part_when_the_model_reads_them():
    class Alias:
        def __init__(self, name):
            self.name, self.line = name, 42
    ctx = ctx_of()
    model = ctx.model
    fake = [type("V", (), {"name": v.name, "line": v.line, "path": v.path, "vr": v.vr,
                           "aliases": (Alias("x"),) if v.name == "z" else ("zz",)})()
            for v in model.variables]
    fake_model = type("M", (), {"variables": fake, "file": model.file})()
    found = list(model_variables.variable_name_duplicate(CheckContext(fake_model, None, None)))
    # 'x' reused by an alias of z; 'zz' is the alias of every other variable.
    assert [v.subject for v in found].count("x") == 1
    assert [v.subject for v in found].count("zz") == len(fake) - 2
    alias_x = next(v for v in found if v.subject == "x")
    assert alias_x.location.line == 42 and ev(alias_x)["alias"] is True


# --- DAE504 causality-variability-invalid -----------------------------------------------------

@pytest.mark.parametrize("decl, fault", [
    ('<Float64 name="p" valueReference="9" causality="parameter" variability="continuous" '
     'start="1"/>', "combination"),
    ('<Float64 name="p" valueReference="9" causality="input" variability="fixed" start="1"/>',
     "combination"),
    ('<Float64 name="p" valueReference="9" causality="input" variability="constant" '
     'start="1"/>', "combination"),
    ('<Float64 name="p" valueReference="9" causality="calculatedParameter" '
     'variability="discrete"/>', "combination"),
    ('<Int32 name="p" valueReference="9" variability="continuous"/>', "continuous-non-float"),
    ('<Boolean name="p" valueReference="9" causality="output" variability="continuous"/>',
     "continuous-non-float"),
    ('<Clock name="p" valueReference="9" causality="parameter"/>', "clock-causality"),
    ('<Clock name="p" valueReference="9" causality="input" variability="tunable"/>',
     "clock-variability"),
    ('<Float64 name="p" valueReference="9" clocks="10"/>', "clocked"),
])
def test_causality_variability_invalid(decl, fault):
    [v] = run("DAE504", ctx_of(variables=VARIABLES + decl))
    assert v.subject == "p" and ev(v)["fault"] == fault


@pytest.mark.parametrize("decl", [
    '<Float64 name="p" valueReference="9" causality="parameter" variability="tunable" start="1"/>',
    '<Float64 name="p" valueReference="9" causality="parameter" start="1"/>',    # default fixed
    '<Int32 name="p" valueReference="9" causality="input" start="1"/>',          # default discrete
    '<Float64 name="p" valueReference="9" causality="output" variability="constant" start="1"/>',
    '<Float64 name="p" valueReference="9" clocks="10" variability="discrete"/>',
    '<Float64 name="p" valueReference="9" causality="parameter" variability="tunable" '
    'start="1" clocks="10"/>',                                                   # clocked tunable
    '<Clock name="p" valueReference="9" causality="input"/>',
    '<Clock name="p" valueReference="9" causality="output"/>',
    '<Clock name="p" valueReference="9"/>',                                      # local
    '<Float64 name="p" valueReference="9" causality="weird" variability="continuous"/>',  # schema's
])
def test_causality_variability_valid(decl):
    assert run("DAE504", ctx_of(variables=VARIABLES + decl)) == []


def test_clocked_continuous_when_every_variable_is_clocked():
    # every variable has a clocks attribute (no variable shares the plain attribute set):
    # the clocked continuous p is still MV-12's fault
    xml = ('<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">'
           '<ModelExchange modelIdentifier="M"/><ModelVariables>'
           '<Float64 name="time" valueReference="0" causality="independent" '
           'variability="continuous" clocks="1"/>'
           '<Clock name="c" valueReference="1" causality="input" '
           'intervalVariability="triggered" clocks="1"/>'
           '<Float64 name="p" valueReference="2" clocks="1"/>'
           '</ModelVariables><ModelStructure/></fmiModelDescription>')
    [v] = run("DAE504", ctx_of(xml))
    assert v.subject == "p"


def test_independent_is_left_to_its_own_rule():
    bad_time = VARIABLES.replace('causality="independent" variability="continuous"',
                                 'causality="independent" variability="discrete"')
    assert run("DAE504", ctx_of(variables=bad_time)) == []
    assert subjects("DAE508", ctx_of(variables=bad_time)) == ["time"]


# --- DAE505 initial-invalid -------------------------------------------------------------------

@pytest.mark.parametrize("decl, ok", [
    ('<Float64 name="p" valueReference="9" causality="parameter" initial="calculated"/>', False),
    ('<Float64 name="p" valueReference="9" causality="parameter" initial="approx" start="1"/>',
     False),
    ('<Float64 name="p" valueReference="9" causality="parameter" initial="exact" start="1"/>',
     True),
    ('<Float64 name="p" valueReference="9" causality="structuralParameter" initial="exact" '
     'start="1"/>', True),
    ('<Float64 name="p" valueReference="9" causality="input" initial="approx" start="1"/>', False),
    ('<Float64 name="p" valueReference="9" causality="input" initial="exact" start="1"/>', True),
    ('<Float64 name="p" valueReference="9" causality="input" variability="discrete" '
     'initial="exact" start="1"/>', True),
    ('<Float64 name="p" valueReference="9" causality="calculatedParameter" initial="exact" '
     'start="1"/>', False),
    ('<Float64 name="p" valueReference="9" causality="calculatedParameter" initial="approx" '
     'start="1"/>', True),
    ('<Float64 name="p" valueReference="9" variability="constant" initial="approx" start="1"/>',
     False),
    ('<Float64 name="p" valueReference="9" variability="tunable" initial="exact" start="1"/>',
     False),
    ('<Float64 name="p" valueReference="9" causality="output" initial="exact" start="1"/>', True),
    ('<Float64 name="p" valueReference="9" initial="bogus"/>', True),  # the schema's to report
])
def test_initial_invalid(decl, ok):
    found = run("DAE505", ctx_of(variables=VARIABLES + decl))
    assert (found == []) == ok
    if not ok:
        assert found[0].subject == "p" and "allowed" in ev(found[0])


@pytest.mark.parametrize("causality, variability, allowed", [
    ("input", "continuous", ("exact",)),
    ("input", "discrete", ("exact",)),
    ("parameter", "fixed", ("exact",)),
    ("structuralParameter", "tunable", ("exact",)),
    ("calculatedParameter", "fixed", ("approx", "calculated")),
    ("local", "tunable", ("approx", "calculated")),
    ("output", "constant", ("exact",)),
])
def test_initial_invalid_names_the_allowed_values(causality, variability, allowed):
    bad = "calculated" if "calculated" not in allowed else "exact"
    decl = (f'<Float64 name="p" valueReference="9" causality="{causality}" '
            f'variability="{variability}" initial="{bad}"/>')
    [v] = run("DAE505", ctx_of(variables=VARIABLES + decl))
    assert ev(v) == {"initial": bad, "causality": causality, "variability": variability,
                     "allowed": allowed}


def test_attribute_rules_quiet_on_values_the_schema_reports():
    # a misspelt causality or variability is the schema stage's; the initial and start rules
    # do not judge the variable by it
    decl = ('<Float64 name="p" valueReference="9" causality="bogus" initial="exact" start="1"/>'
            '<Float64 name="q" valueReference="10" causality="bogus" variability="constant"/>'
            '<Float64 name="r" valueReference="11" variability="bogus" start="1"/>')
    ctx = ctx_of(variables=VARIABLES + decl)
    for code in ("DAE504", "DAE505", "DAE506", "DAE507"):
        assert run(code, ctx) == [], code


def test_initial_quiet_when_pair_is_invalid():
    decl = ('<Float64 name="p" valueReference="9" causality="input" variability="fixed" '
            'initial="calculated"/>')
    ctx = ctx_of(variables=VARIABLES + decl)
    assert subjects("DAE504", ctx) == ["p"]
    for code in ("DAE505", "DAE506", "DAE507"):
        assert run(code, ctx) == [], code


# --- DAE506 start-missing, DAE507 start-not-allowed -------------------------------------------

@pytest.mark.parametrize("decl, reason", [
    ('<Float64 name="p" valueReference="9" causality="parameter"/>', "initial=exact"),
    ('<Float64 name="p" valueReference="9" causality="input"/>', "initial=exact"),
    ('<Float64 name="p" valueReference="9" initial="approx"/>', "initial=approx"),
    ('<Float64 name="p" valueReference="9" variability="constant"/>', "initial=exact"),
    ('<Boolean name="p" valueReference="9" causality="structuralParameter"/>', "initial=exact"),
    ('<String name="p" valueReference="9" causality="parameter"/>', "initial=exact"),
])
def test_start_missing(decl, reason):
    [v] = run("DAE506", ctx_of(variables=VARIABLES + decl))
    assert v.subject == "p" and ev(v)["required_by"] == reason


@pytest.mark.parametrize("decl", [
    '<String name="p" valueReference="9" causality="parameter"><Start value="a"/></String>',
    '<Float64 name="p" valueReference="9" causality="calculatedParameter"/>',
    '<Float64 name="p" valueReference="9" causality="output"/>',
    '<Clock name="p" valueReference="9" causality="input"/>',
])
def test_start_present_or_not_needed(decl):
    assert run("DAE506", ctx_of(variables=VARIABLES + decl)) == []


@pytest.mark.parametrize("decl, fires", [
    ('<Float64 name="p" valueReference="9" start="1"/>', True),                  # local calculated
    ('<Float64 name="p" valueReference="9" causality="output" start="1"/>', True),
    ('<Float64 name="p" valueReference="9" causality="calculatedParameter" start="1"/>', True),
    ('<Float64 name="p" valueReference="9" initial="approx" start="1"/>', False),
    ('<Float64 name="p" valueReference="9" causality="output" initial="exact" start="1"/>', False),
])
def test_start_not_allowed(decl, fires):
    assert subjects("DAE507", ctx_of(variables=VARIABLES + decl)) == (["p"] if fires else [])


def test_start_not_allowed_after_a_missing_start():
    # p1's start problem (missing) comes first in the model; p2's (not allowed) is this rule's
    decl = ('<Float64 name="p1" valueReference="9" causality="parameter"/>'
            '<Float64 name="p2" valueReference="10" start="1"/>')
    assert subjects("DAE507", ctx_of(variables=VARIABLES + decl)) == ["p2"]


# --- DAE508 independent-variable-invalid ------------------------------------------------------

def test_no_independent_variable():
    no_time = VARIABLES.replace('causality="independent" variability="continuous"', "")
    [v] = run("DAE508", ctx_of(variables=no_time))
    assert v.subject is None and ev(v)["independent_variables"] == 0
    assert (v.location.file, v.location.line, v.location.path) == (
        "modelDescription.xml", 1, "/fmiModelDescription/ModelVariables")


def test_two_independent_variables():
    decl = '<Float64 name="t2" valueReference="9" causality="independent"/>'
    assert subjects("DAE508", ctx_of(variables=VARIABLES + decl)) == ["t2"]


@pytest.mark.parametrize("attrs, problem", [
    ('causality="independent" variability="continuous" start="0"', "start"),
    ('causality="independent" variability="continuous" initial="exact"', "initial"),
    ('causality="independent" variability="discrete"', "variability discrete"),
])
def test_independent_attributes(attrs, problem):
    variables = VARIABLES.replace('causality="independent" variability="continuous"', attrs)
    [v] = run("DAE508", ctx_of(variables=variables))
    assert v.subject == "time" and problem in ev(v)["problems"]
    # start and initial on time are not reported again by the start/initial rules
    ctx = ctx_of(variables=variables)
    for code in ("DAE504", "DAE505", "DAE506", "DAE507"):
        assert run(code, ctx) == [], code


def test_independent_not_float():
    variables = VARIABLES.replace('<Float64 name="time" valueReference="0" causality="independent"'
                                  ' variability="continuous"/>',
                                  '<Int64 name="time" valueReference="0" causality="independent"/>')
    [v] = run("DAE508", ctx_of(variables=variables))
    assert "type Int64" in ev(v)["problems"]


# --- DAE509 derivative-invalid ----------------------------------------------------------------

def test_derivative_target_missing():
    ctx = ctx_of(variables=VARIABLES.replace('derivative="2"', 'derivative="99"'))
    [v] = run("DAE509", ctx)
    assert v.subject == "der(x)" and ev(v)["derivative"] == 99


def test_derivative_target_not_float():
    ctx = ctx_of(variables=VARIABLES.replace('derivative="2"', 'derivative="1"'))
    [v] = run("DAE509", ctx)
    assert ev(v)["target_type"] == "Boolean"


def test_csd_without_derivative_attribute():
    ctx = ctx_of(variables=VARIABLES.replace(' derivative="2"', ""))
    [v] = run("DAE509", ctx)
    assert v.subject == "der(x)" and v.location.line is not None


def test_state_listed_twice():
    variables = VARIABLES + '<Float64 name="der2" valueReference="9" derivative="2"/>'
    structure = STRUCTURE.replace(
        '<InitialUnknown valueReference="8"',
        '<ContinuousStateDerivative valueReference="9"/><InitialUnknown valueReference="8"')
    structure += '<InitialUnknown valueReference="9"/>'
    ctx = ctx_of(variables=variables, structure=structure)
    [v] = run("DAE509", ctx)
    assert v.subject == "der2" and ev(v)["earlier_derivative"] == "der(x)"
    assert v.location.path.startswith("/fmiModelDescription/ModelStructure/")


def test_csd_without_derivative_after_an_unresolved_one():
    # the unresolved element is model-structure-unknown-vr's; the loop goes on to the next
    ctx = ctx_of(variables=VARIABLES.replace(' derivative="2"', ""),
                 structure='<ContinuousStateDerivative valueReference="99"/>' + STRUCTURE)
    [v] = run("DAE509", ctx)
    assert (v.subject, v.part) == ("der(x)", "csd-without-derivative")
    assert ev(v) == {"value_reference": 3, "type": "Float64", "structure_line": 14}


def test_two_states_each_listed_once_are_no_repeat():
    # der(x) and der(x2) name two states; loc (no derivative attribute) takes the rule past its
    # fast path, and is the only finding
    variables = VARIABLES + ('<Float64 name="x2" valueReference="9" initial="exact" start="0"/>'
                             '<Float64 name="der(x2)" valueReference="10" derivative="9"/>'
                             '<Float64 name="loc" valueReference="11"/>')
    structure = STRUCTURE + ('<ContinuousStateDerivative valueReference="10"/>'
                             '<ContinuousStateDerivative valueReference="11"/>')
    found = run("DAE509", ctx_of(variables=variables, structure=structure))
    assert [(v.subject, v.part) for v in found] == [("loc", "csd-without-derivative")]


def test_same_derivative_listed_twice():
    structure = STRUCTURE + '<ContinuousStateDerivative valueReference="3"/>'
    assert subjects("DAE509", ctx_of(structure=structure)) == ["der(x)"]


def test_discrete_state():
    ctx = ctx_of(variables=VARIABLES.replace('initial="exact" start="1"',
                                             'variability="discrete" initial="exact" start="1"'))
    assert subjects("DAE509", ctx) == ["der(x)"]
    [v] = run("DAE509", ctx)
    assert ev(v) == {"derivative_variability": "continuous", "state": "x",
                     "state_variability": "discrete"}


def test_derivative_linking_outputs_is_fine():
    variables = VARIABLES + ('<Float64 name="a" valueReference="9" causality="output" '
                             'derivative="8"/>')
    structure = STRUCTURE + ('<Output valueReference="9"/>')
    # Outputs must come first for the schema, but order does not matter to these checks.
    ctx = ctx_of(variables=variables, structure=structure + '<InitialUnknown valueReference="9"/>')
    for code in ("DAE509", "DAE511", "DAE512", "DAE513"):
        assert run(code, ctx) == [], code


def test_output_set_of_a_model_without_outputs():
    # no output at all, and an <Output> naming a local: the list is not the (empty) set
    variables = VARIABLES.replace('name="v" valueReference="8" causality="output"',
                                  'name="v" valueReference="8"')
    [v] = run("DAE511", ctx_of(variables=variables))
    assert v.subject == "v" and v.location.path == "/fmiModelDescription/ModelStructure/Output[1]"
    assert ev(v)["causality"] == "local"


def test_output_set_leaves_out_outputs_without_their_own_value_reference():
    # o2 has no valueReference, o3 shares y's: neither can be listed (the schema and
    # value-reference-duplicate say why), so <Output> is not asked to list them
    decl = ('<Float64 name="o2" causality="output"/>'
            '<Float64 name="o3" valueReference="4" causality="output"/>')
    assert run("DAE511", ctx_of(variables=VARIABLES + decl)) == []


# --- DAE510 model-structure-unknown-vr --------------------------------------------------------

def test_unknown_value_reference_zero():
    # no variable has valueReference 0 here: an element naming 0 is unresolved like any other
    variables = VARIABLES.replace('valueReference="0"', 'valueReference="20"')
    ctx = ctx_of(variables=variables, structure=STRUCTURE + '<InitialUnknown valueReference="0"/>')
    [v] = run("DAE510", ctx)
    assert v.subject == "InitialUnknown valueReference=0"
    assert ev(v) == {"kind": "InitialUnknown", "value_reference": 0}


def test_unknown_vr_in_element_and_dependencies():
    structure = STRUCTURE.replace('<Output valueReference="8" dependencies="2"/>',
                                  '<Output valueReference="8" dependencies="2 98 99 99"/>')
    structure += '<InitialUnknown valueReference="77"/>'
    found = run("DAE510", ctx_of(structure=structure))
    assert sorted(v.subject for v in found) == ["InitialUnknown valueReference=77", "v"]
    dep = next(v for v in found if v.subject == "v")
    assert ev(dep)["missing"] == (98, 99)
    assert dep.location.path == "/fmiModelDescription/ModelStructure/Output[1]"
    # the unresolved entry is not reported again as a set mismatch
    assert run("DAE513", ctx_of(structure=structure)) == []


# --- DAE511 model-structure-output-mismatch ---------------------------------------------------

def test_output_missing():
    structure = STRUCTURE.replace('<Output valueReference="8" dependencies="2"/>', "")
    [v] = run("DAE511", ctx_of(structure=structure))
    assert v.subject == "v" and v.location.path.endswith("[@name='v']")


def test_output_not_an_output_and_duplicate():
    structure = ('<Output valueReference="8"/><Output valueReference="8"/>'
                 '<Output valueReference="4"/>') + STRUCTURE.split("/>", 1)[1]
    found = run("DAE511", ctx_of(structure=structure))
    assert sorted(v.subject for v in found) == ["v", "y"]
    assert {v.location.path for v in found} == {"/fmiModelDescription/ModelStructure/Output[2]",
                                                "/fmiModelDescription/ModelStructure/Output[3]"}


# --- DAE512 model-structure-derivative-missing ------------------------------------------------

def test_state_derivative_not_listed():
    structure = ('<Output valueReference="8" dependencies="2"/>'
                 '<InitialUnknown valueReference="8" dependencies="2"/>')
    ctx = ctx_of(structure=structure)
    [v] = run("DAE512", ctx)
    assert v.subject == "der(x)" and ev(v)["state"] == "x"


@pytest.mark.parametrize("interface", ['<CoSimulation modelIdentifier="M"/>',
                                       '<ScheduledExecution modelIdentifier="M"/>'])
def test_without_model_exchange_state_derivatives_need_not_be_listed(interface):
    # FMI 3.0 §2.4.8: a Co-Simulation FMU may leave out <ContinuousStateDerivative> (issue 8)
    structure = ('<Output valueReference="8" dependencies="2"/>'
                 '<InitialUnknown valueReference="8" dependencies="2"/>')
    assert run("DAE512", ctx_of(structure=structure, me=interface)) == []
    both = ME + interface
    assert subjects("DAE512", ctx_of(structure=structure, me=both)) == ["der(x)"]


def test_second_derivative_of_a_listed_state_is_not_a_missing_derivative():
    variables = VARIABLES + '<Float64 name="dx" valueReference="9" derivative="2"/>'
    assert run("DAE512", ctx_of(variables=variables)) == []


def test_derivative_missing_goes_past_every_derivative_it_leaves_alone():
    # in model order: der(x) is listed, dx2 names a state already covered, d1 names no
    # variable, d2 a discrete state, do1 links two outputs; only dq is a state derivative
    # that Model Exchange must list
    variables = VARIABLES + """
        <Float64 name="dx2" valueReference="9" derivative="2"/>
        <Float64 name="d1" valueReference="10" derivative="99"/>
        <Float64 name="s" valueReference="11" variability="discrete" initial="exact" start="0"/>
        <Float64 name="d2" valueReference="12" derivative="11"/>
        <Float64 name="o1" valueReference="13" causality="output"/>
        <Float64 name="do1" valueReference="14" causality="output" derivative="13"/>
        <Float64 name="q" valueReference="15" initial="exact" start="0"/>
        <Float64 name="dq" valueReference="16" derivative="15"/>
    """
    [v] = run("DAE512", ctx_of(variables=variables))
    assert v.subject == "dq"
    assert ev(v) == {"value_reference": 16, "state": "q", "state_value_reference": 15}


@pytest.mark.parametrize("state, derivative", [("output", "local"), ("local", "output")])
def test_derivative_missing_of_an_output_state_or_an_output_derivative(state, derivative):
    variables = VARIABLES + (
        f'<Float64 name="q" valueReference="9" causality="{state}" initial="exact" start="0"/>'
        f'<Float64 name="dq" valueReference="10" causality="{derivative}" derivative="9"/>')
    assert subjects("DAE512", ctx_of(variables=variables)) == ["dq"]


# --- DAE513 model-structure-initial-unknown-mismatch ------------------------------------------

def test_initial_unknown_missing_derivative_and_output():
    structure = STRUCTURE.replace('<InitialUnknown valueReference="8" dependencies="2"/>', "")
    structure = structure.replace('<InitialUnknown valueReference="3" dependencies="2"/>', "")
    found = run("DAE513", ctx_of(structure=structure))
    assert sorted(v.subject for v in found) == ["der(x)", "v"]
    assert {ev(v)["reason"] for v in found} == {"derivative with initial=calculated",
                                                "output with initial=calculated"}


def test_initial_unknown_missing_calculated_parameter():
    decl = '<Float64 name="cp" valueReference="9" causality="calculatedParameter"/>'
    [v] = run("DAE513", ctx_of(variables=VARIABLES + decl))
    assert v.subject == "cp" and v.location.line == 12
    assert ev(v) == {"kind": "InitialUnknown", "value_reference": 9,
                     "reason": "calculatedParameter"}


def test_initial_unknown_missing_approx_output():
    variables = VARIABLES.replace('name="v" valueReference="8" causality="output"',
                                  'name="v" valueReference="8" causality="output" '
                                  'initial="approx" start="0"')
    structure = STRUCTURE.replace('<InitialUnknown valueReference="8" dependencies="2"/>', "")
    [v] = run("DAE513", ctx_of(variables=variables, structure=structure))
    assert v.subject == "v" and ev(v)["reason"] == "output with initial=approx"


def test_initial_unknown_may_list_a_clock():
    # MS-05 (d): clocked variables, and the Clocks themselves, may be added
    variables = VARIABLES + ('<Clock name="c" valueReference="9" causality="input" '
                             'intervalVariability="triggered"/>')
    structure = STRUCTURE + '<InitialUnknown valueReference="9"/>'
    assert run("DAE513", ctx_of(variables=variables, structure=structure)) == []


def test_initial_unknown_extra_exact_state():
    structure = STRUCTURE + '<InitialUnknown valueReference="2"/>'
    [v] = run("DAE513", ctx_of(structure=structure))
    assert v.subject == "x"
    assert v.location.path == "/fmiModelDescription/ModelStructure/InitialUnknown[3]"


def test_initial_unknown_state_with_approx_and_calculated_parameter_required():
    variables = (VARIABLES.replace('initial="exact" start="1"', 'initial="approx" start="1"')
                 + '<Float64 name="cp" valueReference="9" causality="calculatedParameter"/>')
    found = run("DAE513", ctx_of(variables=variables))
    assert sorted(v.subject for v in found) == ["cp", "x"]


def test_initial_unknown_algebraic_local_not_allowed_in_model_description():
    structure = STRUCTURE + '<InitialUnknown valueReference="4"/>'
    assert subjects("DAE513", ctx_of(structure=structure)) == ["y"]


def test_initial_unknown_clocked_variable_allowed_and_duplicate_reported():
    variables = VARIABLES + ('<Clock name="c" valueReference="9" causality="input"/>'
                             '<Float64 name="q" valueReference="10" variability="discrete" '
                             'clocks="9"/>')
    structure = STRUCTURE + ('<InitialUnknown valueReference="10"/>'
                             '<InitialUnknown valueReference="3"/>')
    [v] = run("DAE513", ctx_of(variables=variables, structure=structure))
    assert v.subject == "der(x)" and v.location.path.endswith("InitialUnknown[4]")


# --- DAE514 directional-derivatives-missing ---------------------------------------------------

def test_directional_derivatives_missing_only_with_manifest():
    me = '<ModelExchange modelIdentifier="M" providesAdjointDerivatives="true"/>'
    [v] = run("DAE514", ctx_of(me=me, manifest=MANIFEST))
    assert v.subject == "M" and v.location.path == "/fmiModelDescription/ModelExchange"
    assert run("DAE514", ctx_of(me=me)) == []
    assert run("DAE514", ctx_of(me=ME, manifest=MANIFEST)) == []


def test_directional_derivatives_missing_when_an_enable_parameter_declares_the_layer():
    variables = VARIABLES.replace('name="dae"', 'name="enableDAEModeParameter"')
    me = '<ModelExchange modelIdentifier="M"/>'
    [v] = run("DAE514", ctx_of(me=me, variables=variables))
    assert v.subject == "M"


# --- grouping and speed -----------------------------------------------------------------------

def test_many_equal_faults_share_one_message():
    extra = "".join(f'<Float64 name="p{i}" valueReference="{100 + i}" causality="parameter"/>'
                    for i in range(200))
    found = run("DAE506", ctx_of(variables=VARIABLES + extra))
    assert len(found) == 200 and len({v.message for v in found}) == 1


def big_model_xml(n_blocks: int) -> str:
    parts = [VARIABLES.replace('<Float64 name="v" valueReference="8" causality="output"/>', "")]
    structure = ['<ContinuousStateDerivative valueReference="3"/>']
    initial = ['<InitialUnknown valueReference="3"/>']
    for k in range(n_blocks):
        base = 100 + 4 * k
        parts.append(
            f'<Float64 name="x{k}" valueReference="{base}" initial="exact" start="1"/>'
            f'<Float64 name="der(x{k})" valueReference="{base + 1}" derivative="{base}"/>'
            f'<Float64 name="w{k}" valueReference="{base + 2}" initial="approx" start="0"/>'
            f'<Float64 name="o{k}" valueReference="{base + 3}" causality="output"/>')
        structure.append(f'<ContinuousStateDerivative valueReference="{base + 1}" '
                         f'dependencies="{base} {base + 2}"/>')
        initial.append(f'<InitialUnknown valueReference="{base + 1}"/>'
                       f'<InitialUnknown valueReference="{base + 3}" dependencies="{base}"/>')
    outputs = [f'<Output valueReference="{100 + 4 * k + 3}" dependencies="{100 + 4 * k}"/>'
               for k in range(n_blocks)]
    return md_xml(variables="".join(parts), structure="".join(outputs + structure + initial))


def test_big_model_is_clean():
    # speed is measured by `make bench` (reports/bench/static.md), never by a timed test
    ctx = ctx_of(big_model_xml(2000), manifest=MANIFEST)
    for code in CHECKS:
        assert run(code, ctx) == [], code


# --- parts: the sub-checks whose basis differs carry their catalogue part -----------------------

def parts(code: str, ctx: CheckContext) -> list:
    return [v.part for v in run(code, ctx)]


def test_alias_name_part():
    alias = '<Float64 name="w" valueReference="9"><Alias name="y"/><Alias name="y2"/></Float64>'
    assert parts("DAE503", ctx_of(variables=VARIABLES + alias)) == ["alias-name"]
    after = ('<Float64 name="w" valueReference="9"><Alias name="a1"/></Float64>'
             '<Float64 name="a1" valueReference="10"/>')
    assert parts("DAE503", ctx_of(variables=VARIABLES + after)) == ["alias-name"]
    assert parts("DAE503", ctx_of(variables=VARIABLES + '<Float64 name="y" valueReference="9"/>')
                 ) == [None]


@pytest.mark.parametrize("decl, part", [
    ('<Float64 name="p" valueReference="9" causality="input" variability="fixed" start="1"/>',
     None),
    ('<Int32 name="p" valueReference="9" variability="continuous"/>', "continuous-non-float"),
    ('<Clock name="p" valueReference="9" causality="parameter"/>', "clock-causality"),
    ('<Clock name="p" valueReference="9" causality="input" variability="tunable"/>',
     "clock-variability"),
    ('<Float64 name="p" valueReference="9" clocks="10"/>', "clocked"),
])
def test_causality_variability_parts(decl, part):
    assert parts("DAE504", ctx_of(variables=VARIABLES + decl)) == [part]


@pytest.mark.parametrize("attrs, part", [
    ('causality="independent" variability="continuous" start="0"', "type-or-start"),
    ('causality="independent" variability="discrete" start="0" initial="exact"', "type-or-start"),
    ('causality="independent" variability="continuous" initial="exact"', "initial"),
    ('causality="independent" variability="discrete" initial="exact"', "initial"),
    ('causality="independent" variability="discrete"', "variability"),
])
def test_independent_attribute_parts(attrs, part):
    variables = VARIABLES.replace('causality="independent" variability="continuous"', attrs)
    assert parts("DAE508", ctx_of(variables=variables)) == [part]
    no_time = VARIABLES.replace('causality="independent" variability="continuous"', "")
    assert parts("DAE508", ctx_of(variables=no_time)) == [None]


def test_derivative_parts():
    assert parts("DAE509", ctx_of(variables=VARIABLES.replace('derivative="2"', 'derivative="99"'))
                 ) == [None]
    assert parts("DAE509", ctx_of(variables=VARIABLES.replace('derivative="2"', 'derivative="1"'))
                 ) == ["target-not-float"]
    link = ('<Int32 name="n" valueReference="9" causality="input" start="0"/>'
            '<Float64 name="dn" valueReference="10" causality="output" derivative="9"/>')
    assert parts("DAE509", ctx_of(variables=VARIABLES + link)) == ["target-not-float-io-link"]
    # listed as a state derivative: the target is a state even when both are inputs/outputs
    listed = STRUCTURE + '<ContinuousStateDerivative valueReference="10"/>'
    assert parts("DAE509", ctx_of(variables=VARIABLES + link, structure=listed))[0] == \
        "target-not-float"
    link_in = ('<Int32 name="n" valueReference="9" causality="output"/>'
               '<Float64 name="dn" valueReference="10" causality="input" start="0" '
               'derivative="9"/>')
    assert parts("DAE509", ctx_of(variables=VARIABLES + link_in)) == ["target-not-float-io-link"]
    local = ('<Int32 name="n" valueReference="9" causality="input" start="0"/>'
             '<Float64 name="dn" valueReference="10" derivative="9"/>')
    assert parts("DAE509", ctx_of(variables=VARIABLES + local)) == ["target-not-float"]
    assert parts("DAE509", ctx_of(variables=VARIABLES.replace(' derivative="2"', ""))) == [
        "csd-without-derivative"]
    discrete = VARIABLES.replace('initial="exact" start="1"',
                                 'variability="discrete" initial="exact" start="1"')
    assert parts("DAE509", ctx_of(variables=discrete)) == ["not-continuous"]
    twice = STRUCTURE + '<ContinuousStateDerivative valueReference="3"/>'
    assert parts("DAE509", ctx_of(structure=twice)) == ["state-listed-twice"]


def test_output_duplicate_part():
    structure = ('<Output valueReference="8"/><Output valueReference="8"/>'
                 '<Output valueReference="4"/>') + STRUCTURE.split("/>", 1)[1]
    found = {v.subject: v.part for v in run("DAE511", ctx_of(structure=structure))}
    assert found == {"v": "duplicate", "y": None}


def test_initial_unknown_parts():
    variables = VARIABLES + '<Float64 name="e" valueReference="9"/>'
    structure = STRUCTURE + ('<EventIndicator valueReference="9"/>'
                             '<InitialUnknown valueReference="9"/>'
                             '<InitialUnknown valueReference="4"/>'
                             '<InitialUnknown valueReference="3"/>')
    found = [(v.subject, v.part) for v in run("DAE513", ctx_of(variables=variables,
                                                                  structure=structure))]
    assert found == [("e", "event-indicator-listed"), ("y", None), ("der(x)", "duplicate")]


def test_nominal_not_positive_part():
    from conformance.checks import attribute_values
    variables = (VARIABLES.replace('initial="exact" start="1"',
                                   'initial="exact" start="1" nominal="0"')
                 .replace('name="g1" valueReference="6"', 'name="g1" valueReference="6" '
                          'nominal="-1"'))
    found = {v.subject: v.part
             for v in attribute_values.nominal_not_positive(ctx_of(variables=variables))}
    assert found == {"x": None, "g1": "not-a-state"}


# --- DAE515 output-state-self-dependency ------------------------------------------------------

def test_output_state_self_dependency():
    variables = VARIABLES.replace('name="v" valueReference="8" causality="output"',
                                  'name="v" valueReference="8"')
    variables += '<Float64 name="xo" valueReference="9" causality="output" start="1"/>' \
                 '<Float64 name="der(xo)" valueReference="10" derivative="9"/>'
    structure = ('<Output valueReference="9" dependencies="2"/>'
                 '<ContinuousStateDerivative valueReference="3" dependencies="2"/>'
                 '<ContinuousStateDerivative valueReference="10" dependencies="9"/>')
    [v] = run("DAE515", ctx_of(variables=variables, structure=structure))
    assert v.subject == "xo" and v.location.path == "/fmiModelDescription/ModelStructure/Output[1]"
    assert ev(v)["value_reference"] == 9 and ev(v)["dependencies"] == (2,)
    structure = structure.replace('dependencies="2"/><Cont', 'dependencies="2 9"/><Cont', 1)
    assert run("DAE515", ctx_of(variables=variables, structure=structure)) == []


def test_output_state_self_dependency_of_an_unknown_state_names_its_reference():
    # der(x) names a state (9) that no variable has, and an <Output> lists 9: the finding names
    # the value reference (model-structure-unknown-vr and derivative-invalid say the rest)
    ctx = ctx_of(variables=VARIABLES.replace('derivative="2"', 'derivative="9"'),
                 structure=STRUCTURE + '<Output valueReference="9" dependencies="2"/>')
    [v] = run("DAE515", ctx)
    assert v.subject == "9" and v.location.line == 17
    assert v.location.path == "/fmiModelDescription/ModelStructure/Output[2]"
    assert ev(v)["value_reference"] == 9 and ev(v)["dependencies"] == (2,)
