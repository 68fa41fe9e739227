"""List the entries of a ZIP archive: names, types, flags, compression, sizes and overlaps.

Nothing is read but the central directory: every entry is judged by what it declares, and
entries whose data overlap another's (the worst zip bombs) are left out.
"""
from __future__ import annotations

import stat
import zipfile
from pathlib import Path

from conformance.intake.archive.base import (
    COMPRESSION,
    TOO_LARGE,
    UNREADABLE,
    UNSAFE_PATH,
    ArchiveLimits,
    archive_violation,
    describe_error,
    normalise_name,
    show_name,
    unsafe_reason,
)
from conformance.intake.archive.inventory import Inventory, ScanResult, too_many, unusable

_ALLOWED_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
_DECODABLE_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA)
_METHOD_NAMES = {0: "stored", 1: "shrink", 6: "implode", 8: "deflate", 9: "deflate64",
                 12: "bzip2", 14: "lzma", 93: "zstd", 95: "xz", 98: "ppmd", 99: "AES"}
_LOCAL_HEADER_SIZE = 30


def scan_zip(path: Path, limits: ArchiveLimits) -> ScanResult:
    try:
        zf = zipfile.ZipFile(path)
    except Exception as exc:  # BadZipFile, truncated, bad encoding of names, unsupported version
        return unusable(archive_violation(
            UNREADABLE, f"the FMU is not a readable ZIP archive: {describe_error(exc)}",
            error=type(exc).__name__))
    try:
        infos = zf.infolist()
        if len(infos) > limits.max_members:
            zf.close()
            return unusable(too_many(len(infos), limits))
        inventory = Inventory(limits)
        for info in infos:
            _inspect_zip_entry(inventory, info)
        _check_overlaps(inventory, infos, getattr(zf, "start_dir", None))
        inventory.finish()
    except BaseException:
        zf.close()
        raise
    return ScanResult("zip", inventory.violations, inventory.members, inventory.excluded, zf=zf)


def _inspect_zip_entry(inv: Inventory, info: zipfile.ZipInfo) -> None:
    raw = info.orig_filename
    inv.total += info.file_size
    unsafe = unsafe_reason(raw)
    if unsafe:
        inv.exclude(UNSAFE_PATH, "{subject} " + unsafe.reason, raw, part=unsafe.part)
        return
    mode = info.external_attr >> 16
    kind = stat.S_IFMT(mode)
    if kind == stat.S_IFLNK:
        inv.exclude(UNSAFE_PATH, "{subject} is a symbolic link; FMI forbids links in the archive "
                    "(AR-02), and it is never followed", raw, mode=oct(mode), part="link-entry")
        return
    if kind and kind not in (stat.S_IFREG, stat.S_IFDIR):
        inv.exclude(UNSAFE_PATH, "{subject} is a special file (device, FIFO or socket), not a "
                    "regular file", raw, mode=oct(mode), part="special-file")
        return
    if info.is_dir() or not normalise_name(raw):
        inv.dirs.add(normalise_name(raw))
        return
    if info.flag_bits & 0x1:
        inv.exclude(UNREADABLE, "{subject} is encrypted; FMI forbids encryption (AR-02)", raw,
                    part="encrypted-entry")
        return
    if info.volume:
        inv.exclude(UNREADABLE, "{subject} lies on another disk of a split archive, which FMI "
                    "does not allow (AR-02)", raw, part="split-or-spanned")
        return
    method = info.compress_type
    if method not in _ALLOWED_METHODS:
        label = f"{method} ({_METHOD_NAMES.get(method, 'unknown')})"
        inv.report(COMPRESSION, f"{{subject}} uses compression method {label}; FMI allows only "
                   "stored (0) and deflate (8)", raw, method=method)
        if method not in _DECODABLE_METHODS:
            inv.exclude(UNREADABLE, f"{{subject}} cannot be read: compression method {label} is "
                        "not supported", raw, method=method, part="undecodable-method")
            return
    size, packed = info.file_size, info.compress_size
    if size > inv.limits.ratio_min_size and size > inv.limits.max_ratio * packed:
        ratio = size / packed if packed else float("inf")
        inv.exclude(TOO_LARGE, f"{{subject}} expands {ratio:.0f} times ({packed} bytes to {size}), "
                    f"more than the limit of {inv.limits.max_ratio:g}: a zip bomb", raw,
                    compressed=packed, uncompressed=size, limit=inv.limits.max_ratio)
        return
    inv.add(raw, size, info, executable=bool(mode & 0o111))


def _check_overlaps(inv: Inventory, infos: list[zipfile.ZipInfo], start_dir: int | None) -> None:
    """Exclude entries whose data overlaps another's: that is how the worst zip bombs work."""
    ordered = sorted(infos, key=lambda i: i.header_offset)
    bounds = [(i, i.header_offset + _LOCAL_HEADER_SIZE + _raw_name_length(i) + i.compress_size)
              for i in ordered]
    for (info, end), (after, _) in zip(bounds, bounds[1:]):
        if after.header_offset < end:
            _drop(inv, after, TOO_LARGE, "{subject} overlaps the data of another entry "
                  f"('{show_name(info.orig_filename)}'); overlapping entries are a zip-bomb "
                  "technique", part="overlapping-entries")
    if bounds and start_dir is not None and bounds[-1][1] > start_dir:
        _drop(inv, bounds[-1][0], UNREADABLE, "{subject} cannot be read: its data runs into the "
              "central directory (the archive is corrupt)")


def _drop(inv: Inventory, info: zipfile.ZipInfo, rule: str, message: str, *,
          part: str | None = None) -> None:
    name = normalise_name(info.orig_filename)
    member = inv.members.get(name)
    if member is not None and member.ref is info:
        del inv.members[name]
        inv.exclude(rule, message, info.orig_filename, part=part)


def _raw_name_length(info: zipfile.ZipInfo) -> int:
    encoding = "utf-8" if info.flag_bits & 0x800 else "cp437"
    try:
        return len(info.orig_filename.encode(encoding))
    except UnicodeEncodeError:
        return len(info.orig_filename)
