"""The readers share what repeats (issue 11: peak memory at 500k variables), and the shared
representation reads and pickles like the plain one."""
from __future__ import annotations

import pickle

from lxml import etree

from bench.generate import manifest_xml, model_description_xml
from conformance.run import heap
from conformance.model.manifest import read_manifest
from conformance.model.description import NO_DETAILS, read_model_description
from conformance.model.unknowns import Unknown, path_template


def _read(m: int = 4):
    model = read_model_description(etree.ElementTree(etree.fromstring(
        model_description_xml(m).encode())))
    manifest = read_manifest(etree.ElementTree(etree.fromstring(manifest_xml(m).encode())),
                             draft="alpha1")
    return model, manifest


def test_variables_of_one_class_share_their_attribute_strings():
    model, _ = _read()
    states = [v for v in model.variables if v.declared_initial == "exact"
              and v.causality == "local"]
    assert len(states) == 4
    first = states[0]
    for var in states[1:]:
        for field in ("type", "causality", "variability", "initial", "declared_variability",
                      "declared_initial"):
            assert getattr(var, field) is getattr(first, field), field


def test_structure_elements_share_kind_and_dependencies_kind():
    _, manifest = _read()
    residuals = manifest.residuals
    assert len(residuals) == 4
    kinds = {id(r.kind) for r in residuals}
    assert len(kinds) == 1
    shapes: dict[tuple[str, ...], int] = {}
    for r in residuals:
        assert r.dependencies_kind is not None
        assert shapes.setdefault(r.dependencies_kind, id(r.dependencies_kind)) == id(
            r.dependencies_kind)
    tokens = {id(t) for r in residuals for t in r.dependencies_kind or ()
              if t == "constant"}
    assert len(tokens) == 1


def test_paths_are_built_from_kind_and_position():
    model, manifest = _read()
    outputs = list(model.unknowns("Output"))
    assert outputs[1].path == "/fmiModelDescription/ModelStructure/Output[2]"
    assert manifest.residuals[2].path == "/fmiDAEManifest/ModelStructure/Residual[3]"
    assert manifest.algebraic[1].path == "/fmiDAEManifest/AlgebraicVariables/AlgebraicVariable[2]"
    assert manifest.algebraic[0].element is manifest.algebraic[3].element
    assert manifest.enable is not None
    assert manifest.enable.path == "/fmiDAEManifest/EnableDAEParameter"
    derivatives = list(model.unknowns("ContinuousStateDerivative"))
    assert derivatives[0].path == "/fmiModelDescription/ModelStructure/ContinuousStateDerivative[1]"


def test_legacy_formulation_path_and_hand_built_path():
    xml = ('<fmiLayeredStandardManifest xmlns="http://fmi-standard.org/fmi-ls-manifest">'
           '<ModelStructure><Output valueReference="3"/>'
           '<Residual><Formulation index="1" valueReference="7" dependencies="2"/>'
           '<Formulation index="2" valueReference="8"/></Residual></ModelStructure>'
           '</fmiLayeredStandardManifest>')
    manifest = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="legacy")
    (residual,) = manifest.residuals
    assert residual.path == ("/fmiLayeredStandardManifest/ModelStructure/Residual[1]"
                             "/Formulation[1]")
    assert residual.formulations == 2
    assert Unknown("Residual", 1, None, None, None, "m", "/x/Residual[9]").path == (
        "/x/Residual[9]")


def test_a_root_name_with_braces_stays_literal():
    xml = '<a><ModelStructure><Residual valueReference="3"/></ModelStructure></a>'
    manifest = read_manifest(etree.ElementTree(etree.fromstring(xml)), draft="alpha1")
    assert manifest.residuals[0].path == "/a/ModelStructure/Residual[1]"
    assert path_template("/{0}").format("Output", 2) == "/{0}/Output[2]"


def test_model_and_manifest_pickle_with_their_paths():
    model, manifest = _read()
    model2, manifest2 = pickle.loads(pickle.dumps((model, manifest)))
    assert model2.variables == model.variables
    assert model2.structure == model.structure
    assert [u.path for u in manifest2.structure] == [u.path for u in manifest.structure]
    assert manifest2.structure == manifest.structure
    assert manifest2 == manifest
    assert [r.path for r in manifest2.algebraic] == [r.path for r in manifest.algebraic]


def _variables(xml: str):
    md = (f'<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">'
          f'<ModelVariables>{xml}</ModelVariables></fmiModelDescription>')
    return read_model_description(etree.ElementTree(etree.fromstring(md))).variables


def test_details_are_shared_and_read_through_the_variable():
    plain, typed, typed2, odd, alias = _variables(
        '<Float64 name="a" valueReference="1" causality="output" description="d" start="1"'
        ' derivative="3" initial="exact" variability="continuous"/>'
        '<Float64 name="b" valueReference="2" unit="m" declaredType="L" min="0" nominal="2"/>'
        '<Float64 name="c" valueReference="3" unit="m" declaredType="L" min="0" nominal="2"/>'
        '<Int32 name="d" valueReference="x4" previous="2" reinit="true" clocks="5"/>'
        '<Float64 name="e" valueReference="5"><Alias name="f" displayUnit="cm"/>'
        '<Dimension start="2"/></Float64>')
    assert plain.details is NO_DETAILS and plain.description == "d" and plain.start == "1"
    assert (plain.unit, plain.dimensions, plain.reinit) == (None, (), False)
    assert typed.details is typed2.details
    assert (typed.unit, typed.declared_type, typed.minimum, typed.nominal) == ("m", "L", "0", "2")
    assert (odd.vr, odd.raw_vr, odd.previous, odd.reinit, odd.clocks) == (None, "x4", 2, True, "5")
    assert alias.aliases == ("f",) and alias.alias_display_units == (("f", "cm"),)
    assert [d.start for d in alias.dimensions] == ["2"]
    assert pickle.loads(pickle.dumps(alias)) == alias


def test_an_unknown_attribute_does_not_hide_the_details():
    (var,) = _variables('<Float64 name="a" valueReference="1" foo="1" unit="m"/>')
    assert var.unit == "m"
    (var,) = _variables('<Float64 name="a" valueReference="1" causality="local" max="9"/>')
    assert var.maximum == "9"
    (var,) = _variables('<Float64 name="a" valueReference="1" causality="local" start="1"'
                        ' variability="continuous" initial="exact" derivative="0"'
                        ' description="d" unit="m"/>')
    assert var.unit == "m"


def test_a_large_model_gives_its_freed_tree_back_before_the_manifest(monkeypatch):
    from conformance.run import engine
    from scenes.build import build_scene

    calls: list[int] = []
    monkeypatch.setattr(engine, "release_freed_memory", lambda: calls.append(1))
    fmu = build_scene("HelloWorldDAE")
    engine.check_fmu(fmu, options=engine.EngineOptions(probes=False))
    assert calls == []
    monkeypatch.setattr(engine, "RELEASE_FROM", 1)
    engine.check_fmu(fmu, options=engine.EngineOptions(probes=False))
    assert calls == [1]


def test_release_freed_memory_never_raises():
    heap.release_freed_memory()


def test_equal_start_values_are_one_string():
    a, b, c = _variables('<Float64 name="a" valueReference="1" start="0.5"/>'
                         '<Float64 name="b" valueReference="2" start="0.5"/>'
                         '<Float64 name="c" valueReference="3" start="0.25"/>')
    assert a.start is b.start and (a.start, c.start) == ("0.5", "0.25")
