"""What listing and reading an FMU share: pseudo-rule names, limits, members, entry names.

:mod:`conformance.intake.archive.scan` lists the entries and
:mod:`conformance.intake.archive.source` reads them; both import this module and it imports neither,
so there is no import cycle. The rule names and :class:`ArchiveLimits` are re-exported by
:mod:`conformance.intake.fmu`; callers import them from there.
"""
from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

from conformance.report.findings import Location, Violation, evidence

UNREADABLE = "archive-unreadable"
UNSAFE_PATH = "unsafe-archive-path"
DUPLICATE = "archive-duplicate-entry"
TOO_LARGE = "archive-too-large"
COMPRESSION = "archive-compression-method"

MiB = 1 << 20
GiB = 1 << 30
_DRIVE = re.compile(r"^[A-Za-z]:")


@dataclass(frozen=True, slots=True)
class ArchiveLimits:
    """Bounds on what reading an FMU may cost; the catalogue options of ``archive-too-large``.

    No defaults here: the catalogue is the one place they are written
    (:func:`conformance.intake.fmu.default_limits` reads them).
    """

    max_total_uncompressed: int
    max_member: int
    max_ratio: float
    ratio_min_size: int  # the ratio limit applies only to members larger than this
    max_members: int

    @classmethod
    def from_options(cls, options: Mapping[str, Any]) -> ArchiveLimits:
        """Build limits from catalogue options: every limit must be given, other keys are ignored."""
        values: dict[str, Any] = {}
        for f in fields(cls):
            if f.name not in options:
                raise ValueError(f"archive limit {f.name} is missing from the options")
            value = float(options[f.name]) if f.name == "max_ratio" else int(options[f.name])
            if value <= 0:
                raise ValueError(f"archive limit {f.name} must be positive, got {value}")
            values[f.name] = value
        return cls(**values)


@dataclass(frozen=True, slots=True)
class Member:
    """A usable entry of the FMU."""

    name: str        # normalised name, as listed by FmuSource.names()
    size: int        # declared (zip) or on-disk (folder) size
    ref: Any         # the ZipInfo, or the absolute file-system path
    executable: bool = False


def archive_violation(rule: str, message: str, *, part: str | None = None,
                      **ev: Any) -> Violation:
    """A violation about the FMU as a whole; ``part`` names the sub-check of ``rule`` (catalogue
    ``[[rule.parts]]``), if any."""
    return Violation(message, Location(), evidence(ev), rule=rule, part=part)


def show_name(name: str, limit: int = 200) -> str:
    """A name safe to print: control and unprintable characters escaped, length bounded."""
    out = "".join(c if c.isprintable() else
                  (f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}") for c in name)
    return out if len(out) <= limit else out[:limit] + "..."


def normalise_name(name: str) -> str:
    """NFC, forward slashes only as given, no empty or '.' components."""
    name = unicodedata.normalize("NFC", name)
    return "/".join(p for p in name.split("/") if p not in ("", "."))


class Unsafe(NamedTuple):
    """Why an entry name is unsafe, and the part of ``unsafe-archive-path`` it falls under."""

    reason: str
    part: str | None = None


def unsafe_reason(raw: str) -> Unsafe | None:
    """Why an entry name is unsafe to extract or ambiguous between platforms, or None.

    A name fmusim rejects too (it starts with '.' or '/' or contains a backslash) is the rule's
    own case; any other unsafe name (a drive letter, an inner '..', NUL or control characters,
    an empty name) is the part ``other-unsafe-name``.
    """
    reason = _unsafe_text(raw)
    if reason is None:
        return None
    if raw.startswith((".", "/")) or "\\" in raw:
        return Unsafe(reason)
    return Unsafe(reason, part="other-unsafe-name")


def _unsafe_text(raw: str) -> str | None:
    if raw in ("", "/"):
        return "has an empty name"
    if "\x00" in raw:
        return "contains a NUL character, which truncates the name in some extractors"
    if "\\" in raw:
        return "uses a backslash; ZIP entry names must use forward slashes (AR-03)"
    if raw.startswith("/"):
        return "is an absolute path; entry names must be relative (AR-03)"
    if _DRIVE.match(raw):
        return "starts with a drive letter; entry names must be relative (AR-03)"
    if ".." in raw.split("/"):
        return "has a '..' component that points outside the extraction folder"
    if any(not c.isprintable() and c != " " for c in raw):
        return "contains control characters"
    return None


def describe_error(exc: BaseException) -> str:
    """An exception as text for a message: the OS error text, or the text and the type."""
    text = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror
    return f"{text} ({type(exc).__name__})" if not isinstance(exc, OSError) else text


def is_within(target: str, root: str) -> bool:
    """Whether the absolute path ``target`` is ``root`` or lies below it."""
    try:
        return os.path.commonpath([target, root]) == root
    except ValueError:  # different drives on Windows
        return False
