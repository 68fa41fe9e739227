"""An opened FMU: its safe members, read and extracted with bounded cost (:class:`FmuSource`).

:func:`conformance.intake.fmu.open_fmu` builds it from what :mod:`conformance.intake.archive.scan`
listed. Every read counts the bytes actually decompressed and stops at the limit; a member that
cannot be read raises :class:`ArchiveReadError`, whose violation names the rule. Nothing is written
anywhere except by :meth:`FmuSource.extract_to`, and only into a private temporary directory.
"""
from __future__ import annotations

import os
import re
import stat
import tempfile
import zipfile
from pathlib import Path
from typing import IO, Any, Callable, Iterable, Mapping

from conformance.intake.archive.base import (
    TOO_LARGE,
    UNREADABLE,
    ArchiveLimits,
    Member,
    MiB,
    describe_error,
    is_within,
    normalise_name,
    show_name,
)
from conformance.report.findings import Location, Violation, evidence

_CHUNK = MiB
_O_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_O_NONBLOCK = getattr(os, "O_NONBLOCK", 0)
_O_BINARY = getattr(os, "O_BINARY", 0)


class ArchiveReadError(Exception):
    """A member could not be read; ``violation`` says why, with its rule set."""

    def __init__(self, reason: str, violation: Violation):
        super().__init__(reason)
        self.violation = violation


class _LimitExceeded(Exception):
    pass


class FmuSource:
    """An opened FMU: the safe members, readable with bounded cost. Use as a context manager."""

    def __init__(self, kind: str, path: Path, members: Mapping[str, Member],
                 excluded: Mapping[str, str], limits: ArchiveLimits,
                 zf: zipfile.ZipFile | None = None, root: str | None = None):
        self.kind = kind
        self.path = path
        self.limits = limits
        self._members = dict(members)
        self._excluded = dict(excluded)
        self._zip = zf
        self._root = root

    def names(self) -> list[str]:
        """Normalised names (forward slashes, NFC) of the usable files, sorted; no directories."""
        return sorted(self._members)

    def exists(self, name: str) -> bool:
        return normalise_name(name) in self._members

    def excluded(self) -> dict[str, str]:
        """Entries left out of :meth:`names` (escaped as in messages) and the rule that did it."""
        return dict(self._excluded)

    def size(self, name: str) -> int:
        """The declared (zip) or on-disk (folder) size of a member."""
        return self._member(name).size

    def find(self, pattern: str) -> list[str]:
        """Names matching a glob: ``*`` and ``?`` stay within one folder, ``**/`` spans folders."""
        regex = _glob_regex(pattern)
        return [n for n in self.names() if regex.match(n)]

    def read(self, name: str) -> bytes:
        """The member's bytes; KeyError if unknown, ArchiveReadError if it cannot be read."""
        member = self._member(name)
        chunks: list[bytes] = []
        self._copy(member, chunks.append, self._read_limit())
        return b"".join(chunks)

    def try_read(self, name: str) -> tuple[bytes | None, list[Violation]]:
        """Like :meth:`read`, but failures come back as violations."""
        try:
            return self.read(name), []
        except ArchiveReadError as exc:
            return None, [exc.violation]
        except KeyError:
            return None, [Violation("{subject} is not a usable member of the FMU",
                                    Location(file=name), subject=show_name(name), rule=UNREADABLE)]

    def extract_to(self, dest: Path, *, names: Iterable[str] | None = None) -> list[Violation]:
        """Write the safe members (or ``names`` among them) below ``dest`` and nowhere else.

        ``dest`` must be an empty directory private to this user inside the system temporary
        directory, as made by :func:`tempfile.mkdtemp`; anything else raises ValueError.
        """
        root = _private_destination(dest)
        wanted = self.names() if names is None else [normalise_name(n) for n in names]
        budget = self.limits.max_total_uncompressed
        violations: list[Violation] = []
        for name in wanted:
            member = self._members.get(name)
            if member is None:
                continue
            target = os.path.join(root, *name.split("/"))
            if not is_within(os.path.abspath(target), root):
                continue  # cannot happen for a normalised safe name; kept as a last guard
            try:
                _make_parents(root, name)
                mode = 0o700 if member.executable else 0o600
                flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | _O_BINARY
                fd = os.open(target, flags, mode)
                with os.fdopen(fd, "wb") as out:
                    budget -= self._copy(member, out.write, min(self.limits.max_member, budget))
            except ArchiveReadError as exc:
                _remove_quietly(target)
                violations.append(exc.violation)
                if exc.violation.rule == TOO_LARGE and budget <= self.limits.max_member:
                    break
            except OSError as exc:
                _remove_quietly(target)
                violations.append(Violation(
                    f"{{subject}} cannot be extracted: {exc.strerror or exc}",
                    Location(file=name), subject=show_name(name), rule=UNREADABLE,
                    part="path-or-system-error"))
        return violations

    def close(self) -> None:
        if self._zip is not None:
            self._zip.close()
            self._zip = None

    def __enter__(self) -> FmuSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"FmuSource({self.kind!r}, {str(self.path)!r}, {len(self._members)} members)"

    # -- reading ---------------------------------------------------------------------------

    def _member(self, name: str) -> Member:
        member = self._members.get(normalise_name(name))
        if member is None:
            raise KeyError(name)
        return member

    def _read_limit(self) -> int:
        return min(self.limits.max_member, self.limits.max_total_uncompressed)

    def _copy(self, member: Member, sink: Callable[[bytes], Any], limit: int) -> int:
        """Stream a member into ``sink``, counting the bytes really produced; returns the count."""
        where = Location(file=member.name)
        total = 0
        try:
            with self._open_stream(member) as stream:
                while True:
                    chunk = stream.read(_CHUNK)
                    if not chunk:
                        return total
                    total += len(chunk)
                    if total > limit:
                        raise _LimitExceeded
                    sink(chunk)
        except _LimitExceeded:
            reason = f"decompresses to more than {limit} bytes; reading stopped there"
            raise ArchiveReadError(reason, Violation(
                "{subject} " + reason, where, evidence(limit=limit, declared=member.size),
                subject=show_name(member.name), rule=TOO_LARGE)) from None
        except Exception as exc:  # corrupt data, CRC mismatch, truncated file, I/O error
            reason = describe_error(exc)
            raise ArchiveReadError(reason, Violation(
                "{subject} cannot be read: " + reason, where, evidence(error=type(exc).__name__),
                subject=show_name(member.name), rule=UNREADABLE)) from exc

    def _open_stream(self, member: Member) -> IO[bytes]:
        if self._zip is not None:
            return self._zip.open(member.ref)
        if self._root is None:
            raise ValueError("the FMU is closed")
        return _open_regular_file(member.ref, self._root)


# -- reading and extracting -------------------------------------------------------------------


def _glob_regex(pattern: str) -> re.Pattern[str]:
    out, i = [], 0
    while i < len(pattern):
        if pattern.startswith("**/", i):
            out.append("(?:[^/]*/)*")
            i += 3
        elif pattern.startswith("**", i):
            out.append(".*")
            i += 2
        else:
            c = pattern[i]
            out.append("[^/]*" if c == "*" else "[^/]" if c == "?" else re.escape(c))
            i += 1
    return re.compile("".join(out) + r"\Z", re.DOTALL)


def _open_regular_file(path: str, root: str) -> IO[bytes]:
    """Open a file inside ``root`` for reading, refusing links out of it and special files."""
    real = os.path.realpath(path)
    if not is_within(real, root):
        raise OSError(f"resolves to a place outside the FMU folder ({real})")
    fd = os.open(real, os.O_RDONLY | _O_NOFOLLOW | _O_NONBLOCK | _O_BINARY)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError("is not a regular file")
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def _private_destination(dest: Path) -> str:
    """Check that ``dest`` is an empty, private directory inside the temporary directory."""
    path = os.fspath(dest)
    if os.path.islink(path) or not os.path.isdir(path):
        raise ValueError(f"extract_to: {path} is not an existing directory")
    real = os.path.realpath(path)
    tmp = os.path.realpath(tempfile.gettempdir())
    if real == tmp or not is_within(real, tmp):
        raise ValueError(f"extract_to: {path} is not inside the temporary directory {tmp}")
    st = os.stat(real)
    if hasattr(os, "getuid") and (st.st_uid != os.getuid() or st.st_mode & 0o077):
        raise ValueError(f"extract_to: {path} is not private to this user (use tempfile.mkdtemp)")
    with os.scandir(real) as entries:
        if any(True for _ in entries):
            raise ValueError(f"extract_to: {path} is not empty")
    return real


def _make_parents(root: str, name: str) -> None:
    current = root
    for part in name.split("/")[:-1]:
        current = os.path.join(current, part)
        if not os.path.isdir(current) or os.path.islink(current):
            os.mkdir(current, 0o700)


def _remove_quietly(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
