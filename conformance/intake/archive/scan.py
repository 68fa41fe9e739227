"""List the entries of an FMU (ZIP archive or unpacked folder) and decide which are safe to use.

:func:`scan` looks at every entry's name, type and declared size before anything is read, and
sorts the entries into usable members and excluded ones, with a violation for each problem (see
:mod:`conformance.intake.fmu` for the pseudo-rules). It reads no member data:
:mod:`conformance.intake.fmu` builds the ``FmuSource`` (:mod:`conformance.intake.archive.source`)
from the :class:`ScanResult`, which reads, bounded by the same limits. This module tells a folder
from a ZIP archive; the listing itself is in :mod:`conformance.intake.archive.zipped` and
:mod:`conformance.intake.archive.folder`.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from conformance.intake.archive.base import (UNREADABLE, ArchiveLimits, archive_violation,
                                             describe_error)
from conformance.intake.archive.folder import scan_folder
from conformance.intake.archive.inventory import ScanResult, unusable
from conformance.intake.archive.zipped import scan_zip


def scan(path: Path, limits: ArchiveLimits) -> ScanResult:
    """List an FMU (a ZIP archive, whatever its extension, or an unpacked folder).

    Raises only for unexpected failures, which :func:`conformance.intake.fmu.open_fmu` turns into a
    violation; everything the FMU itself gets wrong comes back as violations.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return unusable(archive_violation(UNREADABLE, "the FMU does not exist (no such file or "
                                                      "folder)", part="path-or-system-error"))
    except OSError as exc:
        return unusable(archive_violation(UNREADABLE,
                                          f"the FMU cannot be accessed: {describe_error(exc)}",
                                          part="path-or-system-error"))
    if stat.S_ISDIR(st.st_mode):
        return scan_folder(path, limits)
    if not stat.S_ISREG(st.st_mode):
        return unusable(archive_violation(UNREADABLE,
                                          "the FMU is neither a regular file nor a folder"))
    if st.st_size == 0:
        return unusable(archive_violation(UNREADABLE,
                                          "the FMU is an empty file, not a ZIP archive"))
    with open(path, "rb") as fh:
        head = fh.read(4)
    if head == b"PK\x07\x08":
        return unusable(archive_violation(UNREADABLE, "the FMU is a split or spanned ZIP "
                                                      "archive, which FMI does not allow (AR-02)",
                                          part="split-or-spanned"))
    if head not in (b"PK\x03\x04", b"PK\x05\x06"):
        hint = " (it looks like XML)" if head.lstrip().startswith(b"<") else ""
        return unusable(archive_violation(
            UNREADABLE, f"the FMU is not a ZIP archive{hint}: it starts with bytes "
            f"{head.hex(' ')}, not 'PK'", first_bytes=head.hex()))
    return scan_zip(path, limits)
