"""conformance/model/layer.py: what declares the fmi-ls-dae layer, and why layer rules are
skipped."""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.model.layer import (
    NOT_A_DAE_FMU,
    interface_types,
    layer_declaration,
    skip_reason,
)
from conformance.model.manifest import MANIFEST
from conformance.model.description import read_model_description


def model(interfaces: str = '<ModelExchange modelIdentifier="M"/>', variables: str = ""):
    text = (f'<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">'
            f"{interfaces}<ModelVariables>"
            '<Float64 name="time" valueReference="0" causality="independent"/>'
            f"{variables}</ModelVariables><ModelStructure/></fmiModelDescription>")
    return read_model_description(etree.ElementTree(etree.fromstring(text)))


SWITCH = ('<Boolean name="{}" valueReference="1" causality="structuralParameter" '
          'variability="fixed" start="false"/>')


def test_a_plain_fmu_does_not_declare_the_layer():
    assert layer_declaration(model(), ["modelDescription.xml", "binaries/x86_64-linux/M.so"]) \
        is None


@pytest.mark.parametrize("names", [
    [MANIFEST],                                                       # any draft shape
    ["extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.XML"],        # a file of the folder
])
def test_a_file_in_the_layer_folder_declares_it(names):
    assert layer_declaration(model(), names) == names[0]
    assert layer_declaration(None, names) == names[0]   # even without a modelDescription


@pytest.mark.parametrize("name", ["enableDAEModeParameter", "enableDAEModeVariable",
                                  "ODE_DAE_Switch"])
def test_a_variable_named_like_the_enable_parameter_declares_it(name):
    assert layer_declaration(model(variables=SWITCH.format(name)), []) == f"variable '{name}'"


@pytest.mark.parametrize("name", ["useOffset", "dae", "enable"])
def test_another_boolean_structural_parameter_does_not(name):
    # FMI 3.0 allows a Boolean structural parameter in any FMU (MV-42).
    assert layer_declaration(model(variables=SWITCH.format(name)), []) is None


def test_other_layered_standards_do_not_declare_it():
    assert layer_declaration(model(), ["extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml",
                                       "extra/org.fmi-standard.fmi-ls-dae"]) is None


def test_interface_types_in_the_standard_order():
    both = model('<CoSimulation modelIdentifier="M"/><ScheduledExecution modelIdentifier="M"/>'
                 '<ModelExchange modelIdentifier="M"/>')
    assert interface_types(both) == ("Model Exchange", "Co-Simulation", "Scheduled Execution")
    assert interface_types(None) == ()


HAVE_NOTHING = {"model-description": True, "manifest": False, "dae-layer": False, "binary": True}


@pytest.mark.parametrize("needs, have, reason", [
    (("model-description",), HAVE_NOTHING, None),                      # a core rule runs
    (("model-description", "manifest"), HAVE_NOTHING, NOT_A_DAE_FMU),
    (("model-description", "dae-layer"), HAVE_NOTHING, NOT_A_DAE_FMU),
    (("model-description", "manifest", "binary"), HAVE_NOTHING, NOT_A_DAE_FMU),
    (("model-description", "manifest"), {**HAVE_NOTHING, "dae-layer": True}, "no manifest"),
    (("model-description", "dae-layer"), {**HAVE_NOTHING, "dae-layer": True}, None),
    (("model-description", "manifest"), {**HAVE_NOTHING, "model-description": False},
     "no model-description"),
])
def test_skip_reason(needs, have, reason):
    assert skip_reason(needs, have) == reason


def test_manifest_missing_is_a_part_when_files_of_the_layer_folder_show_the_layer():
    """[[rule.parts]] layer-folder-without-manifest: alpha.1 requires the manifest once the
    layer's folder is there; a plain FMU, or a variable named like the switch, stays the rule's
    own (info) case."""
    from conformance.model.layer import manifest_missing

    folder = ["extra/org.fmi-standard.fmi-ls-dae/notes.txt"]
    assert manifest_missing(model(), folder).part == "layer-folder-without-manifest"
    assert manifest_missing(model(), []).part is None
    switch = model(variables=SWITCH.format("enableDAEModeParameter"))
    assert manifest_missing(switch, []).part is None
