"""``runtime.modes.start_initialization``: a fresh instance in Initialization Mode whose start
values were set in Instantiated, read there and freed without an illegal call."""
from __future__ import annotations

import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.errors import FmiError
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.runtime.modes import start_initialization
from scenes.build import build_scene


@pytest.fixture
def library(tmp_path: Path) -> Iterator[Library]:
    with zipfile.ZipFile(build_scene("SimpleDAE")) as zf:
        zf.extractall(tmp_path)
    model = read_model_description(etree.parse(str(tmp_path / MODEL_DESCRIPTION)))
    manifest = read_manifest(etree.parse(str(tmp_path / MANIFEST)), draft="alpha1")
    lib = Library(str(tmp_path), Layout.build(model, manifest), CallRecord())
    yield lib
    lib.free_all()


def _residuals_zero(inst) -> bool:
    return bool(np.all(np.abs(inst.get_float64([11, 12])) < 1e-9))


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_start_values_are_used_in_initialization_mode(library, mode):
    inst = start_initialization(library, mode, {1: 0.7, 3: 0.4, 7: 0.2, 8: -0.1}, 0.25)
    try:
        assert inst.initializing and inst.mode == mode
        assert inst.get_float64([1, 3, 7, 8, 0]).tolist() == [0.7, 0.4, 0.2, -0.1, 0.25]
        z1 = inst.get_float64([5])[0]           # solved from g = 0 at those start values
        assert abs(z1 * 0.2**2 + np.tanh(3 * z1) - 0.1 * 0.7**3) < 1e-9
        if mode == "dae":
            assert _residuals_zero(inst)
    finally:
        inst.free()
    assert library.instances == []


def test_free_in_initialization_mode_calls_no_terminate(library):
    inst = start_initialization(library, "dae", {}, 0.0)
    inst.get_float64([2])
    calls = inst.calls
    inst.free()
    assert inst.calls == calls + 1               # fmi3FreeInstance only
    assert not any("[Error]" in line for line in library.log), library.log


def test_a_rejected_start_value_names_the_set_and_frees_the_instance(library):
    with pytest.raises(FmiError) as err:
        start_initialization(library, "dae", {11: 1.0}, 0.0)   # a residual: not settable
    assert err.value.call == "fmi3SetFloat64"
    assert library.instances == []


def test_initialization_instances_are_numbered_apart(library):
    # many of them must not rename the other instances named in the reports
    for _ in range(3):
        start_initialization(library, "dae", {}, 0.0).free()
    assert library.next_name("dae") == "lsdae-dae-1"
