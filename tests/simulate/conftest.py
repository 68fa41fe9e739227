"""Shared fixtures of the simulation tests: a scene's binary loaded in this process."""
from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.intake.xmlsafe import parse_xml
from scenes.build import build_scene


@pytest.fixture
def loaded(tmp_path):
    """load(scene, *defines) -> (library, layout, model, manifest), extracted into tmp_path."""
    libraries = []

    def load(scene: str, *defines: str):
        folder = Path(tmp_path) / "-".join([scene, *defines])
        with zipfile.ZipFile(build_scene(scene, defines=list(defines))) as zf:
            zf.extractall(folder)
        model = read_model_description(parse_xml((folder / MODEL_DESCRIPTION).read_bytes(),
                                                 file=MODEL_DESCRIPTION)[0],
                                       file=MODEL_DESCRIPTION)
        manifest = read_manifest(parse_xml((folder / MANIFEST).read_bytes(), file=MANIFEST)[0],
                                 draft="alpha1", file=MANIFEST)
        layout = Layout.build(model, manifest)
        library = Library(str(folder), layout, CallRecord())
        libraries.append(library)
        return library, layout, model, manifest

    yield load
    for library in libraries:
        library.free_all()
