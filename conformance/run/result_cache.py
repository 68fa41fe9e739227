"""``--cache-dir DIR``: one FMU's result, kept under the hash of what decides it.

The key is the FMU's content (sha256 of the ``.fmu`` bytes; for an unpacked folder, of every
file's relative path and bytes, and of its folders and symbolic links) together with a
fingerprint of what decides the findings (lsdae's version, a digest of its code and schemas and
of the libraries' versions, the rule catalogue with its options, the engine options and the
platform, computed by :mod:`conformance.run.fleet`). An
unchanged FMU checked with the same settings gets its stored :class:`FmuReport` back and is not
checked again; one changed byte is another key.

Entries are JSON files (the JSON reporter's form plus the source lines, read back with
:mod:`conformance.report.reader`) written to a temporary file and moved into place with
:func:`os.replace`, so parallel jobs sharing the folder and interrupted runs never leave half an
entry. An entry that cannot be read, or is not what its name says, is a miss, never an error.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import stat
import tempfile
from pathlib import Path

from ..report.findings import FmuReport
from ..report.reader import read_fmu
from ..reporters.json_report import fmu_dict

log = logging.getLogger(__name__)

FORMAT = 1          # the layout of an entry; part of every key
_CHUNK = 1 << 20


def content_hash(path: str | Path) -> str | None:
    """The sha256 of an FMU's content, or None when it is neither a file nor a folder, or
    cannot be read (such an FMU is checked, never cached)."""
    digest = hashlib.sha256()
    try:
        info = os.lstat(path)
        if stat.S_ISREG(info.st_mode):
            digest.update(b"fmu-file\0")
            _add_file(digest, Path(path))
        elif stat.S_ISDIR(info.st_mode):
            digest.update(b"fmu-folder\0")
            _add_folder(digest, Path(path))
        else:
            return None
    except OSError:
        return None
    return digest.hexdigest()


def _add_file(digest, path: Path) -> None:
    with path.open("rb") as handle:
        while block := handle.read(_CHUNK):
            digest.update(block)


def _add_folder(digest, root: Path) -> None:
    """Every entry below ``root`` in sorted order: kind, relative path, then bytes or target
    (symbolic links are hashed as links, never followed)."""
    entries: list[str] = []
    for folder, dirs, files in os.walk(root, followlinks=False):
        entries.extend(os.path.join(folder, name) for name in (*dirs, *files))
    for entry in sorted(entries, key=lambda e: Path(e).relative_to(root).as_posix()):
        rel = Path(entry).relative_to(root).as_posix().encode("utf-8", "surrogateescape")
        mode = os.lstat(entry).st_mode
        if stat.S_ISLNK(mode):
            target = os.readlink(entry).encode("utf-8", "surrogateescape")
            digest.update(b"L\0" + rel + b"\0" + target)
        elif stat.S_ISDIR(mode):
            digest.update(b"D\0" + rel)
        elif stat.S_ISREG(mode):
            digest.update(b"F\0" + rel + b"\0" + str(os.lstat(entry).st_size).encode() + b"\0")
            _add_file(digest, Path(entry))
        else:
            digest.update(b"O\0" + rel)
        digest.update(b"\n")


class ResultCache:
    """The entries of one folder for one fingerprint of the settings."""

    def __init__(self, directory: str | Path, settings: str):
        self.directory = Path(directory)
        self.settings = settings

    def key(self, content: str) -> str:
        text = f"lsdae-cache {FORMAT}\0{self.settings}\0{content}"
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def _file(self, key: str) -> Path:
        return self.directory / key[:2] / f"{key}.json"

    def get(self, content: str) -> FmuReport | None:
        """The stored report for this content, or None (absent, unreadable, corrupt)."""
        key = self.key(content)
        file = self._file(key)
        try:
            entry = json.loads(file.read_text(encoding="utf-8"))
            if entry.get("lsdae-cache") != FORMAT or entry.get("key") != key:
                raise ValueError("the entry is not the one its name says")
            return read_fmu(entry["fmu"])
        except FileNotFoundError:
            return None
        except Exception as exc:  # whatever is wrong with an entry, it is a miss
            log.info("cache entry %s not used: %s: %s", file, type(exc).__name__, exc)
            return None

    def put(self, content: str, report: FmuReport) -> bool:
        """Store atomically; False when the folder cannot be written (the run goes on)."""
        key = self.key(content)
        file = self._file(key)
        text = json.dumps({"lsdae-cache": FORMAT, "key": key,
                           "fmu": fmu_dict(report, snippets=True)}, ensure_ascii=False)
        temp = None
        try:
            file.parent.mkdir(parents=True, exist_ok=True)
            handle, temp = tempfile.mkstemp(dir=file.parent, prefix=".tmp-", suffix=".json")
            with os.fdopen(handle, "w", encoding="utf-8") as out:
                out.write(text)
            os.replace(temp, file)
        except OSError as exc:
            if temp is not None:
                Path(temp).unlink(missing_ok=True)
            log.info("cannot write the cache entry %s: %s", file, exc)
            return False
        return True
