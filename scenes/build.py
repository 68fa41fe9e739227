"""Build the lsdae test-scene FMUs from scenes/<Name>/ and the corpus from scenes/corpus/<Name>/.

Each scene folder holds ``model.c`` (plus optional model-specific ``*.c``/``*.h``),
``modelDescription.xml`` and ``fmi-ls-manifest.xml``.  The C framework in
``scenes/common/`` is compiled together with the model into
``binaries/<platform-tuple>/<modelIdentifier>.<ext>`` and zipped with the two XML
files into ``<Name>.fmu``.

The corpus (``scenes/corpus/<Name>/``) holds ordinary FMI 3.0 FMUs that do not use the
fmi-ls-dae layer: Model Exchange, Co-Simulation or Scheduled Execution, no manifest. Their
``model.c`` is compiled with ``scenes/corpus/common/corpus_fmu.c``; every other file of the
folder except C sources and README.md (``terminalsAndIcons/...``) goes into the FMU at the
same relative path. A folder with an ``fmi-ls-manifest.xml`` gets it as the manifest; one
without is built without.

Results are cached by a hash of every input (sources, XML, defines, compiler and
its version, FMI headers, this file).  The cache lives in ``<repo>/.cache/scenes``
unless ``cache_dir`` or the environment variable ``LSDAE_SCENE_CACHE`` says
otherwise.  Builds write into a private temporary directory inside the cache and
publish with an atomic rename, so concurrent builds (two pytest processes) are safe.

``overrides`` replace the text of C sources for one build (the mutation campaign,
``bench/mutation/``): ``build_scene("SimpleDAE", overrides={"SimpleDAE/model.c": text})``
compiles a staged copy of the sources with that file replaced; the cache key holds the
replaced text, so each distinct source set is built once.

Command line::

    python -m scenes.build SimpleDAE Robertson --out DIR [-D DEFECT_X ...]
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Mapping, Sequence

SCENES_DIR = Path(__file__).resolve().parent
REPO_ROOT = SCENES_DIR.parent
COMMON_DIR = SCENES_DIR / "common"
CORPUS_DIR = SCENES_DIR / "corpus"
CORPUS_COMMON_DIR = CORPUS_DIR / "common"
DEFAULT_CACHE_DIR = REPO_ROOT / ".cache" / "scenes"
CACHE_ENV_VAR = "LSDAE_SCENE_CACHE"
MANIFEST_ENTRY = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
MANIFEST_FILE = "fmi-ls-manifest.xml"
INTERFACES = ("ModelExchange", "CoSimulation", "ScheduledExecution")
_NOT_PACKED = {".c", ".h"}
CFLAGS = ("-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-shared", "-fPIC",
          "-fvisibility=hidden")
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # fixed timestamps: reproducible archives
_DEFINE_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(=.*)?$")


class SceneBuildError(RuntimeError):
    """The scene does not exist or the C compiler failed."""


def scene_names() -> list[str]:
    """All scene folders (those with a model.c and a modelDescription.xml)."""
    return sorted(p.name for p in SCENES_DIR.iterdir()
                  if (p / "model.c").is_file() and (p / "modelDescription.xml").is_file())


def corpus_names() -> list[str]:
    """All corpus folders (scenes/corpus/<Name>/ with a model.c and a modelDescription.xml)."""
    return sorted(p.name for p in CORPUS_DIR.iterdir()
                  if (p / "model.c").is_file() and (p / "modelDescription.xml").is_file())


def is_corpus(name: str) -> bool:
    return name in corpus_names()


def scene_xml_dir(name: str) -> Path:
    """Folder holding the scene's modelDescription.xml (and fmi-ls-manifest.xml, if any)."""
    if name in scene_names():
        return SCENES_DIR / name
    if name in corpus_names():
        return CORPUS_DIR / name
    raise SceneBuildError(f"unknown scene {name!r} (known: "
                          f"{', '.join(scene_names() + corpus_names())})")


def _packed_files(name: str) -> list[Path]:
    """Files of a corpus folder that go into the FMU as they are (not the C sources)."""
    if not is_corpus(name):
        return []
    folder = scene_xml_dir(name)
    return sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix not in _NOT_PACKED
                  and p.name not in ("modelDescription.xml", MANIFEST_FILE, "README.md"))


def platform_tuple() -> str:
    """FMI 3 platform tuple of the host, e.g. ``x86_64-linux``."""
    machine = platform.machine().lower()
    arch = {"x86_64": "x86_64", "amd64": "x86_64", "aarch64": "aarch64", "arm64": "aarch64",
            "i386": "x86", "i686": "x86", "x86": "x86", "armv7l": "aarch32"}.get(machine, machine)
    if sys.platform.startswith("linux"):
        system = "linux"
    elif sys.platform == "darwin":
        system = "darwin"
    elif sys.platform in ("win32", "cygwin"):
        system = "windows"
    else:
        system = sys.platform
    return f"{arch}-{system}"


def shared_library_extension() -> str:
    return {"darwin": ".dylib", "win32": ".dll", "cygwin": ".dll"}.get(sys.platform, ".so")


def fmi_headers_dir() -> Path:
    """The FMI 3 C headers shipped with fmpy."""
    import fmpy

    return Path(fmpy.__file__).resolve().parent / "c-code"


def compiler() -> str:
    return os.environ.get("CC", "cc")


@functools.lru_cache(maxsize=None)
def compiler_version(cc: str) -> str:
    try:
        proc = subprocess.run([cc, "--version"], capture_output=True, text=True, check=False)
    except OSError as exc:
        raise SceneBuildError(f"C compiler {cc!r} not found: {exc}") from exc
    return proc.stdout + proc.stderr


def _normalize_defines(defines: Sequence[str]) -> list[str]:
    result = []
    for d in defines:
        d = d[2:] if d.startswith("-D") else d
        if not _DEFINE_RE.match(d):
            raise SceneBuildError(f"not a valid preprocessor define: {d!r}")
        result.append(d)
    return result


def _source_files(name: str) -> list[Path]:
    scene = scene_xml_dir(name)
    common = CORPUS_COMMON_DIR if is_corpus(name) else COMMON_DIR
    files = [p for p in common.iterdir() if p.suffix in (".c", ".h")]
    files += [p for p in scene.iterdir() if p.suffix in (".c", ".h", ".xml")]
    return sorted(set(files) | set(_packed_files(name)))


def _xml_info(md_path: Path) -> tuple[str, str]:
    """(modelIdentifier, instantiationToken).

    A scene needs <ModelExchange>; a corpus model any interface type, all with one
    modelIdentifier (one library serves them all).
    """
    root = ET.parse(md_path).getroot()
    corpus = md_path.parent.parent == CORPUS_DIR
    found = {tag: el.get("modelIdentifier") for tag in INTERFACES
             if (el := root.find(tag)) is not None and (corpus or tag == "ModelExchange")}
    identifiers = set(found.values())
    if not found or None in identifiers or "" in identifiers:
        wanted = "<ModelExchange|CoSimulation|ScheduledExecution" if corpus else "<ModelExchange"
        raise SceneBuildError(f"{md_path}: no {wanted} modelIdentifier=...>")
    if len(identifiers) > 1:
        raise SceneBuildError(f"{md_path}: interface types with different modelIdentifiers")
    token = root.get("instantiationToken", "")
    if not token or any(ch in token for ch in '"\\\n'):
        raise SceneBuildError(f"{md_path}: unusable instantiationToken {token!r}")
    return identifiers.pop(), token


def _check_overrides(name: str, overrides: Mapping[str, str]) -> dict[str, bytes]:
    """The overrides as bytes by path relative to scenes/; each must name a C source of the
    build (a file of the scene's folder or of the framework's)."""
    known = {p.relative_to(SCENES_DIR).as_posix() for p in _source_files(name)
             if p.suffix in _NOT_PACKED}
    for rel in overrides:
        if rel not in known:
            raise SceneBuildError(f"override {rel!r} is not a C source of scene {name} "
                                  f"(known: {', '.join(sorted(known))})")
    return {rel: text.encode() for rel, text in overrides.items()}


def _cache_key(name: str, defines: list[str], cc: str,
               overrides: Mapping[str, bytes] | None = None) -> str:
    h = hashlib.sha256()

    def feed(label: str, data: bytes) -> None:
        h.update(f"{label}\0{len(data)}\0".encode())
        h.update(data)

    feed("scene", name.encode())
    feed("build.py", Path(__file__).read_bytes())
    overrides = overrides or {}
    for path in _source_files(name):
        rel = path.relative_to(SCENES_DIR).as_posix()
        feed(rel, overrides[rel] if rel in overrides else path.read_bytes())
    for header in sorted(fmi_headers_dir().glob("fmi3*.h")):
        feed(header.name, header.read_bytes())
    feed("defines", "\n".join(defines).encode())
    feed("cc", cc.encode())
    feed("cc-version", compiler_version(cc).encode())
    feed("platform", platform_tuple().encode())
    return h.hexdigest()


def _stage(name: str, overrides: Mapping[str, bytes], dest: Path) -> tuple[Path, Path]:
    """Copies of the scene's and the framework's C sources in ``dest`` with ``overrides``
    applied; returns the staged (common, scene) folders."""
    scene = scene_xml_dir(name)
    common = CORPUS_COMMON_DIR if is_corpus(name) else COMMON_DIR
    staged = []
    for folder in (common, scene):
        target = dest / folder.relative_to(SCENES_DIR)
        target.mkdir(parents=True, exist_ok=True)
        for path in folder.iterdir():
            if path.is_file() and path.suffix in _NOT_PACKED:
                rel = path.relative_to(SCENES_DIR).as_posix()
                data = overrides[rel] if rel in overrides else path.read_bytes()
                (target / path.name).write_bytes(data)
        staged.append(target)
    return staged[0], staged[1]


def _compile(name: str, defines: list[str], cc: str, token: str, library: Path,
             overrides: Mapping[str, bytes] | None = None) -> str:
    scene = scene_xml_dir(name)
    common = CORPUS_COMMON_DIR if is_corpus(name) else COMMON_DIR
    if overrides:
        common, scene = _stage(name, overrides, library.parent / "src")
    framework = "corpus_fmu.c" if is_corpus(name) else "fmi3_framework.c"
    sources = [common / framework] + sorted(scene.glob("*.c"))
    cmd = [cc, *CFLAGS, f"-I{common}", f"-I{scene}", f"-I{fmi_headers_dir()}",
           f'-DFMU_INSTANTIATION_TOKEN="{token}"', *[f"-D{d}" for d in defines],
           *map(str, sources), "-o", str(library), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise SceneBuildError(f"compiling scene {name} failed:\n{' '.join(cmd)}\n{proc.stderr}")
    return proc.stderr


def _zip_entry(zf: zipfile.ZipFile, arcname: str, data: bytes) -> None:
    info = zipfile.ZipInfo(arcname, date_time=_ZIP_DATE)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    zf.writestr(info, data)


def build_scene(name: str, *, defines: Sequence[str] = (), cache_dir: Path | None = None,
                overrides: Mapping[str, str] | None = None) -> Path:
    """Build (or fetch from the cache) the FMU of scene ``name``; returns its path.

    ``defines`` are preprocessor macros (``"DEFECT_X"``, ``"N=3"`` or ``"-DDEFECT_X"``)
    used to build deliberately defective variants.  ``overrides`` maps a C source's path
    relative to scenes/ (``"SimpleDAE/model.c"``, ``"common/fmi3_framework.c"``) to the text
    compiled instead of the file's (a mutant); the cache is keyed on that text.  The returned
    file is named
    ``<name>.fmu`` and lives in a cache folder specific to all inputs; next to it,
    ``build.log`` holds the compiler's diagnostics (empty for a clean build).
    """
    defines = _normalize_defines(defines)
    if cache_dir is None:
        cache_dir = Path(os.environ.get(CACHE_ENV_VAR) or DEFAULT_CACHE_DIR)
    cache_dir = Path(cache_dir)
    cc = compiler()
    replaced = _check_overrides(name, overrides or {})
    key = _cache_key(name, defines, cc, replaced)
    out_dir = cache_dir / f"{name}-{key[:20]}"
    fmu = out_dir / f"{name}.fmu"
    if fmu.is_file():
        return fmu

    scene = scene_xml_dir(name)
    model_identifier, token = _xml_info(scene / "modelDescription.xml")
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out_dir, prefix=".build-") as tmp:
        tmp_path = Path(tmp)
        library = tmp_path / (model_identifier + shared_library_extension())
        log = _compile(name, defines, cc, token, library, replaced)
        tmp_fmu = tmp_path / fmu.name
        with zipfile.ZipFile(tmp_fmu, "w") as zf:
            _zip_entry(zf, "modelDescription.xml", (scene / "modelDescription.xml").read_bytes())
            _zip_entry(zf, f"binaries/{platform_tuple()}/{library.name}", library.read_bytes())
            if (scene / MANIFEST_FILE).is_file():  # a corpus model has none
                _zip_entry(zf, MANIFEST_ENTRY, (scene / MANIFEST_FILE).read_bytes())
            for path in _packed_files(name):
                _zip_entry(zf, path.relative_to(scene).as_posix(), path.read_bytes())
        tmp_log = tmp_path / "build.log"
        tmp_log.write_text(log)
        os.replace(tmp_log, out_dir / "build.log")
        os.replace(tmp_fmu, fmu)  # publish last: an existing .fmu is always complete
    return fmu


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m scenes.build",
                                     description="Build the lsdae test-scene FMUs.")
    parser.add_argument("scenes", nargs="*", help="scene or corpus names (default: every scene "
                        f"{scene_names()}); --corpus: every corpus model {corpus_names()}")
    parser.add_argument("--corpus", action="store_true",
                        help="build the corpus of non-DAE FMUs (scenes/corpus/) as well")
    parser.add_argument("--out", type=Path, help="copy the built FMUs into this folder")
    parser.add_argument("-D", dest="defines", action="append", default=[], metavar="MACRO",
                        help="preprocessor define, e.g. -D DEFECT_WRONG_JACOBIAN (repeatable)")
    parser.add_argument("--cache-dir", type=Path, help=f"cache folder (default: ${CACHE_ENV_VAR} "
                        f"or {DEFAULT_CACHE_DIR})")
    args = parser.parse_args(argv)
    try:
        names = list(args.scenes) or scene_names()
        if args.corpus:
            names = list(args.scenes) + corpus_names()
        for name in names:
            fmu = build_scene(name, defines=args.defines, cache_dir=args.cache_dir)
            if args.out:
                args.out.mkdir(parents=True, exist_ok=True)
                fmu = Path(shutil.copyfile(fmu, args.out / fmu.name))
            print(fmu)
    except SceneBuildError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
