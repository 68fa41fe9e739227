"""Small FMU folders made from the HelloWorldDAE scene's XML, with textual edits."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from conformance.model.manifest import MANIFEST
from conformance.model.description import MODEL_DESCRIPTION
from tests.fixturekit import scene_xml

BOOLEAN_DAE = ('<Boolean name="dae" valueReference="1" causality="structuralParameter" '
               'variability="fixed" start="false" description="enables the fmi-ls-dae DAE mode"/>')
INT_DAE = ('<Int32 name="dae" valueReference="1" causality="structuralParameter" '
           'variability="fixed" start="0" description="enables the fmi-ls-dae DAE mode"/>')


def make_fmu(root: Path, *, edits: tuple[tuple[str, str], ...] = (), manifest: bool = True
             ) -> Path:
    """Write an unpacked FMU folder at ``root``; ``edits`` replace text in modelDescription."""
    for name, src in scene_xml("HelloWorldDAE").items():
        if name == MANIFEST and not manifest:
            continue
        target = root / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
    md = root / MODEL_DESCRIPTION
    text = md.read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    md.write_text(text, encoding="utf-8")
    return root


@pytest.fixture
def fmu(tmp_path):
    """``fmu(name, **kw)`` -> the path of a fresh FMU folder under tmp_path."""
    def factory(name: str, **kw) -> Path:
        return make_fmu(tmp_path / name, **kw)
    return factory
