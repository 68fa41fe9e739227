"""The FMU being fixed, and how it is written: nothing but the fixed files changes.

A zip is rewritten entry by entry in the original order: an entry that no fix touched is copied
raw (local header fields, compressed bytes, name and compression method as they were: its CRC
and bytes cannot change), an edited entry is recompressed with its own method and timestamp, and
a dropped duplicate is left out. An unpacked folder is copied (or, in place, left alone) and only
the fixed files are rewritten. Every read is bounded by the archive limits ``check`` uses; the
caller refuses to fix an archive that ``check`` found unsafe, oversized or unreadable.
"""
from __future__ import annotations

import copy
import os
import shutil
import struct
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from ..intake.archive.base import ArchiveLimits, is_within

_LOCAL_HEADER = 30
_DATA_DESCRIPTOR = 0x08


class PackageError(Exception):
    """The FMU cannot be read or written as needed for fixing (the message says why)."""


@dataclass(frozen=True)
class Package:
    """An FMU (``zip`` or ``folder``) plus the new text of edited files and dropped entries."""

    path: Path
    limits: ArchiveLimits
    changed: tuple[tuple[str, bytes], ...] = ()
    dropped: frozenset[int] = field(default_factory=frozenset)   # indices into entries()

    @property
    def kind(self) -> str:
        return "folder" if self.path.is_dir() else "zip"

    # -- reading ------------------------------------------------------------------------------
    def entries(self) -> list[zipfile.ZipInfo]:
        """The zip's entries in archive order (empty for a folder)."""
        if self.kind == "folder":
            return []
        try:
            with zipfile.ZipFile(self.path) as zf:
                return zf.infolist()
        except (OSError, zipfile.BadZipFile) as exc:
            raise PackageError(f"cannot read the archive: {exc}") from None

    def entry_bytes(self, index: int) -> bytes:
        info = self.entries()[index]
        with zipfile.ZipFile(self.path) as zf:
            return self._bounded(zf, info)

    def _bounded(self, zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> bytes:
        limit = self.limits.max_member
        if info.file_size > limit:
            raise PackageError(f"{info.filename} is larger than the member limit")
        with zf.open(info) as stream:
            data = stream.read(limit + 1)
        if len(data) > limit:
            raise PackageError(f"{info.filename} is larger than the member limit")
        return data

    def original(self, name: str) -> bytes | None:
        """The file as the FMU holds it (the last entry of that name, as ``check`` reads)."""
        if self.kind == "folder":
            target = self.path / name
            if target.is_symlink() or not is_within(str(target.resolve()),
                                                    str(self.path.resolve())):
                return None
            if not target.is_file() or target.stat().st_size > self.limits.max_member:
                return None
            return target.read_bytes()
        entries = [i for i in self.entries() if i.filename == name]
        if not entries:
            return None
        with zipfile.ZipFile(self.path) as zf:
            return self._bounded(zf, entries[-1])

    def read(self, name: str) -> bytes | None:
        """The file as fixed so far."""
        return dict(self.changed).get(name, self.original(name))

    def with_files(self, files: dict[str, bytes], drop: frozenset[int] = frozenset()) -> Package:
        changed = dict(self.changed)
        changed.update(files)
        return Package(self.path, self.limits, tuple(sorted(changed.items())),
                       self.dropped | drop)

    def diffable(self) -> list[tuple[str, bytes, bytes]]:
        """(name, before, after) of every edited file whose bytes changed."""
        out = []
        for name, new in self.changed:
            old = self.original(name) or b""
            if old != new:
                out.append((name, old, new))
        return out

    @property
    def modified(self) -> bool:
        return bool(self.dropped) or bool(self.diffable())

    # -- writing ------------------------------------------------------------------------------
    def write(self, dest: Path) -> None:
        """Write the fixed FMU to ``dest`` (a file for a zip, a folder for a folder), through a
        temporary sibling that replaces ``dest`` only when complete."""
        dest = Path(dest)
        if self.kind == "folder":
            self._write_folder(dest)
        else:
            self._write_zip(dest)

    def _write_zip(self, dest: Path) -> None:
        changed = dict(self.changed)
        fd, tmp = tempfile.mkstemp(prefix=".lsdae-fix-", suffix=".fmu", dir=dest.parent)
        os.close(fd)
        try:
            with open(self.path, "rb") as src, zipfile.ZipFile(tmp, "w") as out:
                for index, info in enumerate(zipfile.ZipFile(src).infolist()):
                    if index in self.dropped:
                        continue
                    if info.filename in changed:
                        _write_edited(out, info, changed[info.filename])
                    else:
                        _copy_raw(src, out, info)
            shutil.copymode(dest if dest.exists() else self.path, tmp)  # mkstemp gives 0600
            os.replace(tmp, dest)
        except BaseException:
            _remove(Path(tmp))
            raise

    def _write_folder(self, dest: Path) -> None:
        same = dest.exists() and dest.resolve() == self.path.resolve()
        root = self.path if same else Path(tempfile.mkdtemp(prefix=".lsdae-fix-",
                                                            dir=dest.parent))
        try:
            if not same:
                shutil.copytree(self.path, root, symlinks=True, dirs_exist_ok=True)
            for name, data in self.changed:
                target = root / name
                if not is_within(str(target.resolve()), str(root.resolve())):
                    raise PackageError(f"{name} would be written outside the output")
                if target.exists() and target.read_bytes() == data:
                    continue
                fd, tmp = tempfile.mkstemp(prefix=".lsdae-fix-", dir=target.parent)
                with os.fdopen(fd, "wb") as handle:
                    handle.write(data)
                if target.exists():
                    shutil.copymode(target, tmp)  # mkstemp gives 0600
                os.replace(tmp, target)
            if not same:
                if dest.exists():
                    raise PackageError(f"{dest} exists")
                os.replace(root, dest)
        except BaseException:
            if not same:
                shutil.rmtree(root, ignore_errors=True)
            raise


def _write_edited(out: zipfile.ZipFile, info: zipfile.ZipInfo, data: bytes) -> None:
    entry = zipfile.ZipInfo(info.filename, info.date_time)
    entry.compress_type = info.compress_type
    entry.external_attr = info.external_attr
    entry.create_system = info.create_system
    entry.comment = info.comment
    out.writestr(entry, data)


def _copy_raw(src, out: zipfile.ZipFile, info: zipfile.ZipInfo) -> None:
    """Copy one entry's compressed bytes unchanged. zipfile has no public raw copy, so this
    writes the local header itself and registers the entry in ``out`` the way ``writestr`` does
    (``filelist``, ``NameToInfo``, ``start_dir``); tests compare the result entry by entry."""
    src.seek(info.header_offset)
    header = src.read(_LOCAL_HEADER)
    if len(header) != _LOCAL_HEADER or header[:4] != b"PK\x03\x04":
        raise PackageError(f"{info.filename}: no local header where the directory says")
    name_len, extra_len = struct.unpack("<HH", header[26:30])
    src.seek(info.header_offset + _LOCAL_HEADER + name_len + extra_len)
    raw = src.read(info.compress_size)
    if len(raw) != info.compress_size:
        raise PackageError(f"{info.filename}: the archive ends inside this entry")
    entry = copy.copy(info)
    entry.flag_bits &= ~_DATA_DESCRIPTOR   # sizes and CRC go into the local header instead
    entry.header_offset = out.fp.tell()
    out.fp.write(entry.FileHeader())
    out.fp.write(raw)
    out.filelist.append(entry)
    out.NameToInfo[entry.filename] = entry
    out.start_dir = out.fp.tell()
    out._didModify = True


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass
