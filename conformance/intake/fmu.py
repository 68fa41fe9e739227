"""Open an FMU, a ZIP archive or an unpacked folder, without trusting anything in it.

:func:`open_fmu` inspects every entry before anything is read and reports, each as its own
pseudo-rule: unsafe paths and links (``unsafe-archive-path``), entries that share a name
(``archive-duplicate-entry``), zip bombs and oversized members (``archive-too-large``), archives
or entries that cannot be read (``archive-unreadable``) and compression methods FMI does not
allow (``archive-compression-method``). Unsafe, oversized and undecodable entries are left out of
:meth:`FmuSource.names`; everything else stays usable so the check goes on. The listing itself
lives in :mod:`conformance.intake.archive.scan`, the reading in
:mod:`conformance.intake.archive.source`; this module is the public API.

Reading is bounded twice: declared sizes are checked when the archive is opened, and every read
counts the bytes actually decompressed and stops at the limit. Nothing is written anywhere except
by :meth:`FmuSource.extract_to`, and only into a private temporary directory.
"""
from __future__ import annotations

import logging
from pathlib import Path

from conformance.intake.archive.base import (
    COMPRESSION,
    DUPLICATE,
    TOO_LARGE,
    UNREADABLE,
    UNSAFE_PATH,
    ArchiveLimits,
    GiB,
    MiB,
    archive_violation,
    describe_error,
)
from conformance.intake.archive.scan import scan
from conformance.intake.archive.source import ArchiveReadError, FmuSource
from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Violation

__all__ = [
    "COMPRESSION",
    "DUPLICATE",
    "MANIFEST",
    "MANIFEST_BASENAME",
    "MODEL_DESCRIPTION",
    "TOO_LARGE",
    "UNREADABLE",
    "UNSAFE_PATH",
    "ArchiveLimits",
    "ArchiveReadError",
    "FmuSource",
    "GiB",
    "MiB",
    "default_limits",
    "find_manifest_candidates",
    "open_fmu",
]

log = logging.getLogger(__name__)

MODEL_DESCRIPTION = "modelDescription.xml"
MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
MANIFEST_BASENAME = "fmi-ls-manifest.xml"


def default_limits() -> ArchiveLimits:
    """The limits the catalogue's ``archive-too-large`` options give by default."""
    return ArchiveLimits.from_options(default_catalogue()[TOO_LARGE].option_values)


def open_fmu(path: Path, *, limits: ArchiveLimits | None = None
             ) -> tuple[FmuSource | None, list[Violation]]:
    """Open an FMU (a ZIP archive, whatever its extension, or an unpacked folder).

    ``limits`` default to the catalogue's (:func:`default_limits`). Returns the source, or None
    when nothing in it can be used, and the violations found while listing it. Never raises for
    anything the FMU contains.
    """
    if limits is None:
        limits = default_limits()
    try:
        return _open(Path(path), limits)
    except Exception as exc:  # a last resort: the FMU must never crash the checker
        log.debug("open_fmu(%s) failed", path, exc_info=True)
        return None, [archive_violation(UNREADABLE,
                                        f"the FMU cannot be opened: {describe_error(exc)}",
                                        part="path-or-system-error")]


def find_manifest_candidates(source: FmuSource) -> list[str]:
    """Files named like a layered-standard manifest (any letter case) other than :data:`MANIFEST`.

    Under ``extra/`` these may belong to other layered standards; anywhere else they are misplaced.
    """
    return [n for n in source.names()
            if n != MANIFEST and n.rsplit("/", 1)[-1].casefold() == MANIFEST_BASENAME]


def _open(path: Path, limits: ArchiveLimits) -> tuple[FmuSource | None, list[Violation]]:
    found = scan(path, limits)
    if found.kind is None:
        return None, found.violations
    return (FmuSource(found.kind, path, found.members, found.excluded, limits,
                      zf=found.zf, root=found.root), found.violations)

