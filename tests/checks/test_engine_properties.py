"""Property: on random mutations of the scenes' XML, the engine only ever returns findings.

No exception escapes, no check fails internally (an ``internal-error`` finding would mean a
check crashed on input it did not expect), and the report is complete: it renders as JSON and
its summary does not call a present manifest absent. Mutations delete, set, swap and add
attributes (hostile values included: numbers of thousands of digits, out of range for UInt32),
duplicate, move, drop and retag elements, and truncate the file.

The examples are derandomised (the same ones every run) and few in ``make test``; ``make fuzz``
(``pytest --fuzz N``) runs N times as many, with a random seed.
"""
from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from conformance.run.engine import EngineOptions, check_paths
from conformance.model.manifest import MANIFEST
from conformance.model.description import MODEL_DESCRIPTION
from conformance.reporters import json_report
from tests.fixturekit import scene_xml

SCENES = ("HelloWorldDAE", "SimpleDAE", "Robertson")
HUGE = "1" * 5000     # more digits than Python's int() reads by default (4300)
VALUES = st.sampled_from(["", "0", "1", "-1", "99", "1 2 3", "x", "true", "false", "fixed",
                          "continuous", "local", "output", "structuralParameter", "dependent",
                          "constant", "1e308", "nan", "4294967296", "2 2", "\u00e9", HUGE,
                          f"1 {HUGE} 2", "18446744073709551616", "-0", "INF", "-INF", "NaN",
                          f"{HUGE}.0.0", f"1.0.0-{HUGE}", "1.0.0-alpha.01", "\t", "a\nb",
                          "0x10", "+1", "1_000"])
ACTIONS = ["drop-attr", "set-attr", "drop-element", "duplicate-element", "move-element",
           "rename-element", "add-attr", "swap-attrs", "truncate"]
MUTATIONS = st.lists(st.tuples(st.sampled_from(ACTIONS), st.integers(0, 10_000),
                               st.integers(0, 10_000), VALUES),
                     min_size=1, max_size=6)
EXAMPLES = 300


def _mutate(data: bytes, mutations) -> bytes:
    root = etree.fromstring(data)
    cut = None
    for action, i, j, value in mutations:
        if action == "truncate":
            cut = i
            continue
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        el = elements[i % len(elements)]
        names = sorted(el.attrib)
        if action == "drop-attr" and names:
            del el.attrib[names[j % len(names)]]
        elif action == "set-attr" and names:
            el.set(names[j % len(names)], value)
        elif action == "add-attr":
            el.set(["valueReference", "dependencies", "dependenciesKind", "causality",
                    "variability", "initial", "start", "derivative"][j % 8], value)
        elif action == "drop-element" and el is not root:
            el.getparent().remove(el)
        elif action == "duplicate-element" and el is not root:
            el.addnext(etree.fromstring(etree.tostring(el)))
        elif action == "move-element" and el is not root:
            target = elements[j % len(elements)]
            if el not in target.iterancestors() and el is not target:
                el.getparent().remove(el)
                target.append(el)
        elif action == "swap-attrs" and len(names) > 1:
            a, b = names[j % len(names)], names[(j + 1) % len(names)]
            va, vb = el.get(a), el.get(b)
            el.set(a, vb)
            el.set(b, va)
        elif action == "rename-element" and el is not root:
            el.tag = ["Float64", "Boolean", "Residual", "Output", "AlgebraicVariable",
                      "Formulation", "InitialUnknown", "Int32"][j % 8]
    text = etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    return text if cut is None else text[:cut % max(len(text), 1)]


def _check(scene: str, target: str, mutations) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "fmu"
        for name, src in scene_xml(scene).items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, root / name)
        path = root / target
        path.write_bytes(_mutate(path.read_bytes(), mutations))
        report = check_paths([root], options=EngineOptions(probes=False))
    fmu = report.fmus[0]
    crashed = [f for f in fmu.findings if f.name == "internal-error"]
    assert not crashed, crashed
    data = json.loads(json_report.render(report))        # the report is complete and strict
    assert len(data["fmus"]) == 1 and data["fmus"][0]["rules_run"]
    if fmu.draft is None:  # a present manifest is never summarised as absent
        assert "DAE091" not in {f.code for f in fmu.findings}, "the manifest is there"


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(scene=st.sampled_from(SCENES), target=st.sampled_from([MODEL_DESCRIPTION, MANIFEST]),
       mutations=MUTATIONS)
def test_engine_never_raises_on_mutated_xml(scene, target, mutations):
    _check(scene, target, mutations)


def test_fuzz(fuzz):
    """``pytest --fuzz N`` (``make fuzz``): N times the examples, with a random seed."""
    if not fuzz:
        pytest.skip("run with --fuzz N (make fuzz)")

    @settings(max_examples=EXAMPLES * fuzz, deadline=None, derandomize=False,
              suppress_health_check=[HealthCheck.too_slow])
    @given(scene=st.sampled_from(SCENES), target=st.sampled_from([MODEL_DESCRIPTION, MANIFEST]),
           mutations=MUTATIONS)
    def run(scene, target, mutations):
        _check(scene, target, mutations)

    run()


INTEGERS = ("valueReference", "dependencies", "derivative")  # UInt32: 4294967296 is too large
NUMERIC = [*INTEGERS, "version", "start", "nominal", "startTime", "stopTime", "fmiVersion"]


def _present() -> list[tuple[str, str]]:
    """(file, attribute) pairs of NUMERIC that SimpleDAE's XML has (the others cannot be set)."""
    out = []
    for target in (MODEL_DESCRIPTION, MANIFEST):
        root = etree.fromstring(scene_xml("SimpleDAE")[target].read_bytes())
        names = {a for el in root.iter() if isinstance(el.tag, str) for a in el.attrib}
        out += [(target, attribute) for attribute in NUMERIC if attribute in names]
    return out


@pytest.mark.parametrize("target, attribute", _present())
@pytest.mark.parametrize("value", [HUGE, f"{HUGE}.0.0", f"1 {HUGE}", "4294967296"])
def test_a_number_out_of_range_is_a_finding_never_an_internal_error(target, attribute, value):
    """Every numeric attribute of the scene, set to a number of thousands of digits (or just
    past UInt32): the rule that reads it reports it; no check stops with an internal error."""
    root = etree.fromstring((scene_xml("SimpleDAE")[target]).read_bytes())
    hits = [el for el in root.iter() if isinstance(el.tag, str) and attribute in el.attrib]
    assert hits
    mutations = [("set-attr-named", k, 0, (attribute, value)) for k in range(len(hits))]
    for el in hits:
        el.set(attribute, value)
    data = etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    with tempfile.TemporaryDirectory() as tmp:
        fmu = Path(tmp) / "fmu"
        for name, src in scene_xml("SimpleDAE").items():
            (fmu / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, fmu / name)
        (fmu / target).write_bytes(data)
        report = check_paths([fmu], options=EngineOptions(probes=False))
    assert mutations
    crashed = [f.message for f in report.fmus[0].findings if f.name == "internal-error"]
    assert not crashed, crashed
    # (a DefaultExperiment time of 1e4999 is read as infinity and is only a suggestion)
    if (attribute in INTEGERS or value != "4294967296") and "Time" not in attribute:
        assert report.fmus[0].findings, "a number out of range passed unreported"
