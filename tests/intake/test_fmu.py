"""Opening hostile FMUs: each problem has its rule, the rest stays usable, nothing escapes tmp."""
from __future__ import annotations

import os
import shutil
import struct
import sys
import tempfile
import warnings
import zipfile
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conformance.report.catalogue import load_catalogue
from conformance.intake.fmu import (
    MANIFEST,
    MODEL_DESCRIPTION,
    ArchiveLimits,
    ArchiveReadError,
    FmuSource,
    default_limits,
    find_manifest_candidates,
    open_fmu,
)
from conformance.report.paths import rules_dir

MD = b'<?xml version="1.0" encoding="UTF-8"?>\n<fmiModelDescription/>\n'
SUPPRESS = [HealthCheck.function_scoped_fixture]  # tmp_path is reused; each example overwrites
EMITTED = {"archive-unreadable", "unsafe-archive-path", "archive-duplicate-entry",
           "archive-too-large", "archive-compression-method"}


def limits_with(**changes: int) -> ArchiveLimits:
    """The catalogue's limits with some of them changed."""
    return replace(default_limits(), **changes)


# -- building hostile archives -------------------------------------------------------------------


def make_zip(path: Path, entries: list[tuple[str | zipfile.ZipInfo, bytes]],
             method: int = zipfile.ZIP_DEFLATED) -> Path:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about duplicate names; that is the point
        with zipfile.ZipFile(path, "w", method) as zf:
            for name, data in entries:
                zf.writestr(name, data)
    return path


def patch_entry(path: Path, name: str, *, flags: int | None = None, method: int | None = None,
                size: int | None = None, external_attr: int | None = None,
                new_name: bytes | None = None) -> None:
    """Rewrite header fields that zipfile will not write for us, in local and central headers."""
    data = bytearray(path.read_bytes())
    raw = name.encode()
    pos = 0
    while (pos := data.find(b"PK\x03\x04", pos)) >= 0:
        nlen = struct.unpack_from("<H", data, pos + 26)[0]
        if bytes(data[pos + 30:pos + 30 + nlen]) == raw:
            if flags is not None:
                old = struct.unpack_from("<H", data, pos + 6)[0]
                struct.pack_into("<H", data, pos + 6, old | flags)
            if method is not None:
                struct.pack_into("<H", data, pos + 8, method)
            if size is not None:
                struct.pack_into("<I", data, pos + 22, size)
            if new_name is not None:
                data[pos + 30:pos + 30 + nlen] = new_name
        pos += 4
    pos = 0
    while (pos := data.find(b"PK\x01\x02", pos)) >= 0:
        nlen = struct.unpack_from("<H", data, pos + 28)[0]
        if bytes(data[pos + 46:pos + 46 + nlen]) == raw:
            if flags is not None:
                old = struct.unpack_from("<H", data, pos + 8)[0]
                struct.pack_into("<H", data, pos + 8, old | flags)
            if method is not None:
                struct.pack_into("<H", data, pos + 10, method)
            if size is not None:
                struct.pack_into("<I", data, pos + 24, size)
            if external_attr is not None:
                struct.pack_into("<I", data, pos + 38, external_attr)
            if new_name is not None:
                data[pos + 46:pos + 46 + nlen] = new_name
        pos += 4
    path.write_bytes(bytes(data))


def rules_of(violations) -> set[str]:
    return {v.rule for v in violations}


def by_rule(violations, rule: str) -> list:
    return [v for v in violations if v.rule == rule]


@pytest.fixture
def private_tmp():
    """A directory like the probes use: tempfile.mkdtemp, mode 0700."""
    path = Path(tempfile.mkdtemp(prefix="lsdae-test-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


# -- a clean FMU ----------------------------------------------------------------------------------


def test_clean_zip_lists_reads_and_finds(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [
        (MODEL_DESCRIPTION, MD), (MANIFEST, b"<m/>"), ("binaries/x86_64-linux/m.so", b"\x7fELF"),
        ("documentation/", b""), ("extra/org.other/fmi-ls-manifest.xml", b"<o/>"),
    ])
    source, violations = open_fmu(fmu)
    assert violations == []
    assert source is not None and source.kind == "zip"
    with source:
        assert source.names() == sorted([MODEL_DESCRIPTION, MANIFEST, "binaries/x86_64-linux/m.so",
                                         "extra/org.other/fmi-ls-manifest.xml"])
        assert source.exists(MODEL_DESCRIPTION) and not source.exists("documentation")
        assert source.read(MODEL_DESCRIPTION) == MD
        assert source.find("binaries/*/*.so") == ["binaries/x86_64-linux/m.so"]
        assert source.find("**/fmi-ls-manifest.xml") == sorted(
            [MANIFEST, "extra/org.other/fmi-ls-manifest.xml"])
        assert source.find("*.xml") == [MODEL_DESCRIPTION]
        assert find_manifest_candidates(source) == ["extra/org.other/fmi-ls-manifest.xml"]
        with pytest.raises(KeyError):
            source.read("nope.txt")


def test_any_extension_is_sniffed(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "model.zip.bak", [(MODEL_DESCRIPTION, MD)])
    source, violations = open_fmu(fmu)
    assert source is not None and violations == []
    source.close()


def test_stored_members_are_fine(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD)], method=zipfile.ZIP_STORED)
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None
    assert source.read(MODEL_DESCRIPTION) == MD
    source.close()


# -- unsafe paths ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", [
    "../evil.txt", "a/../../evil.txt", "/etc/evil.txt", "C:\\evil.txt", "C:/evil.txt",
    "c:evil.txt", "dir\\evil.txt", "nul\x00.txt", "ctl\x1b[31m.txt",
])
def test_unsafe_names_are_reported_and_excluded(tmp_path: Path, name: str) -> None:
    # zipfile cuts names at NUL when writing; write a placeholder and patch the bytes in.
    placeholder = name.replace("\x00", "_")
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), (placeholder, b"payload")])
    if placeholder != name:
        patch_entry(fmu, placeholder, new_name=name.encode())
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"unsafe-archive-path"}
    assert source is not None
    assert source.names() == [MODEL_DESCRIPTION]
    assert source.read(MODEL_DESCRIPTION) == MD
    assert "\x1b" not in (violations[0].subject or "")  # names are escaped before printing
    source.close()


def test_symlink_entry_is_reported_and_excluded(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("link", b"/etc/passwd")])
    patch_entry(fmu, "link", external_attr=(0o120777 << 16))
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"unsafe-archive-path"}
    assert violations[0].subject == "link"
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    assert source.excluded() == {"link": "unsafe-archive-path"}
    source.close()


def test_device_entry_is_unsafe(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("dev", b"")])
    patch_entry(fmu, "dev", external_attr=(0o020644 << 16))  # S_IFCHR
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"unsafe-archive-path"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    source.close()


# -- duplicates -----------------------------------------------------------------------------------


def test_duplicate_names(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [
        (MODEL_DESCRIPTION, b"<first/>"), (MODEL_DESCRIPTION, MD), ("ok.txt", b"ok"),
    ])
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-duplicate-entry"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION, "ok.txt"]
    assert source.read(MODEL_DESCRIPTION) == MD  # the last copy, as Python's zipfile and fmpy do
    source.close()


@pytest.mark.parametrize("first, second", [
    ("resources/Data.txt", "resources/data.txt"),        # letter case
    ("resources/a.txt", "resources//a.txt"),              # empty component
    ("resources/a.txt", "./resources/a.txt"),             # '.' component
    ("resources/caf\u00e9.txt", "resources/cafe\u0301.txt"),  # NFC versus NFD
    ("resources/a", "resources/a/b.txt"),                 # a file and a folder
])
def test_names_equal_after_normalisation(tmp_path: Path, first: str, second: str) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), (first, b"1"), (second, b"2")])
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-duplicate-entry"}
    assert source is not None and source.read(MODEL_DESCRIPTION) == MD
    source.close()


# -- sizes and bombs ------------------------------------------------------------------------------


def test_highly_compressible_member_hits_the_ratio_limit(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("bomb.bin", bytes(50 << 20))])
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-too-large"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    source.close()


def test_ratio_limit_spares_small_members(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("zeros.bin", bytes(512 << 10))])
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None
    assert source.read("zeros.bin") == bytes(512 << 10)
    source.close()


def test_member_and_total_limits(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("a.bin", os.urandom(3000)),
                                        ("b.bin", os.urandom(3000))])
    limits = limits_with(max_member=2000)
    source, violations = open_fmu(fmu, limits=limits)
    assert rules_of(violations) == {"archive-too-large"} and len(violations) == 2
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    source.close()
    source, violations = open_fmu(fmu, limits=limits_with(max_total_uncompressed=5000))
    assert rules_of(violations) == {"archive-too-large"} and len(violations) == 1
    assert source is not None and source.read("a.bin")  # the total is reported, members still read
    source.close()


def test_too_many_members(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(f"f{i}.txt", b"x") for i in range(20)])
    source, violations = open_fmu(fmu, limits=limits_with(max_members=10))
    assert source is None and rules_of(violations) == {"archive-too-large"}


def test_declared_size_is_not_trusted(tmp_path: Path) -> None:
    """A member declaring 1000 bytes that inflates to 5 MB: never more than 1000 bytes come out."""
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("liar.bin", bytes(5 << 20))])
    patch_entry(fmu, "liar.bin", size=1000)
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None  # declared sizes look harmless
    with pytest.raises(ArchiveReadError) as info:
        source.read("liar.bin")
    assert info.value.violation.rule == "archive-unreadable"
    assert source.read(MODEL_DESCRIPTION) == MD
    source.close()


def test_reading_counts_actual_bytes(tmp_path: Path) -> None:
    """A folder member that grows after listing is still cut off at the limit while reading."""
    folder = tmp_path / "fmu"
    folder.mkdir()
    (folder / MODEL_DESCRIPTION).write_bytes(MD)
    (folder / "grows.bin").write_bytes(b"x" * 500)
    source, violations = open_fmu(folder, limits=limits_with(max_member=1000))
    assert violations == [] and source is not None
    (folder / "grows.bin").write_bytes(b"x" * (3 << 20))
    with pytest.raises(ArchiveReadError) as info:
        source.read("grows.bin")
    assert info.value.violation.rule == "archive-too-large"
    data, found = source.try_read("grows.bin")
    assert data is None and rules_of(found) == {"archive-too-large"}


def test_overlapping_entries_are_a_bomb(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("a.bin", b"a" * 100),
                                        ("b.bin", b"b" * 100)])
    data = bytearray(fmu.read_bytes())
    records = {}  # name -> position of its central directory record
    pos = 0
    while (pos := data.find(b"PK\x01\x02", pos)) >= 0:
        nlen = struct.unpack_from("<H", data, pos + 28)[0]
        records[bytes(data[pos + 46:pos + 46 + nlen])] = pos
        pos += 4
    # Point b.bin's record at a.bin's local header: two entries sharing one piece of data.
    a_offset = struct.unpack_from("<I", data, records[b"a.bin"] + 42)[0]
    struct.pack_into("<I", data, records[b"b.bin"] + 42, a_offset)
    fmu.write_bytes(bytes(data))
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-too-large"}
    assert violations[0].subject in ("a.bin", "b.bin")
    assert source is not None and source.read(MODEL_DESCRIPTION) == MD
    assert len(source.names()) == 2
    source.close()


# -- unreadable archives and members --------------------------------------------------------------


def test_missing_path(tmp_path: Path) -> None:
    source, violations = open_fmu(tmp_path / "does-not-exist.fmu")
    assert source is None and rules_of(violations) == {"archive-unreadable"}


def test_empty_file(tmp_path: Path) -> None:
    (tmp_path / "e.fmu").write_bytes(b"")
    source, violations = open_fmu(tmp_path / "e.fmu")
    assert source is None and rules_of(violations) == {"archive-unreadable"}


def test_random_bytes(tmp_path: Path) -> None:
    (tmp_path / "r.fmu").write_bytes(os.urandom(4096))
    source, violations = open_fmu(tmp_path / "r.fmu")
    assert source is None and rules_of(violations) == {"archive-unreadable"}


def test_xml_instead_of_zip(tmp_path: Path) -> None:
    (tmp_path / "r.fmu").write_bytes(MD)
    source, violations = open_fmu(tmp_path / "r.fmu")
    assert source is None and rules_of(violations) == {"archive-unreadable"}


@pytest.mark.parametrize("keep", [0.3, 0.6, 0.95])
def test_truncated_zip(tmp_path: Path, keep: float) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("b.bin", os.urandom(20000))])
    data = fmu.read_bytes()
    fmu.write_bytes(data[:int(len(data) * keep)])
    source, violations = open_fmu(fmu)
    assert source is None and rules_of(violations) == {"archive-unreadable"}


def test_corrupt_member_data(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("b.bin", os.urandom(20000))],
                   method=zipfile.ZIP_STORED)
    data = bytearray(fmu.read_bytes())
    middle = data.find(b"b.bin") + 5000
    data[middle:middle + 16] = bytes(16)
    fmu.write_bytes(bytes(data))
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None
    data_read, found = source.try_read("b.bin")
    assert data_read is None and rules_of(found) == {"archive-unreadable"}
    assert source.read(MODEL_DESCRIPTION) == MD
    source.close()


def test_encrypted_member(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("secret.bin", b"s" * 50)])
    patch_entry(fmu, "secret.bin", flags=0x1)
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-unreadable"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    source.close()


def test_unsupported_compression_method(tmp_path: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("odd.bin", b"o" * 50)],
                   method=zipfile.ZIP_STORED)
    patch_entry(fmu, "odd.bin", method=98)  # PPMd
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-compression-method", "archive-unreadable"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION]
    source.close()


@pytest.mark.parametrize("method", [zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA])
def test_other_standard_methods_warn_but_read(tmp_path: Path, method: int) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD)], method=method)
    source, violations = open_fmu(fmu)
    assert rules_of(violations) == {"archive-compression-method"}
    assert source is not None and source.read(MODEL_DESCRIPTION) == MD
    source.close()


# -- folders --------------------------------------------------------------------------------------


@pytest.mark.skipif(sys.platform == "win32", reason="symlinks need privileges on Windows")
def test_folder_with_symlinks(tmp_path: Path) -> None:
    folder = tmp_path / "fmu"
    (folder / "resources").mkdir(parents=True)
    (folder / MODEL_DESCRIPTION).write_bytes(MD)
    (folder / "resources" / "data.txt").write_bytes(b"data")
    os.symlink("/etc/passwd", folder / "resources" / "passwd")
    os.symlink("/etc", folder / "etc")
    os.symlink("../../" + MODEL_DESCRIPTION, folder / "resources" / "md-link.xml")
    os.symlink("data.txt", folder / "resources" / "inside.txt")
    source, violations = open_fmu(folder)
    assert source is not None and source.kind == "folder"
    assert rules_of(violations) == {"unsafe-archive-path"}
    assert {v.subject for v in violations} == {"resources/passwd", "etc", "resources/md-link.xml"}
    assert source.names() == [MODEL_DESCRIPTION, "resources/data.txt", "resources/inside.txt"]
    assert source.read("resources/inside.txt") == b"data"
    assert source.read(MODEL_DESCRIPTION) == MD
    source.close()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_folder_with_fifo_is_never_read(tmp_path: Path) -> None:
    folder = tmp_path / "fmu"
    folder.mkdir()
    (folder / MODEL_DESCRIPTION).write_bytes(MD)
    os.mkfifo(folder / "pipe")
    source, violations = open_fmu(folder)
    assert rules_of(violations) == {"unsafe-archive-path"}
    assert source is not None and source.names() == [MODEL_DESCRIPTION]


def test_folder_case_duplicates_and_limits(tmp_path: Path) -> None:
    folder = tmp_path / "fmu"
    folder.mkdir()
    (folder / MODEL_DESCRIPTION).write_bytes(MD)
    (folder / "Readme.txt").write_bytes(b"a")
    if (folder / "readme.txt").exists():
        pytest.skip("case-insensitive file system")
    (folder / "readme.txt").write_bytes(b"b")
    (folder / "big.bin").write_bytes(b"x" * 5000)
    source, violations = open_fmu(folder, limits=limits_with(max_member=4000))
    assert rules_of(violations) == {"archive-duplicate-entry", "archive-too-large"}
    assert source is not None and "big.bin" not in source.names()
    assert source.read("readme.txt") == b"b"


# -- extraction -----------------------------------------------------------------------------------


def test_extract_writes_only_into_the_private_destination(tmp_path: Path, private_tmp: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    marker = f"lsdae-escape-{os.getpid()}.txt"
    fmu = make_zip(tmp_path / "m.fmu", [
        (MODEL_DESCRIPTION, MD), ("binaries/x86_64-linux/m.so", b"\x7fELF"),
        ("../" + marker, b"x"), ("../../" + marker, b"x"), ("/tmp/" + marker, b"x"),
        ("resources/..\\..\\" + marker, b"x"), ("link", b"/etc/passwd"),
    ])
    patch_entry(fmu, "link", external_attr=(0o120777 << 16))
    before = {p.name for p in tmp_path.iterdir()}
    source, violations = open_fmu(fmu)
    assert source is not None and len(by_rule(violations, "unsafe-archive-path")) == 5
    assert source.extract_to(private_tmp) == []
    source.close()
    written = sorted(str(p.relative_to(private_tmp)) for p in private_tmp.rglob("*") if p.is_file())
    assert written == ["binaries/x86_64-linux/m.so", MODEL_DESCRIPTION]
    assert {p.name for p in tmp_path.iterdir()} == before
    assert list(work.iterdir()) == []
    for place in (Path("/tmp"), private_tmp.parent, tmp_path.parent):
        assert not (place / marker).exists()


def test_extract_subset_and_bounded(tmp_path: Path, private_tmp: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("a.bin", b"a" * 3000),
                                        ("b.bin", b"b" * 3000)])
    source, _ = open_fmu(fmu, limits=limits_with(max_total_uncompressed=4000))
    assert source is not None
    found = source.extract_to(private_tmp, names=["a.bin", "b.bin", "missing"])
    assert rules_of(found) == {"archive-too-large"}
    assert (private_tmp / "a.bin").read_bytes() == b"a" * 3000
    assert not (private_tmp / "b.bin").exists()  # the partial file is removed
    source.close()


def test_extract_refuses_a_destination_that_is_not_private(tmp_path: Path,
                                                           private_tmp: Path) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD)])
    source, _ = open_fmu(fmu)
    assert source is not None
    with pytest.raises(ValueError):
        source.extract_to(Path.home())
    with pytest.raises(ValueError):
        source.extract_to(Path(tempfile.gettempdir()))
    (private_tmp / "x").write_bytes(b"")
    with pytest.raises(ValueError):
        source.extract_to(private_tmp)  # not empty
    public = Path(tempfile.mkdtemp())
    try:
        public.chmod(0o777)
        with pytest.raises(ValueError):
            source.extract_to(public)
    finally:
        public.rmdir()
    source.close()


# -- limits and catalogue -------------------------------------------------------------------------


def test_default_limits_are_the_catalogue_options() -> None:
    catalogue = load_catalogue(rules_dir())
    options = catalogue["archive-too-large"].option_values
    assert default_limits() == ArchiveLimits.from_options(options)
    assert {k: getattr(default_limits(), k) for k in options} == options
    assert set(options) == {"max_total_uncompressed", "max_member", "max_ratio",
                            "ratio_min_size", "max_members"}
    for rule in EMITTED:
        assert catalogue.get(rule) is not None, rule


def test_limits_from_options_rejects_nonsense() -> None:
    options = load_catalogue(rules_dir())["archive-too-large"].option_values
    with pytest.raises(ValueError):
        ArchiveLimits.from_options({**options, "max_member": 0})
    with pytest.raises(ValueError):
        ArchiveLimits.from_options({"max_member": 7})  # the other limits are missing
    assert ArchiveLimits.from_options({**options, "max_member": 7, "other": 1}).max_member == 7


# -- parts: the sub-checks whose basis differs from the rule's ([[rule.parts]]) --------------------


@pytest.mark.parametrize("name,part", [
    ("../evil.txt", None), ("/etc/evil.txt", None), ("C:\\evil.txt", None),   # fmusim rejects
    ("dir\\evil.txt", None), ("./a/../evil.txt", None),
    ("a/../../evil.txt", "other-unsafe-name"), ("C:/evil.txt", "other-unsafe-name"),
    ("c:evil.txt", "other-unsafe-name"), ("nul\x00.txt", "other-unsafe-name"),
    ("ctl\x1b[31m.txt", "other-unsafe-name"),
])
def test_unsafe_names_fmusim_accepts_are_a_part(tmp_path: Path, name: str, part) -> None:
    placeholder = name.replace("\x00", "_")
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), (placeholder, b"payload")])
    if placeholder != name:
        patch_entry(fmu, placeholder, new_name=name.encode())
    source, violations = open_fmu(fmu)
    assert [(v.rule, v.part) for v in violations] == [("unsafe-archive-path", part)]
    source.close()


@pytest.mark.parametrize("name,patch,rule,part", [
    ("link", {"external_attr": 0o120777 << 16}, "unsafe-archive-path", "link-entry"),
    ("dev", {"external_attr": 0o020644 << 16}, "unsafe-archive-path", "special-file"),
    ("secret.bin", {"flags": 0x1}, "archive-unreadable", "encrypted-entry"),
    ("odd.bin", {"method": 98}, "archive-unreadable", "undecodable-method"),
])
def test_entry_sub_checks_carry_their_part(tmp_path: Path, name, patch, rule, part) -> None:
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), (name, b"x" * 50)],
                   method=zipfile.ZIP_STORED)
    patch_entry(fmu, name, **patch)
    source, violations = open_fmu(fmu)
    assert [v.part for v in by_rule(violations, rule)] == [part]
    assert [v.part for v in by_rule(violations, "archive-compression-method")] in ([], [None])
    source.close()


def test_archive_sub_checks_carry_their_part(tmp_path: Path) -> None:
    _, missing = open_fmu(tmp_path / "does-not-exist.fmu")
    assert [v.part for v in missing] == ["path-or-system-error"]
    (tmp_path / "s.fmu").write_bytes(b"PK\x07\x08" + bytes(60))
    _, split = open_fmu(tmp_path / "s.fmu")
    assert [v.part for v in split] == ["split-or-spanned"]
    (tmp_path / "r.fmu").write_bytes(MD)
    _, not_zip = open_fmu(tmp_path / "r.fmu")
    assert [v.part for v in not_zip] == [None]   # the rule's own case


# -- never raises ---------------------------------------------------------------------------------


def _exercise(source: FmuSource | None) -> None:
    if source is None:
        return
    with source:
        for name in source.names():
            source.try_read(name)
        find_manifest_candidates(source)


@settings(max_examples=150, deadline=None, suppress_health_check=SUPPRESS)
@given(st.binary(max_size=2048))
def test_arbitrary_bytes_never_raise(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "h.fmu"
    path.write_bytes(data)
    source, violations = open_fmu(path)
    assert source is not None or violations
    _exercise(source)


_BASE = None


def _base_zip() -> bytes:
    global _BASE
    if _BASE is None:
        d = Path(tempfile.mkdtemp())
        _BASE = make_zip(d / "b.fmu", [(MODEL_DESCRIPTION, MD), ("resources/a.txt", b"a" * 300),
                                       ("binaries/x.so", os.urandom(200))]).read_bytes()
        (d / "b.fmu").unlink()
        d.rmdir()
    return _BASE


@settings(max_examples=300, deadline=None, suppress_health_check=SUPPRESS)
@given(st.lists(st.tuples(st.integers(min_value=0), st.integers(min_value=0, max_value=255)),
                min_size=1, max_size=8))
def test_mutated_zips_never_raise(tmp_path: Path, edits: list[tuple[int, int]]) -> None:
    data = bytearray(_base_zip())
    for pos, value in edits:
        data[pos % len(data)] = value
    path = tmp_path / "m.fmu"
    path.write_bytes(bytes(data))
    source, violations = open_fmu(path)
    _exercise(source)
    assert all(v.rule in EMITTED for v in violations)
