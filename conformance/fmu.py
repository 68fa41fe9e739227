"""Open an FMU, a ZIP archive or an unpacked folder, without trusting anything in it.

:func:`open_fmu` inspects every entry before anything is read and reports, each as its own
pseudo-rule: unsafe paths and links (``unsafe-archive-path``), entries that share a name
(``archive-duplicate-entry``), zip bombs and oversized members (``archive-too-large``), archives
or entries that cannot be read (``archive-unreadable``) and compression methods FMI does not
allow (``archive-compression-method``). Unsafe, oversized and undecodable entries are left out of
:meth:`FmuSource.names`; everything else stays usable so the check goes on.

Reading is bounded twice: declared sizes are checked when the archive is opened, and every read
counts the bytes actually decompressed and stops at the limit. Nothing is written anywhere except
by :meth:`FmuSource.extract_to`, and only into a private temporary directory.
"""
from __future__ import annotations

import logging
import os
import re
import stat
import tempfile
import unicodedata
import zipfile
from dataclasses import dataclass, fields
from pathlib import Path
from typing import IO, Any, Callable, Iterable, Mapping

from conformance.findings import Location, Violation, evidence

log = logging.getLogger(__name__)

MODEL_DESCRIPTION = "modelDescription.xml"
MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
MANIFEST_BASENAME = "fmi-ls-manifest.xml"

UNREADABLE = "archive-unreadable"
UNSAFE_PATH = "unsafe-archive-path"
DUPLICATE = "archive-duplicate-entry"
TOO_LARGE = "archive-too-large"
COMPRESSION = "archive-compression-method"

MiB = 1 << 20
GiB = 1 << 30
_CHUNK = MiB
_ALLOWED_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
_DECODABLE_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA)
_METHOD_NAMES = {0: "stored", 1: "shrink", 6: "implode", 8: "deflate", 9: "deflate64",
                 12: "bzip2", 14: "lzma", 93: "zstd", 95: "xz", 98: "ppmd", 99: "AES"}
_LOCAL_HEADER_SIZE = 30
_O_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_O_NONBLOCK = getattr(os, "O_NONBLOCK", 0)
_O_BINARY = getattr(os, "O_BINARY", 0)
_DRIVE = re.compile(r"^[A-Za-z]:")


@dataclass(frozen=True, slots=True)
class ArchiveLimits:
    """Bounds on what reading an FMU may cost; the catalogue options of ``archive-too-large``."""

    max_total_uncompressed: int = 2 * GiB
    max_member: int = 512 * MiB
    max_ratio: float = 1000.0
    ratio_min_size: int = 1 * MiB  # the ratio limit applies only to members larger than this
    max_members: int = 100_000

    @classmethod
    def from_options(cls, options: Mapping[str, Any]) -> ArchiveLimits:
        """Build limits from catalogue options, ignoring keys that are not limits."""
        values: dict[str, Any] = {}
        for f in fields(cls):
            if f.name in options:
                value = float(options[f.name]) if f.name == "max_ratio" else int(options[f.name])
                if value <= 0:
                    raise ValueError(f"archive limit {f.name} must be positive, got {value}")
                values[f.name] = value
        return cls(**values)


class ArchiveReadError(Exception):
    """A member could not be read; ``violation`` says why, with its rule set."""

    def __init__(self, reason: str, violation: Violation):
        super().__init__(reason)
        self.violation = violation


class _LimitExceeded(Exception):
    pass


@dataclass(frozen=True, slots=True)
class _Member:
    name: str        # normalised name, as listed by names()
    size: int        # declared (zip) or on-disk (folder) size
    ref: Any         # the ZipInfo, or the absolute file-system path
    executable: bool = False


class FmuSource:
    """An opened FMU: the safe members, readable with bounded cost. Use as a context manager."""

    def __init__(self, kind: str, path: Path, members: Mapping[str, _Member],
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
        return _normalise(name) in self._members

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
                                    Location(file=name), subject=_show(name), rule=UNREADABLE)]

    def extract_to(self, dest: Path, *, names: Iterable[str] | None = None) -> list[Violation]:
        """Write the safe members (or ``names`` among them) below ``dest`` and nowhere else.

        ``dest`` must be an empty directory private to this user inside the system temporary
        directory, as made by :func:`tempfile.mkdtemp`; anything else raises ValueError.
        """
        root = _private_destination(dest)
        wanted = self.names() if names is None else [_normalise(n) for n in names]
        budget = self.limits.max_total_uncompressed
        violations: list[Violation] = []
        for name in wanted:
            member = self._members.get(name)
            if member is None:
                continue
            target = os.path.join(root, *name.split("/"))
            if not _is_within(os.path.abspath(target), root):
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
                    Location(file=name), subject=_show(name), rule=UNREADABLE))
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

    def _member(self, name: str) -> _Member:
        member = self._members.get(_normalise(name))
        if member is None:
            raise KeyError(name)
        return member

    def _read_limit(self) -> int:
        return min(self.limits.max_member, self.limits.max_total_uncompressed)

    def _copy(self, member: _Member, sink: Callable[[bytes], Any], limit: int) -> int:
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
                subject=_show(member.name), rule=TOO_LARGE)) from None
        except Exception as exc:  # corrupt data, CRC mismatch, truncated file, I/O error
            reason = _describe(exc)
            raise ArchiveReadError(reason, Violation(
                "{subject} cannot be read: " + reason, where, evidence(error=type(exc).__name__),
                subject=_show(member.name), rule=UNREADABLE)) from exc

    def _open_stream(self, member: _Member) -> IO[bytes]:
        if self._zip is not None:
            return self._zip.open(member.ref)
        if self._root is None:
            raise ValueError("the FMU is closed")
        return _open_regular_file(member.ref, self._root)


def open_fmu(path: Path, *, limits: ArchiveLimits = ArchiveLimits()
             ) -> tuple[FmuSource | None, list[Violation]]:
    """Open an FMU (a ZIP archive, whatever its extension, or an unpacked folder).

    Returns the source, or None when nothing in it can be used, and the violations found while
    listing it. Never raises for anything the FMU contains.
    """
    try:
        return _open(Path(path), limits)
    except Exception as exc:  # a last resort: the FMU must never crash the checker
        log.debug("open_fmu(%s) failed", path, exc_info=True)
        return None, [_archive_violation(UNREADABLE, f"the FMU cannot be opened: {_describe(exc)}")]


def find_manifest_candidates(source: FmuSource) -> list[str]:
    """Files named like a layered-standard manifest (any letter case) other than :data:`MANIFEST`.

    Under ``extra/`` these may belong to other layered standards; anywhere else they are misplaced.
    """
    return [n for n in source.names()
            if n != MANIFEST and n.rsplit("/", 1)[-1].casefold() == MANIFEST_BASENAME]


def _open(path: Path, limits: ArchiveLimits) -> tuple[FmuSource | None, list[Violation]]:
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None, [_archive_violation(UNREADABLE, "the FMU does not exist (no such file or "
                                                     "folder)")]
    except OSError as exc:
        return None, [_archive_violation(UNREADABLE,
                                         f"the FMU cannot be accessed: {_describe(exc)}")]
    if stat.S_ISDIR(st.st_mode):
        return _open_folder(path, limits)
    if not stat.S_ISREG(st.st_mode):
        return None, [_archive_violation(UNREADABLE,
                                         "the FMU is neither a regular file nor a folder")]
    if st.st_size == 0:
        return None, [_archive_violation(UNREADABLE, "the FMU is an empty file, not a ZIP archive")]
    with open(path, "rb") as fh:
        head = fh.read(4)
    if head == b"PK\x07\x08":
        return None, [_archive_violation(UNREADABLE, "the FMU is a split or spanned ZIP archive, "
                                                     "which FMI does not allow (AR-02)")]
    if head not in (b"PK\x03\x04", b"PK\x05\x06"):
        hint = " (it looks like XML)" if head.lstrip().startswith(b"<") else ""
        return None, [_archive_violation(
            UNREADABLE, f"the FMU is not a ZIP archive{hint}: it starts with bytes "
            f"{head.hex(' ')}, not 'PK'", first_bytes=head.hex())]
    return _open_zip(path, limits)


# -- listing: what both readers share -------------------------------------------------------


class _Inventory:
    """The usable members found so far, the excluded ones, and the violations about them."""

    def __init__(self, limits: ArchiveLimits):
        self.limits = limits
        self.members: dict[str, _Member] = {}
        self.raw_names: dict[str, str] = {}
        self.dirs: set[str] = set()
        self.excluded: dict[str, str] = {}
        self.violations: list[Violation] = []
        self.total = 0

    def report(self, rule: str, message: str, raw: str, **ev: Any) -> None:
        self.violations.append(_member_violation(rule, message, raw, **ev))

    def exclude(self, rule: str, message: str, raw: str, **ev: Any) -> None:
        self.report(rule, message, raw, **ev)
        self.excluded[_show(raw)] = rule

    def add(self, raw: str, size: int, ref: Any, *, executable: bool) -> None:
        if size > self.limits.max_member:
            self.exclude(TOO_LARGE, f"{{subject}} is {size} bytes uncompressed, more than the "
                         f"per-member limit of {self.limits.max_member} bytes", raw,
                         size=size, limit=self.limits.max_member)
            return
        name = _normalise(raw)
        if name in self.members:
            first = self.raw_names[name]
            how = ("occurs more than once" if first == raw else
                   f"is the same name as '{_show(first)}' once normalised")
            self.report(DUPLICATE, f"{{subject}} {how}; importers disagree on which copy they "
                        "use (lsdae reads the last one)", raw)
        self.members[name] = _Member(name, size, ref, executable)
        self.raw_names[name] = raw

    def finish(self) -> None:
        by_fold: dict[str, list[str]] = {}
        for name in self.members:
            by_fold.setdefault(name.casefold(), []).append(name)
        for names in by_fold.values():
            if len(names) > 1:
                others = ", ".join(f"'{_show(n)}'" for n in sorted(names)[1:])
                self.report(DUPLICATE, f"{{subject}} and {others} differ only in letter case; "
                            "they overwrite each other when extracted on Windows or macOS",
                            sorted(names)[0], names=[_show(n) for n in sorted(names)])
        parents = set(self.dirs)
        for name in self.members:
            parts = name.split("/")
            parents.update("/".join(parts[:i]) for i in range(1, len(parts)))
        for name in sorted(self.members):
            if name in parents:
                self.report(DUPLICATE, "{subject} is both a file and a folder; it cannot be "
                            "extracted", name)
        if self.total > self.limits.max_total_uncompressed:
            self.violations.append(_archive_violation(
                TOO_LARGE, f"the entries add up to {self.total} bytes uncompressed, more than the "
                f"limit of {self.limits.max_total_uncompressed} bytes",
                total=self.total, limit=self.limits.max_total_uncompressed))


def _too_many(count: int, limits: ArchiveLimits) -> Violation:
    return _archive_violation(TOO_LARGE, f"the FMU has {count} or more entries, more than the "
                              f"limit of {limits.max_members}; it is not checked further",
                              entries=count, limit=limits.max_members)


# -- ZIP archives ------------------------------------------------------------------------------


def _open_zip(path: Path, limits: ArchiveLimits) -> tuple[FmuSource | None, list[Violation]]:
    try:
        zf = zipfile.ZipFile(path)
    except Exception as exc:  # BadZipFile, truncated, bad encoding of names, unsupported version
        return None, [_archive_violation(
            UNREADABLE, f"the FMU is not a readable ZIP archive: {_describe(exc)}",
            error=type(exc).__name__)]
    try:
        infos = zf.infolist()
        if len(infos) > limits.max_members:
            zf.close()
            return None, [_too_many(len(infos), limits)]
        inventory = _Inventory(limits)
        for info in infos:
            _inspect_zip_entry(inventory, info)
        _check_overlaps(inventory, infos, getattr(zf, "start_dir", None))
        inventory.finish()
    except BaseException:
        zf.close()
        raise
    return (FmuSource("zip", path, inventory.members, inventory.excluded, limits, zf=zf),
            inventory.violations)


def _inspect_zip_entry(inv: _Inventory, info: zipfile.ZipInfo) -> None:
    raw = info.orig_filename
    inv.total += info.file_size
    reason = _unsafe_reason(raw)
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
    if info.is_dir() or not _normalise(raw):
        inv.dirs.add(_normalise(raw))
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
                  f"('{_show(info.orig_filename)}'); overlapping entries are a zip-bomb technique")
    if bounds and start_dir is not None and bounds[-1][1] > start_dir:
        _drop(inv, bounds[-1][0], UNREADABLE, "{subject} cannot be read: its data runs into the "
              "central directory (the archive is corrupt)")


def _drop(inv: _Inventory, info: zipfile.ZipInfo, rule: str, message: str) -> None:
    name = _normalise(info.orig_filename)
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


def _open_folder(path: Path, limits: ArchiveLimits) -> tuple[FmuSource | None, list[Violation]]:
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
            inv.report(UNREADABLE, f"{{subject}} cannot be listed: {_describe(exc)}",
                       rel_dir or ".")
            continue
        for entry in entries:
            count += 1
            if count > limits.max_members:
                return None, inv.violations + [_too_many(count, limits)]
            rel = f"{rel_dir}/{entry.name}" if rel_dir else entry.name
            try:
                _inspect_folder_entry(inv, root, rel, entry, pending)
            except OSError as exc:
                inv.exclude(UNREADABLE, f"{{subject}} cannot be read: {_describe(exc)}", rel)
    inv.finish()
    return FmuSource("folder", path, inv.members, inv.excluded, limits, root=root), inv.violations


def _inspect_folder_entry(inv: _Inventory, root: str, rel: str, entry: os.DirEntry[str],
                          pending: list[str]) -> None:
    reason = _unsafe_reason(entry.name)
    if reason:
        inv.exclude(UNSAFE_PATH, "{subject} " + reason, rel)
        return
    if entry.is_symlink():
        target = os.path.realpath(entry.path)
        if not _is_within(target, root):
            inv.exclude(UNSAFE_PATH, "{subject} is a symbolic link to a place outside the FMU "
                        "folder; it is never followed", rel, target=_show(target))
        elif os.path.isfile(target):
            st = os.stat(target)
            inv.total += st.st_size
            inv.add(rel, st.st_size, entry.path, executable=bool(st.st_mode & 0o111))
        else:
            log.info("%s: symbolic link to a folder or to nothing, not followed", _show(rel))
        return
    if entry.is_dir(follow_symlinks=False):
        inv.dirs.add(_normalise(rel))
        pending.append(rel)
        return
    st = entry.stat(follow_symlinks=False)
    if not stat.S_ISREG(st.st_mode):
        inv.exclude(UNSAFE_PATH, "{subject} is a special file (device, FIFO or socket), not a "
                    "regular file", rel, mode=oct(st.st_mode))
        return
    inv.total += st.st_size
    inv.add(rel, st.st_size, entry.path, executable=bool(st.st_mode & 0o111))


# -- helpers shared by the zip and folder readers ---------------------------------------------


def _archive_violation(rule: str, message: str, **ev: Any) -> Violation:
    return Violation(message, Location(), evidence(ev), rule=rule)


def _member_violation(rule: str, message: str, name: str, **ev: Any) -> Violation:
    """A violation about one entry; its (escaped) name is the subject, so the engine can group."""
    return Violation(message, Location(), evidence(ev), subject=_show(name), rule=rule)


def _show(name: str, limit: int = 200) -> str:
    """A name safe to print: control and unprintable characters escaped, length bounded."""
    out = "".join(c if c.isprintable() else
                  (f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}") for c in name)
    return out if len(out) <= limit else out[:limit] + "..."


def _normalise(name: str) -> str:
    """NFC, forward slashes only as given, no empty or '.' components."""
    name = unicodedata.normalize("NFC", name)
    return "/".join(p for p in name.split("/") if p not in ("", "."))


def _unsafe_reason(raw: str) -> str | None:
    """Why an entry name is unsafe to extract or ambiguous between platforms, or None."""
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


def _describe(exc: BaseException) -> str:
    text = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror
    return f"{text} ({type(exc).__name__})" if not isinstance(exc, OSError) else text


def _is_within(target: str, root: str) -> bool:
    try:
        return os.path.commonpath([target, root]) == root
    except ValueError:  # different drives on Windows
        return False


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
    if not _is_within(real, root):
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
    if real == tmp or not _is_within(real, tmp):
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
