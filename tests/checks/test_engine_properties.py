"""Property: on random mutations of the scenes' XML, the engine only ever returns findings.

No exception escapes, and no check fails internally (an ``internal-error`` finding would mean a
check crashed on input it did not expect).
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from conformance.engine import EngineOptions, check_fmu
from conformance.manifest import MANIFEST
from conformance.model import MODEL_DESCRIPTION
from tests.fixturekit import scene_xml

SCENES = ("HelloWorldDAE", "SimpleDAE", "Robertson")
VALUES = st.sampled_from(["", "0", "1", "-1", "99", "1 2 3", "x", "true", "false", "fixed",
                          "continuous", "local", "output", "structuralParameter", "dependent",
                          "constant", "1e308", "nan", "4294967296", "2 2", "\u00e9"])
MUTATIONS = st.lists(st.tuples(st.sampled_from(["drop-attr", "set-attr", "drop-element",
                                                "duplicate-element", "move-element",
                                                "rename-element", "add-attr"]),
                               st.integers(0, 10_000), st.integers(0, 10_000), VALUES),
                     min_size=1, max_size=6)


def _mutate(data: bytes, mutations) -> bytes:
    root = etree.fromstring(data)
    for action, i, j, value in mutations:
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
        elif action == "rename-element" and el is not root:
            el.tag = ["Float64", "Boolean", "Residual", "Output", "AlgebraicVariable",
                      "Formulation", "InitialUnknown", "Int32"][j % 8]
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=st.sampled_from(SCENES), target=st.sampled_from([MODEL_DESCRIPTION, MANIFEST]),
       mutations=MUTATIONS)
def test_engine_never_raises_on_mutated_xml(scene, target, mutations):
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "fmu"
        for name, src in scene_xml(scene).items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, root / name)
        path = root / target
        path.write_bytes(_mutate(path.read_bytes(), mutations))
        report = check_fmu(root, options=EngineOptions(probes=False))
    crashed = [f for f in report.findings if f.name == "internal-error"]
    assert not crashed, crashed
