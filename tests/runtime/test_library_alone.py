"""Instances alone (``Library.alone``): every instance of the twin loads a copy of the binary of
its own, so a C global one instance writes is not what another reads.

SimpleDAE built with ``DEFECT_SHARED=SHARED_MODE`` keeps the DAE switch in one C global: in one
library an ODE-mode instance made after a DAE-mode one reads the switch true; made from the twin,
false. The copies live beside the extracted FMU and are limited in number.
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from lxml import etree

from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.model.manifest import MANIFEST, read_manifest
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.errors import Unavailable
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.runtime.modes import start_instance
from tests.fixtures import build_scene

SHARED = ["DEFECT_SHARED=SHARED_MODE", "DEFECT_SHARED_BY=SHARED_EVERY"]


def _library(where: Path, defines: list[str]) -> Library:
    fmu = where / "fmu"
    with zipfile.ZipFile(build_scene("SimpleDAE", defines=defines)) as zf:
        zf.extractall(fmu)
    model = read_model_description(etree.parse(str(fmu / MODEL_DESCRIPTION)))
    manifest = read_manifest(etree.parse(str(fmu / MANIFEST)), draft="alpha1")
    return Library(str(fmu), Layout.build(model, manifest), CallRecord())


def _switches(library: Library) -> list[bool]:
    """The switch read back by a DAE-mode instance and by an ODE-mode one made after it."""
    dae, ode = start_instance(library, "dae"), start_instance(library, "ode")
    try:
        vr = library.layout.enable
        assert vr is not None
        return [dae.get_boolean(vr), ode.get_boolean(vr)]
    finally:
        dae.free()
        ode.free()


@pytest.mark.parametrize("defines, shared", [(SHARED, [True, True]), ([], [True, False])])
def test_one_library_shares_its_globals_and_the_twin_does_not(tmp_path, defines, shared):
    library = _library(tmp_path, defines)
    assert _switches(library) == shared
    assert _switches(library.alone(4)) == [True, False]


def test_the_copies_are_beside_the_fmu_and_limited(tmp_path):
    library = _library(tmp_path, SHARED)
    twin = library.alone(2)
    first, second = start_instance(twin, "dae"), start_instance(twin, "ode")
    try:
        copies = sorted(p.name for p in tmp_path.iterdir() if p.name != "fmu")
        assert len(copies) == 2 and all(c.startswith("lsdae-alone-") for c in copies)
        with pytest.raises(Unavailable):
            start_instance(twin, "dae")
    finally:
        first.free()
        second.free()
