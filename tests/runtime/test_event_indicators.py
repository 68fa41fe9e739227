"""The runtime's event indicators: the layout reads the <EventIndicator> lists, the instance
calls fmi3GetNumberOfEventIndicators and fmi3GetEventIndicators (EventDAE has one indicator,
SimpleDAE none)."""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from lxml import etree

from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.probes.instruments.api import FmiError, Point
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.runtime.modes import start_instance
from tests.fixtures import build_scene


def _library(name: str, where: Path) -> Library:
    with zipfile.ZipFile(build_scene(name)) as zf:
        zf.extractall(where)
    model = read_model_description(etree.parse(str(where / MODEL_DESCRIPTION)))
    manifest = read_manifest(etree.parse(str(where / MANIFEST)), draft="alpha1")
    return Library(str(where), Layout.build(model, manifest), CallRecord())


def test_layout_lists_the_indicators_of_both_structures(tmp_path):
    library = _library("EventDAE", tmp_path)
    try:
        assert library.layout.event_indicators_for("dae") == (6,)
        assert library.layout.event_indicators_for("ode") == (6,)
    finally:
        library.free_all()


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_instance_reads_count_and_values(tmp_path, mode):
    library = _library("EventDAE", tmp_path)
    try:
        inst = start_instance(library, mode)
        assert inst.number_of_event_indicators() == 1
        point = Point(0.1, {1: 0.7, 3: 0.9} if mode == "dae" else {1: 0.7})
        inst.set_point(point)
        z = inst.get_event_indicators(1)
        expected = 0.9 - 0.5 if mode == "dae" else 0.7 - 0.5   # (w - b)/k - 0.5
        assert z[0] == pytest.approx(expected)
        assert z[0] == inst.get_float64([6])[0]
        with pytest.raises(FmiError):
            inst.get_event_indicators(2)
    finally:
        library.free_all()


def test_a_model_without_indicators(tmp_path):
    library = _library("SimpleDAE", tmp_path)
    try:
        assert library.layout.event_indicators == ()
        inst = start_instance(library, "dae")
        assert inst.number_of_event_indicators() == 0
        assert len(inst.get_event_indicators(0)) == 0
    finally:
        library.free_all()
