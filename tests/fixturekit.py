"""Materialise rule fixtures (tests/fixtures/<CODE>/<case>/) into FMU folders or zips."""
from __future__ import annotations

import importlib.util
import shutil
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

from conformance.model.manifest import MANIFEST
from conformance.model.description import MODEL_DESCRIPTION
from scenes.build import SCENES_DIR, scene_xml_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TESTS = Path(__file__).resolve().parent
FIXTURES = TESTS / "fixtures"
SCENES = SCENES_DIR
ALIASES = {"manifest": MANIFEST, "modelDescription": MODEL_DESCRIPTION}
CONTROL = {"fixture.toml", "fixture.py"}


@dataclass(frozen=True)
class Case:
    code: str
    kind: str          # "fail" or "pass"
    folder: Path
    spec: dict

    @property
    def id(self) -> str:
        return f"{self.code}/{self.folder.name}"

    @property
    def expect(self) -> set[str]:
        return set(self.spec.get("expect", []))


def all_cases() -> list[Case]:
    cases = []
    for code_dir in sorted(p for p in FIXTURES.iterdir() if p.is_dir()):
        for case_dir in sorted(p for p in code_dir.iterdir() if p.is_dir()):
            kind = case_dir.name.split("-")[0]
            if kind not in ("fail", "pass"):
                continue
            spec_file = case_dir / "fixture.toml"
            spec = tomllib.loads(spec_file.read_text()) if spec_file.exists() else {}
            cases.append(Case(code_dir.name, kind, case_dir, spec))
    return cases


def scene_xml(base: str) -> dict[str, Path]:
    """The XML of a scene or of a corpus model (which has no manifest)."""
    folder = scene_xml_dir(base)
    return {MODEL_DESCRIPTION: folder / "modelDescription.xml",
            MANIFEST: folder / "fmi-ls-manifest.xml"}


def materialise(case: Case, dest: Path) -> Path:
    """Write the case below ``dest`` and return the path to check."""
    script = case.folder / "fixture.py"
    if script.exists():
        spec = importlib.util.spec_from_file_location(f"fixture_{case.code}", script)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return Path(module.build(dest))
    root = dest / "fmu"
    root.mkdir(parents=True)
    base = case.spec.get("base")
    if base:
        for name, src in scene_xml(base).items():
            if src.exists():
                target = root / name
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(src, target)
    for src in case.folder.rglob("*"):
        if src.is_file() and src.name not in CONTROL:
            target = root / src.relative_to(case.folder)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, target)
    for name in case.spec.get("remove", []):
        (root / ALIASES.get(name, name)).unlink()
    for edit in case.spec.get("edit", []):
        target = root / ALIASES.get(edit["file"], edit["file"])
        text = target.read_text(encoding="utf-8")
        count = text.count(edit["old"])
        if count != 1:
            raise AssertionError(f"{case.id}: edit text occurs {count} times in {edit['file']}: "
                                 f"{edit['old']!r}")
        target.write_text(text.replace(edit["old"], edit.get("new", "")), encoding="utf-8")
    if case.spec.get("archive", "folder") == "zip":
        fmu = dest / f"{case.code}.fmu"
        with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as zf:
            for src in sorted(root.rglob("*")):
                if src.is_file():
                    zf.write(src, src.relative_to(root).as_posix())
        return fmu
    return root


def zip_scene(base: str, target: Path, *, extra: dict[str, bytes] | None = None,
              compression: int = zipfile.ZIP_DEFLATED, duplicate: str | None = None,
              replace: dict[str, bytes] | None = None) -> Path:
    """Zip a scene's XML (plus ``extra`` members) for archive-level fixtures."""
    import warnings

    target.parent.mkdir(parents=True, exist_ok=True)
    members = {name: path.read_bytes() for name, path in scene_xml(base).items()}
    members.update(replace or {})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about the duplicate on purpose
        with zipfile.ZipFile(target, "w", compression) as zf:
            for name, data in {**members, **(extra or {})}.items():
                zf.writestr(name, data)
            if duplicate:
                zf.writestr(duplicate, members[duplicate])
    return target
