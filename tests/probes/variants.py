"""Build defect variants of the scene FMUs: C defines and/or textual XML edits.

    variant("SimpleDAE", defines=["DEFECT_WRONG_JACOBIAN"])
    variant("HelloWorldDAE", manifest_edits=[('dependencies="2 4 5"', 'dependencies="2 4"')])

Edits use the same rule as the fixtures: each ``old`` text must occur exactly once.
"""
from __future__ import annotations

import hashlib
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

from conformance.manifest import MANIFEST
from conformance.model import MODEL_DESCRIPTION
from scenes.build import build_scene

CACHE = Path(__file__).resolve().parents[2] / ".cache" / "variants"


@dataclass(frozen=True)
class Defect:
    """One defect variant and the probe rule it must trigger (and nothing else)."""

    code: str                       # the rule code expected
    scene: str
    defines: tuple[str, ...] = ()
    manifest_edits: tuple[tuple[str, str], ...] = ()
    md_edits: tuple[tuple[str, str], ...] = ()
    also: tuple[str, ...] = ()      # other codes that legitimately appear (e.g. a static rule)
    note: str = ""
    options: dict = field(default_factory=dict, compare=False, hash=False)

    @property
    def id(self) -> str:
        return f"{self.code}-{self.scene}-{'-'.join(self.defines) or 'xml'}"


def _edit(text: str, edits: Sequence[tuple[str, str]], what: str) -> str:
    for old, new in edits:
        count = text.count(old)
        if count != 1:
            raise AssertionError(f"{what}: edit text occurs {count} times: {old!r}")
        text = text.replace(old, new)
    return text


def variant(scene: str, *, defines: Sequence[str] = (),
            manifest_edits: Sequence[tuple[str, str]] = (),
            md_edits: Sequence[tuple[str, str]] = ()) -> Path:
    """The scene built with ``defines``, its XML edited; cached by content."""
    base = build_scene(scene, defines=defines)
    if not manifest_edits and not md_edits:
        return base
    key = hashlib.sha256(repr((base.read_bytes(), tuple(manifest_edits),
                               tuple(md_edits))).encode()).hexdigest()[:16]
    target = CACHE / f"{scene}-{key}.fmu"
    if target.exists():
        return target
    CACHE.mkdir(parents=True, exist_ok=True)
    tmp = target.with_suffix(f".{os.getpid()}.tmp")
    with zipfile.ZipFile(base) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == MANIFEST and manifest_edits:
                data = _edit(data.decode(), manifest_edits, f"{scene} manifest").encode()
            elif info.filename == MODEL_DESCRIPTION and md_edits:
                data = _edit(data.decode(), md_edits, f"{scene} modelDescription").encode()
            zout.writestr(info, data)
    os.replace(tmp, target)
    return target


def build(defect: Defect) -> Path:
    return variant(defect.scene, defines=defect.defines, manifest_edits=defect.manifest_edits,
                   md_edits=defect.md_edits)
