"""Map the files pre-commit passes to the FMUs to check (``lsdae pre-commit FILES...``).

pre-commit hands a hook the changed files that match its ``files`` pattern (see
``.pre-commit-hooks.yaml``): packed ``.fmu`` archives, and the ``modelDescription.xml`` or
fmi-ls-dae manifest of unpacked FMU folders. An archive is checked as it is; an XML file stands
for the FMU folder it belongs to, so a change to either file of an unpacked FMU checks that FMU
once.
"""
from __future__ import annotations

from pathlib import Path, PurePosixPath
from typing import Iterable

from ..model.manifest import MANIFEST
from ..model.description import MODEL_DESCRIPTION

_MANIFEST_PARTS = PurePosixPath(MANIFEST).parts


def fmu_root(file: str) -> str | None:
    """The FMU a changed file belongs to, as a path string, or None when it belongs to none.

    ``x.fmu`` is itself; ``dir/modelDescription.xml`` is ``dir``;
    ``dir/extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml`` is ``dir``. The manifests of
    other layered standards are not ours to check.
    """
    posix = PurePosixPath(file.replace("\\", "/"))
    if posix.suffix.lower() == ".fmu":
        return file
    if posix.name == MODEL_DESCRIPTION:
        return _as_path(posix.parent)
    depth = len(_MANIFEST_PARTS)
    if posix.parts[-depth:] == _MANIFEST_PARTS:
        return _as_path(PurePosixPath(*posix.parts[:-depth]) if len(posix.parts) > depth
                        else PurePosixPath("."))
    return None


def _as_path(p: PurePosixPath) -> str:
    return str(Path(p)) if str(p) else "."


def fmu_roots(files: Iterable[str]) -> list[str]:
    """The FMUs to check, each once, in the order first named; roots that vanished are skipped
    (a deleted FMU's files are not passed by pre-commit, but a moved folder may be)."""
    seen: dict[str, None] = {}
    for file in files:
        root = fmu_root(file)
        if root is None or not Path(root).exists():
            continue
        seen.setdefault(root, None)
    return list(seen)
