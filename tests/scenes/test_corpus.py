"""The corpus: valid FMI 3.0 FMUs that do not use the fmi-ls-dae layer (scenes/corpus/).

Issue 8: a repository of mixed FMUs holds FMUs of every kind, and one valid FMU without the DAE
layer must not fail the build. Each corpus FMU, one per shape real repositories hold, is valid
(fmpy's validation finds no problem, its XML validates against the FMI 3.0 schemas of our schema
stage) and a full ``lsdae check`` with probes exits 0 with exactly one finding: the layer's info
finding, naming the FMU's interface types. Every layer rule is skipped with the true reason; the
core FMI rules run and find nothing. How the C code behaves is in test_corpus_runtime.py.
"""
from __future__ import annotations

import json
import shutil
import zipfile
from functools import cache
from pathlib import Path

import pytest
from fmpy.validation import validate_fmu
from lxml import etree

from conformance.report.catalogue import default_catalogue
from conformance.commands.cli import main
from conformance.run.engine import EngineOptions, check_fmu
from conformance.model.layer import NOT_A_DAE_FMU
from conformance.model.manifest import MANIFEST
from conformance.intake.schema_loader import core_schema_dir
from conformance.intake.schemas import validate_model_description
from scenes.build import build_scene, corpus_names, scene_xml_dir

# Each corpus model and the interface types its modelDescription declares.
SHAPES = {
    "CoSimulationOnly": ("Co-Simulation",),
    "ScheduledExecutionOnly": ("Scheduled Execution",),
    "ModelExchangeEvents": ("Model Exchange",),
    "TypesAndArrays": ("Model Exchange",),
    "TerminalsAndIcons": ("Model Exchange", "Co-Simulation"),
    "StructuralParameters": ("Model Exchange", "Co-Simulation"),
    "StartTime": ("Model Exchange", "Co-Simulation"),
}
NAMES = sorted(SHAPES)
LAYER_NEEDS = {"manifest", "dae-layer"}


@cache
def corpus_fmu(name: str) -> Path:
    return build_scene(name)


def _members(name: str) -> dict[str, bytes]:
    with zipfile.ZipFile(corpus_fmu(name)) as zf:
        return {n: zf.read(n) for n in zf.namelist()}


def test_the_corpus_holds_every_shape():
    assert corpus_names() == NAMES


@pytest.mark.parametrize("name", NAMES)
def test_fmpy_finds_no_problem(name):
    assert validate_fmu(str(corpus_fmu(name))) == []


@pytest.mark.parametrize("name", NAMES)
def test_model_description_is_valid_against_the_fmi3_schema(name):
    tree = etree.ElementTree(etree.fromstring(_members(name)["modelDescription.xml"]))
    assert list(validate_model_description(tree)) == []


@pytest.mark.parametrize("name", NAMES)
def test_the_fmu_has_no_manifest_and_no_layer_folder(name):
    assert not any(n.startswith("extra/") for n in _members(name))


def test_terminals_and_icons_are_valid_and_their_icons_exist():
    members = _members("TerminalsAndIcons")
    schema = etree.XMLSchema(etree.parse(str(core_schema_dir() / "fmi3TerminalsAndIcons.xsd")))
    root = etree.fromstring(members["terminalsAndIcons/terminalsAndIcons.xml"])
    schema.assertValid(root)
    assert "terminalsAndIcons/icon.png" in members
    bases = [el.get("iconBaseName") for el in root.iter("TerminalGraphicalRepresentation")]
    assert bases and all(f"terminalsAndIcons/{b}.png" in members for b in bases)
    for name, data in members.items():
        if name.endswith(".png"):
            assert data.startswith(b"\x89PNG\r\n\x1a\n"), name
    md = etree.fromstring(members["modelDescription.xml"])
    variables = {el.get("name") for el in md.find("ModelVariables")}
    members_named = {el.get("variableName") for el in root.iter("TerminalMemberVariable")}
    assert members_named <= variables


@pytest.mark.parametrize("name", NAMES)
def test_full_check_with_probes_exits_0_with_only_the_layer_info(name, tmp_path, capsys):
    out = tmp_path / "report.json"
    assert main(["check", str(corpus_fmu(name)), "--format", f"json:{out}"]) == 0
    [fmu] = json.loads(out.read_text(encoding="utf-8"))["fmus"]
    findings = fmu["findings"]
    assert [(f["code"], f["severity"]) for f in findings] == [("DAE091", "info")], findings
    assert tuple(findings[0]["evidence"]["interface_types"]) == SHAPES[name]
    assert findings[0]["evidence"]["layer_declared_by"] is None

    skipped = {s["code"]: s["reason"] for s in fmu["rules_skipped"]}
    catalogue = default_catalogue()
    layer_rules = {r.code for r in catalogue  # the schema stage lists no skipped rule
                   if LAYER_NEEDS & set(r.needs) and r.stage in ("static", "probe")}
    assert {code: skipped.get(code) for code in layer_rules} == dict.fromkeys(layer_rules,
                                                                              NOT_A_DAE_FMU)
    probes = {r.code for r in catalogue if r.stage == "probe"}
    assert probes <= layer_rules       # so the probe stage gives the same true reason
    core = {r.code for r in catalogue
            if r.stage == "static" and set(r.needs) <= {"model-description"}}
    assert core and core <= set(fmu["rules_run"])


def test_a_dae_fmu_without_model_exchange_still_gets_model_exchange_missing(tmp_path):
    """The rule is about the layer: with a manifest, a Co-Simulation-only FMU fails it."""
    fmu = tmp_path / "CoSimulationWithManifest.fmu"
    shutil.copyfile(corpus_fmu("CoSimulationOnly"), fmu)
    with zipfile.ZipFile(fmu, "a") as zf:
        zf.writestr(MANIFEST, (scene_xml_dir("HelloWorldDAE") / "fmi-ls-manifest.xml").read_bytes())
    report = check_fmu(fmu, options=EngineOptions(probes=False))
    assert "DAE501" in {f.code for f in report.findings}
    assert "DAE091" not in {f.code for f in report.findings}


@pytest.mark.parametrize("name", ["CoSimulationOnly", "ScheduledExecutionOnly"])
def test_an_enable_parameter_alone_declares_the_layer(name, tmp_path):
    """A variable named like the enable parameter makes the FMU a DAE FMU without a manifest."""
    fmu = tmp_path / f"{name}.fmu"
    members = _members(name)
    text = members["modelDescription.xml"].decode()
    members["modelDescription.xml"] = text.replace(
        "</ModelVariables>",
        '  <Boolean name="enableDAEModeParameter" valueReference="99" '
        'causality="structuralParameter" variability="fixed" start="false"/>\n'
        "  </ModelVariables>").encode()
    with zipfile.ZipFile(fmu, "w") as zf:
        for member, data in members.items():
            zf.writestr(member, data)
    report = check_fmu(fmu, options=EngineOptions(probes=False))
    by_code = {f.code: f for f in report.findings}
    assert "DAE501" in by_code
    assert dict(by_code["DAE091"].evidence)["layer_declared_by"] == "variable 'enableDAEModeParameter'"
    assert dict(report.rules_skipped).get("DAE501") is None
