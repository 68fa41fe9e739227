"""conformance/model/manifest.py: read_manifest normalises every draft shape into one Manifest,
field by field (enable references, algebraic variables, the structure, paths and lines)."""
from __future__ import annotations

from lxml import etree

from conformance.model.drafts.detect import LS_NAMESPACE
from conformance.model.manifest import MANIFEST, VrRef, _refs, read_manifest
from conformance.model.unknowns import Unknown

ALPHA1 = f"""<fmiDAEManifest xmlns:fmi-ls="{LS_NAMESPACE}"
    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
    fmi-ls:fmi-ls-description="d" fmi-ls-name="unqualified">
  <EnableDAEParameter valueReference="9"/>
  <AlgebraicVariables>
    <AlgebraicVariable valueReference="3"/>
    <!-- a comment -->
    <AlgebraicVariable valueReference="x"/>
  </AlgebraicVariables>
  <ModelStructure>
    <ContinuousStateDerivative valueReference="11"/>
    <Residual valueReference="20" dependencies="1 3"/>
  </ModelStructure>
</fmiDAEManifest>"""


def test_alpha1_manifest_field_by_field():
    m = read_manifest(etree.ElementTree(etree.fromstring(ALPHA1)), draft="alpha1")
    # libxml2 gives a start tag written over several lines the line where it ends
    assert (m.file, m.root_name, m.root_namespace, m.root_line) == (MANIFEST, "fmiDAEManifest",
                                                                    None, 3)
    assert (m.ls_name, m.ls_version, m.ls_description) == (
        "org.fmi-standard.fmi-ls-dae", "1.0.0-alpha.1", "d")
    assert m.unqualified_ls_attributes == ("fmi-ls-name",)
    assert m.enables == (VrRef(9, 4, "/fmiDAEManifest/EnableDAEParameter", "EnableDAEParameter"),)
    assert m.enable.path == "/fmiDAEManifest/EnableDAEParameter"
    assert m.algebraic == (
        VrRef(3, 6, "/fmiDAEManifest/AlgebraicVariables/{}[{}]", "AlgebraicVariable", ordinal=1),
        VrRef(None, 8, "/fmiDAEManifest/AlgebraicVariables/{}[{}]", "AlgebraicVariable", "x",
              ordinal=2))
    assert [a.path for a in m.algebraic] == ["/fmiDAEManifest/AlgebraicVariables/AlgebraicVariable[1]",
                                             "/fmiDAEManifest/AlgebraicVariables/AlgebraicVariable[2]"]
    assert m.algebraic_line == 5
    assert m.has_model_structure is True
    assert [(u.kind, u.vr, u.dependencies, u.line, u.path) for u in m.structure] == [
        ("ContinuousStateDerivative", 11, None, 11,
         "/fmiDAEManifest/ModelStructure/ContinuousStateDerivative[1]"),
        ("Residual", 20, (1, 3), 12, "/fmiDAEManifest/ModelStructure/Residual[1]"),
    ]
    assert [u.vr for u in m.residuals] == [20]
    assert (m.is_dae_fmu, m.draft) == (None, "alpha1")


FORMULATION = f"""<fmi-ls:fmiLayeredStandardManifest xmlns:fmi-ls="{LS_NAMESPACE}"
    enableDAEModeVariable="useDAE" isDaeFmu="true">
  <fmi-ls:EnableDAE valueReference="4" extra="e"/>
  <fmi-ls:ModelStructure>
    <fmi-ls:Residual>
      <fmi-ls:Formulation index="1" valueReference="30" dependencies="1"/>
      <fmi-ls:Formulation index="2" valueReference="31"/>
    </fmi-ls:Residual>
    <fmi-ls:Residual valueReference="32"/>
  </fmi-ls:ModelStructure>
</fmi-ls:fmiLayeredStandardManifest>"""


def test_legacy_manifest_with_formulations():
    m = read_manifest(etree.ElementTree(etree.fromstring(FORMULATION)), draft="formulation",
                      file="f.xml")
    assert (m.file, m.root_name, m.root_namespace) == ("f.xml", "fmiLayeredStandardManifest",
                                                       LS_NAMESPACE)
    assert (m.ls_name, m.unqualified_ls_attributes, m.algebraic, m.algebraic_line) == (
        None, (), (), None)
    assert m.enables == (
        VrRef(4, 3, "/fmiLayeredStandardManifest/EnableDAE", "EnableDAE",
              extra=(("extra", "e"),)),
        VrRef(None, 2, "/fmiLayeredStandardManifest/@enableDAEModeVariable",
              "@enableDAEModeVariable", name="useDAE"),   # the root's line
    )
    where = "/fmiLayeredStandardManifest/ModelStructure/{}[{}]"
    assert m.structure == (
        Unknown("Residual", 30, (1,), None, 6, "f.xml", where + "/Formulation[1]", (), "1", 2, 1),
        Unknown("Residual", 32, None, None, 9, "f.xml", where, (), None, 0, 2),
    )
    assert [u.path for u in m.structure] == [
        "/fmiLayeredStandardManifest/ModelStructure/Residual[1]/Formulation[1]",
        "/fmiLayeredStandardManifest/ModelStructure/Residual[2]"]
    assert (m.has_model_structure, m.is_dae_fmu, m.draft) == (True, "true", "formulation")


def test_enable_variable_attribute_given_by_value_reference():
    m = read_manifest(etree.ElementTree(etree.fromstring(
        '<fmiLayeredStandardManifest enableDAEModeVariable=" 7 "/>')), draft="formulation")
    assert m.enables == (VrRef(7, 1, "/fmiLayeredStandardManifest/@enableDAEModeVariable",
                               "@enableDAEModeVariable"),)
    assert (m.has_model_structure, m.structure) == (False, ())


def test_a_single_attribute_other_than_value_reference_is_no_value_reference():
    container = etree.fromstring('<AlgebraicVariables><AlgebraicVariable name="5"/>'
                                 '<AlgebraicVariable valueReference="6"/></AlgebraicVariables>')
    assert _refs(container, "/r/{}[{}]") == [
        VrRef(None, 1, "/r/{}[{}]", "AlgebraicVariable", None, None, (("name", "5"),), 1),
        VrRef(6, 1, "/r/{}[{}]", "AlgebraicVariable", None, None, (), 2),
    ]
