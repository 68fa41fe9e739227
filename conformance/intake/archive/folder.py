"""List the entries of an unpacked FMU folder: names, links, special files and sizes.

Symbolic links are never followed out of the folder; a link to a file inside it counts as that
file, a link to a folder is not followed at all.
"""
from __future__ import annotations

import logging
import os
import stat
from pathlib import Path

from conformance.intake.archive.base import (
    UNREADABLE,
    UNSAFE_PATH,
    ArchiveLimits,
    describe_error,
    is_within,
    normalise_name,
    show_name,
    unsafe_reason,
)
from conformance.intake.archive.inventory import Inventory, ScanResult, too_many, unusable

log = logging.getLogger(__name__)


def scan_folder(path: Path, limits: ArchiveLimits) -> ScanResult:
    root = os.path.realpath(path)
    inv = Inventory(limits)
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
                       rel_dir or ".", part="path-or-system-error")
            continue
        for entry in entries:
            count += 1
            if count > limits.max_members:
                return unusable(*inv.violations, too_many(count, limits))
            rel = f"{rel_dir}/{entry.name}" if rel_dir else entry.name
            try:
                _inspect_folder_entry(inv, root, rel, entry, pending)
            except OSError as exc:
                inv.exclude(UNREADABLE, f"{{subject}} cannot be read: {describe_error(exc)}", rel,
                            part="path-or-system-error")
    inv.finish()
    return ScanResult("folder", inv.violations, inv.members, inv.excluded, root=root)


def _inspect_folder_entry(inv: Inventory, root: str, rel: str, entry: os.DirEntry[str],
                          pending: list[str]) -> None:
    unsafe = unsafe_reason(entry.name)
    if unsafe:
        inv.exclude(UNSAFE_PATH, "{subject} " + unsafe.reason, rel, part=unsafe.part)
        return
    if entry.is_symlink():
        target = os.path.realpath(entry.path)
        if not is_within(target, root):
            inv.exclude(UNSAFE_PATH, "{subject} is a symbolic link to a place outside the FMU "
                        "folder; it is never followed", rel, target=show_name(target),
                        part="link-entry")
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
                    "regular file", rel, mode=oct(st.st_mode), part="special-file")
        return
    inv.total += st.st_size
    inv.add(rel, st.st_size, entry.path, executable=bool(st.st_mode & 0o111))
