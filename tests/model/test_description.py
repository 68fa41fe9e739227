"""conformance/model/description.py, parts.py, definitions.py and layer.describe_fmu: what
read_model_description makes of each attribute and child, field by field."""
from __future__ import annotations

from lxml import etree

from conformance.model.definitions import TypeDefinition, UnitDefinition, read_definitions
from conformance.model.description import read_model_description
from conformance.model.layer import describe_fmu, manifest_missing
from conformance.model.parts import (
    NO_DETAILS, DefaultExperiment, Dimension, VariableDetails, default_initial,
    default_variability,
)


def read(body: str, interfaces: str = '<ModelExchange modelIdentifier="M"/>'):
    text = ('<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">\n'
            f"{interfaces}\n{body}\n</fmiModelDescription>")
    return read_model_description(etree.ElementTree(etree.fromstring(text)))


def variables(xml: str):
    return read(f"<ModelVariables>\n{xml}\n</ModelVariables>").variables


def test_rare_attributes_are_read_into_the_details():
    (v,) = variables(
        '<Float64 name="x" valueReference="1" nominal="2" min="-1" max="5" reinit="true" '
        'clocks="7 8" previous="3" declaredType="T" unit="m" displayUnit="mm"/>')
    assert v.details == VariableDetails(
        dimensions=(), nominal="2", minimum="-1", maximum="5", reinit=True, clocks="7 8",
        previous=3, raw_vr=None, aliases=(), declared_type="T", unit="m", display_unit="mm",
        alias_display_units=())
    assert v.dimensions == ()     # a tuple, also when only attributes brought the details
    assert (v.maximum, v.reinit, v.clocks, v.previous) == ("5", True, "7 8", 3)


def test_reinit_is_true_only_for_true_or_1():
    got = variables('<Float64 name="a" valueReference="1" reinit="1"/>'
                    '<Float64 name="b" valueReference="2" reinit="false"/>'
                    '<Float64 name="c" valueReference="3" unit="m"/>')
    assert [v.reinit for v in got] == [True, False, False]
    assert all(type(v.reinit) is bool for v in got)


def test_a_value_reference_that_is_no_integer_is_kept_as_text():
    (v,) = variables('<Float64 name="x" valueReference="x1" declaredType="T"/>')
    assert v.vr is None
    assert v.details == VariableDetails(raw_vr="x1", declared_type="T")
    assert (v.raw_vr, v.declared_type, v.aliases) == ("x1", "T", ())


def test_start_dimension_and_alias_children():
    (v,) = variables(
        '<Float64 name="x" valueReference="1">\n'
        '  <Dimension start="3"/>\n'
        '  <Dimension valueReference="5"/>\n'
        '  <Dimension valueReference="n"/>\n'
        '  <!-- a comment -->\n'
        '  <Start value="1"/><Start value="2"/>\n'
        '  <Alias name="y" displayUnit="mm"/><Alias name="z"/>\n'
        '</Float64>')
    assert v.start == "1 2"
    assert v.dimensions == (Dimension("3", None, 5, None), Dimension(None, 5, 6, None),
                            Dimension(None, None, 7, "n"))
    assert v.aliases == ("y", "z")
    assert v.alias_display_units == (("y", "mm"),)


def test_the_start_attribute_wins_over_start_children():
    (v,) = variables('<Float64 name="x" valueReference="1" start="9"><Start value="1"/></Float64>')
    assert v.start == "9"


def test_a_start_child_without_value_reads_as_empty():
    got = variables('<String name="s" valueReference="1"><Start/></String>'
                    '<String name="t" valueReference="2"><Start value="a"/><Start/></String>')
    assert [v.start for v in got] == ["", "a "]


def test_a_plain_variable_shares_no_details():
    (v,) = variables('<Float64 name="x" valueReference="1" causality="output"/>')
    assert v.details is NO_DETAILS
    assert (v.causality, v.variability, v.initial, v.line) == ("output", "continuous",
                                                             "calculated", 4)


def test_default_experiment_fields():
    model = read('<DefaultExperiment startTime="0.5" stopTime="2" tolerance="1e-6" '
                 'stepSize="0.01"/><ModelVariables/>')
    assert model.default_experiment == DefaultExperiment(0.5, 2.0, 1e-6, 0.01)
    partial = read('<DefaultExperiment stopTime="x" tolerance="1e-4"/><ModelVariables/>')
    assert partial.default_experiment == DefaultExperiment(None, None, 1e-4, None)
    assert read("<ModelVariables/>").default_experiment is None


def test_state_vrs_follow_the_derivatives_in_structure_order():
    model = read(
        '<ModelVariables>'
        '<Float64 name="x" valueReference="1"/><Float64 name="y" valueReference="2"/>'
        '<Float64 name="der(y)" valueReference="12" derivative="2"/>'
        '<Float64 name="der(x)" valueReference="11" derivative="1"/>'
        '<Float64 name="z" valueReference="20"/>'
        '</ModelVariables><ModelStructure>'
        '<ContinuousStateDerivative valueReference="12"/>'
        '<ContinuousStateDerivative valueReference="11"/>'
        '<ContinuousStateDerivative valueReference="20"/>'   # no derivative attribute
        '<ContinuousStateDerivative valueReference="99"/>'   # no such variable
        '<ContinuousStateDerivative/>'                       # no valueReference
        '<Output valueReference="1"/>'
        '</ModelStructure>')
    assert model.state_vrs() == (2, 1)


def test_definitions_are_read_with_units_and_lines():
    root = etree.fromstring(
        '<fmiModelDescription>\n'
        '<UnitDefinitions>\n'
        '  <Unit name="m">\n'
        '    <BaseUnit m="1"/><DisplayUnit name="mm" factor="1000"/><!-- c -->\n'
        '    <DisplayUnit name="km" factor="0.001"/>\n'
        '  </Unit>\n'
        '  <Unit name="s"/>\n'
        '</UnitDefinitions>\n'
        '<TypeDefinitions>\n'
        '  <!-- a comment -->\n'
        '  <Float64Type name="Length" unit="m" displayUnit="mm"/>\n'
        '  <EnumerationType name="E"><Item name="a" value="1"/></EnumerationType>\n'
        '  <Annotations/>\n'
        '</TypeDefinitions>\n'
        '</fmiModelDescription>')
    got = read_definitions(root)
    assert got.types == (TypeDefinition("Length", "Float64", "m", "mm", 11),
                         TypeDefinition("E", "Enumeration", None, None, 12))
    assert got.units == (UnitDefinition("m", ("mm", "km"), 3), UnitDefinition("s", (), 7))
    assert got.types[0].path == "/fmiModelDescription/TypeDefinitions/Float64Type[@name='Length']"
    assert got.units[1].path == "/fmiModelDescription/UnitDefinitions/Unit[@name='s']"


def test_describe_fmu_names_the_interface_types():
    assert describe_fmu(None) == "an FMU"
    assert describe_fmu(read("<ModelVariables/>")) == "a Model Exchange FMU"
    assert describe_fmu(read("<ModelVariables/>", '<ModelExchange modelIdentifier="M"/>'
                             '<CoSimulation modelIdentifier="M"/>')) \
        == "a Model Exchange and Co-Simulation FMU"
    assert describe_fmu(read("<ModelVariables/>", '<ModelExchange modelIdentifier="M"/>'
                             '<CoSimulation modelIdentifier="M"/>'
                             '<ScheduledExecution modelIdentifier="M"/>')) \
        == "a Model Exchange, Co-Simulation and Scheduled Execution FMU"
    assert describe_fmu(read("<ModelVariables/>", "")) == "an FMU"


def test_manifest_missing_message_names_the_interface_types():
    cs = read("<ModelVariables/>", '<CoSimulation modelIdentifier="M"/>')
    assert manifest_missing(cs, []).message == (
        "no fmi-ls-dae manifest (extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml): a "
        "Co-Simulation FMU that does not use the DAE layer; the DAE rules are skipped")


def test_fmi_defaults_of_variability_and_initial():
    assert default_variability("Clock", "input") == "discrete"
    assert default_variability("Float64", "parameter") == "fixed"
    assert default_variability("Boolean", "structuralParameter") == "fixed"
    assert default_variability("Int32", "calculatedParameter") == "fixed"
    assert default_variability("Float32", "local") == "continuous"
    assert default_variability("Int32", "local") == "discrete"
    assert default_initial("independent", "continuous") is None
    assert default_initial("output", "constant") == "exact"
    assert default_initial("input", "constant") is None
    assert default_initial("structuralParameter", "tunable") == "exact"
    assert default_initial("calculatedParameter", "fixed") == "calculated"
    assert default_initial("input", "fixed") is None
    assert default_initial("input", "continuous") == "exact"
    assert default_initial("local", "discrete") == "calculated"
    assert default_initial("parameter", "continuous") is None
