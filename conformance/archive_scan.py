"""List the entries of an FMU (ZIP archive or unpacked folder) and decide which are safe to use.

:func:`scan` looks at every entry's name, type and declared size before anything is read, and
sorts the entries into usable members and excluded ones, with a violation for each problem (see
:mod:`conformance.fmu` for the pseudo-rules). It reads no member data: :mod:`conformance.fmu`
builds the ``FmuSource`` (:mod:`conformance.archive_source`) from the :class:`ScanResult`, which
reads, bounded by the same limits.
"""
from __future__ import annotations

import logging
import os
import stat
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from conformance.archive_base import (
    COMPRESSION,
    DUPLICATE,
    TOO_LARGE,
    UNREADABLE,
    UNSAFE_PATH,
    ArchiveLimits,
    Member,
    archive_violation,
    describe_error,
    is_within,
    normalise_name,
    show_name,
    unsafe_reason,
)
from conformance.findings import Location, Violation, evidence

log = logging.getLogger(__name__)

_ALLOWED_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
_DECODABLE_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA)
_METHOD_NAMES = {0: "stored", 1: "shrink", 6: "implode", 8: "deflate", 9: "deflate64",
                 12: "bzip2", 14: "lzma", 93: "zstd", 95: "xz", 98: "ppmd", 99: "AES"}
_LOCAL_HEADER_SIZE = 30


@dataclass(slots=True)
class ScanResult:
    """What :func:`scan` found. ``kind`` is None when nothing in the FMU can be used.

    For a ZIP archive ``zf`` is the open archive, which the caller must close (an
    :class:`~conformance.fmu.FmuSource` takes it over); for a folder ``root`` is its real path.
    """

    kind: str | None
    violations: list[Violation]
    members: dict[str, Member]
    excluded: dict[str, str]
    zf: zipfile.ZipFile | None = None
    root: str | None = None


def _unusable(*violations: Violation) -> ScanResult:
    return ScanResult(None, list(violations), {}, {})


def scan(path: Path, limits: ArchiveLimits) -> ScanResult:
    """List an FMU (a ZIP archive, whatever its extension, or an unpacked folder).

    Raises only for unexpected failures, which :func:`conformance.fmu.open_fmu` turns into a
    violation; everything the FMU itself gets wrong comes back as violations.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return _unusable(archive_violation(UNREADABLE, "the FMU does not exist (no such file or "
                                                       "folder)"))
    except OSError as exc:
        return _unusable(archive_violation(UNREADABLE,
                                           f"the FMU cannot be accessed: {describe_error(exc)}"))
    if stat.S_ISDIR(st.st_mode):
        return _scan_folder(path, limits)
    if not stat.S_ISREG(st.st_mode):
        return _unusable(archive_violation(UNREADABLE,
                                           "the FMU is neither a regular file nor a folder"))
    if st.st_size == 0:
        return _unusable(archive_violation(UNREADABLE,
                                           "the FMU is an empty file, not a ZIP archive"))
    with open(path, "rb") as fh:
        head = fh.read(4)
    if head == b"PK\x07\x08":
        return _unusable(archive_violation(UNREADABLE, "the FMU is a split or spanned ZIP "
                                                       "archive, which FMI does not allow (AR-02)"))
    if head not in (b"PK\x03\x04", b"PK\x05\x06"):
        hint = " (it looks like XML)" if head.lstrip().startswith(b"<") else ""
        return _unusable(archive_violation(
            UNREADABLE, f"the FMU is not a ZIP archive{hint}: it starts with bytes "
            f"{head.hex(' ')}, not 'PK'", first_bytes=head.hex()))
    return _scan_zip(path, limits)


# -- listing: what both readers share -------------------------------------------------------


class _Inventory:
    """The usable members found so far, the excluded ones, and the violations about them."""

    def __init__(self, limits: ArchiveLimits):
        self.limits = limits
        self.members: dict[str, Member] = {}
        self.raw_names: dict[str, str] = {}
        self.dirs: set[str] = set()
        self.excluded: dict[str, str] = {}
        self.violations: list[Violation] = []
        self.total = 0

    def report(self, rule: str, message: str, raw: str, **ev: Any) -> None:
        self.violations.append(_member_violation(rule, message, raw, **ev))

    def exclude(self, rule: str, message: str, raw: str, **ev: Any) -> None:
        self.report(rule, message, raw, **ev)
        self.excluded[show_name(raw)] = rule

    def add(self, raw: str, size: int, ref: Any, *, executable: bool) -> None:
        if size > self.limits.max_member:
            self.exclude(TOO_LARGE, f"{{subject}} is {size} bytes uncompressed, more than the "
                         f"per-member limit of {self.limits.max_member} bytes", raw,
                         size=size, limit=self.limits.max_member)
            return
        name = normalise_name(raw)
        if name in self.members:
            first = self.raw_names[name]
            how = ("occurs more than once" if first == raw else
                   f"is the same name as '{show_name(first)}' once normalised")
            self.report(DUPLICATE, f"{{subject}} {how}; importers disagree on which copy they "
                        "use (lsdae reads the last one)", raw)
        self.members[name] = Member(name, size, ref, executable)
        self.raw_names[name] = raw

    def finish(self) -> None:
        by_fold: dict[str, list[str]] = {}
        for name in self.members:
            by_fold.setdefault(name.casefold(), []).append(name)
        for names in by_fold.values():
            if len(names) > 1:
                others = ", ".join(f"'{show_name(n)}'" for n in sorted(names)[1:])
                self.report(DUPLICATE, f"{{subject}} and {others} differ only in letter case; "
                            "they overwrite each other when extracted on Windows or macOS",
                            sorted(names)[0], names=[show_name(n) for n in sorted(names)])
        parents = set(self.dirs)
        for name in self.members:
            parts = name.split("/")
            parents.update("/".join(parts[:i]) for i in range(1, len(parts)))
        for name in sorted(self.members):
            if name in parents:
                self.report(DUPLICATE, "{subject} is both a file and a folder; it cannot be "
                            "extracted", name)
        if self.total > self.limits.max_total_uncompressed:
            self.violations.append(archive_violation(
                TOO_LARGE, f"the entries add up to {self.total} bytes uncompressed, more than the "
                f"limit of {self.limits.max_total_uncompressed} bytes",
                total=self.total, limit=self.limits.max_total_uncompressed))


def _too_many(count: int, limits: ArchiveLimits) -> Violation:
    return archive_violation(TOO_LARGE, f"the FMU has {count} or more entries, more than the "
                             f"limit of {limits.max_members}; it is not checked further",
                             entries=count, limit=limits.max_members)


def _member_violation(rule: str, message: str, name: str, **ev: Any) -> Violation:
    """A violation about one entry; its (escaped) name is the subject, so the engine can group."""
    return Violation(message, Location(), evidence(ev), subject=show_name(name), rule=rule)


# -- ZIP archives ------------------------------------------------------------------------------


def _scan_zip(path: Path, limits: ArchiveLimits) -> ScanResult:
    try:
        zf = zipfile.ZipFile(path)
    except Exception as exc:  # BadZipFile, truncated, bad encoding of names, unsupported version
        return _unusable(archive_violation(
            UNREADABLE, f"the FMU is not a readable ZIP archive: {describe_error(exc)}",
            error=type(exc).__name__))
    try:
        infos = zf.infolist()
        if len(infos) > limits.max_members:
            zf.close()
            return _unusable(_too_many(len(infos), limits))
        inventory = _Inventory(limits)
        for info in infos:
            _inspect_zip_entry(inventory, info)
        _check_overlaps(inventory, infos, getattr(zf, "start_dir", None))
        inventory.finish()
    except BaseException:
        zf.close()
        raise
    return ScanResult("zip", inventory.violations, inventory.members, inventory.excluded, zf=zf)


def _inspect_zip_entry(inv: _Inventory, info: zipfile.ZipInfo) -> None:
    raw = info.orig_filename
    inv.total += info.file_size
    reason = unsafe_reason(raw)
    if reason:
        inv.exclude(UNSAFE_PATH, "{subject} " + reason, raw)
        return
    mode = info.external_attr >> 16
    kind = stat.S_IFMT(mode)
    if kind == stat.S_IFLNK:
        inv.exclude(UNSAFE_PATH, "{subject} is a symbolic link; FMI forbids links in the archive "
                    "(AR-02), and it is never followed", raw, mode=oct(mode))
        return
    if kind and kind not in (stat.S_IFREG, stat.S_IFDIR):
        inv.exclude(UNSAFE_PATH, "{subject} is a special file (device, FIFO or socket), not a "
                    "regular file", raw, mode=oct(mode))
        return
    if info.is_dir() or not normalise_name(raw):
        inv.dirs.add(normalise_name(raw))
        return
    if info.flag_bits & 0x1:
        inv.exclude(UNREADABLE, "{subject} is encrypted; FMI forbids encryption (AR-02)", raw)
        return
    if info.volume:
        inv.exclude(UNREADABLE, "{subject} lies on another disk of a split archive, which FMI "
                    "does not allow (AR-02)", raw)
        return
    method = info.compress_type
    if method not in _ALLOWED_METHODS:
        label = f"{method} ({_METHOD_NAMES.get(method, 'unknown')})"
        inv.report(COMPRESSION, f"{{subject}} uses compression method {label}; FMI allows only "
                   "stored (0) and deflate (8)", raw, method=method)
        if method not in _DECODABLE_METHODS:
            inv.exclude(UNREADABLE, f"{{subject}} cannot be read: compression method {label} is "
                        "not supported", raw, method=method)
            return
    size, packed = info.file_size, info.compress_size
    if size > inv.limits.ratio_min_size and size > inv.limits.max_ratio * packed:
        ratio = size / packed if packed else float("inf")
        inv.exclude(TOO_LARGE, f"{{subject}} expands {ratio:.0f} times ({packed} bytes to {size}), "
                    f"more than the limit of {inv.limits.max_ratio:g}: a zip bomb", raw,
                    compressed=packed, uncompressed=size, limit=inv.limits.max_ratio)
        return
    inv.add(raw, size, info, executable=bool(mode & 0o111))


def _check_overlaps(inv: _Inventory, infos: list[zipfile.ZipInfo], start_dir: int | None) -> None:
    """Exclude entries whose data overlaps another's: that is how the worst zip bombs work."""
    ordered = sorted(infos, key=lambda i: i.header_offset)
    bounds = [(i, i.header_offset + _LOCAL_HEADER_SIZE + _raw_name_length(i) + i.compress_size)
              for i in ordered]
    for (info, end), (after, _) in zip(bounds, bounds[1:]):
        if after.header_offset < end:
            _drop(inv, after, TOO_LARGE, "{subject} overlaps the data of another entry "
                  f"('{show_name(info.orig_filename)}'); overlapping entries are a zip-bomb "
                  "technique")
    if bounds and start_dir is not None and bounds[-1][1] > start_dir:
        _drop(inv, bounds[-1][0], UNREADABLE, "{subject} cannot be read: its data runs into the "
              "central directory (the archive is corrupt)")


def _drop(inv: _Inventory, info: zipfile.ZipInfo, rule: str, message: str) -> None:
    name = normalise_name(info.orig_filename)
    member = inv.members.get(name)
    if member is not None and member.ref is info:
        del inv.members[name]
        inv.exclude(rule, message, info.orig_filename)


def _raw_name_length(info: zipfile.ZipInfo) -> int:
    encoding = "utf-8" if info.flag_bits & 0x800 else "cp437"
    try:
        return len(info.orig_filename.encode(encoding))
    except UnicodeEncodeError:
        return len(info.orig_filename)


# -- unpacked folders --------------------------------------------------------------------------


def _scan_folder(path: Path, limits: ArchiveLimits) -> ScanResult:
    root = os.path.realpath(path)
    inv = _Inventory(limits)
    pending = [""]
    count = 0
    while pending:
        rel_dir = pending.pop()
        directory = os.path.join(root, *rel_dir.split("/")) if rel_dir else root
        try:
            with os.scandir(directory) as it:
                entries = sorted(it, key=lambda e: e.name)
        except OSError as exc:
            inv.report(UNREADABLE, f"{{subject}} cannot be listed: {describe_error(exc)}",
                       rel_dir or ".")
            continue
        for entry in entries:
            count += 1
            if count > limits.max_members:
                return _unusable(*inv.violations, _too_many(count, limits))
            rel = f"{rel_dir}/{entry.name}" if rel_dir else entry.name
            try:
                _inspect_folder_entry(inv, root, rel, entry, pending)
            except OSError as exc:
                inv.exclude(UNREADABLE, f"{{subject}} cannot be read: {describe_error(exc)}", rel)
    inv.finish()
    return ScanResult("folder", inv.violations, inv.members, inv.excluded, root=root)


def _inspect_folder_entry(inv: _Inventory, root: str, rel: str, entry: os.DirEntry[str],
                          pending: list[str]) -> None:
    reason = unsafe_reason(entry.name)
    if reason:
        inv.exclude(UNSAFE_PATH, "{subject} " + reason, rel)
        return
    if entry.is_symlink():
        target = os.path.realpath(entry.path)
        if not is_within(target, root):
            inv.exclude(UNSAFE_PATH, "{subject} is a symbolic link to a place outside the FMU "
                        "folder; it is never followed", rel, target=show_name(target))
        elif os.path.isfile(target):
            st = os.stat(target)
            inv.total += st.st_size
            inv.add(rel, st.st_size, entry.path, executable=bool(st.st_mode & 0o111))
        else:
            log.info("%s: symbolic link to a folder or to nothing, not followed", show_name(rel))
        return
    if entry.is_dir(follow_symlinks=False):
        inv.dirs.add(normalise_name(rel))
        pending.append(rel)
        return
    st = entry.stat(follow_symlinks=False)
    if not stat.S_ISREG(st.st_mode):
        inv.exclude(UNSAFE_PATH, "{subject} is a special file (device, FIFO or socket), not a "
                    "regular file", rel, mode=oct(st.st_mode))
        return
    inv.total += st.st_size
    inv.add(rel, st.st_size, entry.path, executable=bool(st.st_mode & 0o111))
