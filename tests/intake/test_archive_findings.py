"""The archive findings of conformance/intake/archive, exactly: rule, part, subject, message and
evidence of each entry-level and FMU-level violation, as a user reads them and the engine groups
them (test_fmu.py asserts which rules fire; here, what each one says)."""
from __future__ import annotations

import os
import shutil
import tempfile
import zipfile
from pathlib import Path

import pytest

from conformance.intake.archive import folder as folder_module
from conformance.intake.archive.base import ArchiveLimits, Unsafe, unsafe_reason
from conformance.intake.fmu import MODEL_DESCRIPTION, default_limits, open_fmu
from conformance.report.findings import Location, Violation, evidence
from tests.intake.test_fmu import MD, limits_with, make_zip, patch_entry


def fmu_violation(rule: str, message: str, *, part: str | None = None, **ev) -> Violation:
    """A violation about the FMU as a whole (no subject, no file)."""
    return Violation(message, Location(), evidence(ev), rule=rule, part=part)


def entry_violation(rule: str, message: str, subject: str, *, part: str | None = None,
                    **ev) -> Violation:
    return Violation(message, Location(), evidence(ev), subject=subject, rule=rule, part=part)


def test_an_empty_entry_name_is_unsafe():
    assert unsafe_reason("") == Unsafe("has an empty name", "other-unsafe-name")
    assert unsafe_reason("/") == Unsafe("has an empty name")   # starts with '/': fmusim's case


def test_limits_keep_a_fractional_ratio():
    options = {"max_total_uncompressed": 10, "max_member": 5, "max_ratio": 2.5,
               "ratio_min_size": 1, "max_members": 3, "other": "ignored"}
    assert ArchiveLimits.from_options(options) == ArchiveLimits(10, 5, 2.5, 1, 3)
    assert type(ArchiveLimits.from_options(options).max_ratio) is float


# -- what the path is ----------------------------------------------------------------------------


def test_a_missing_fmu(tmp_path: Path):
    assert open_fmu(tmp_path / "none.fmu") == (None, [fmu_violation(
        "archive-unreadable", "the FMU does not exist (no such file or folder)",
        part="path-or-system-error")])


def test_an_fmu_path_through_a_file(tmp_path: Path):
    (tmp_path / "file").write_bytes(b"x")
    assert open_fmu(tmp_path / "file" / "m.fmu") == (None, [fmu_violation(
        "archive-unreadable", "the FMU cannot be accessed: Not a directory",
        part="path-or-system-error")])


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_an_fmu_that_is_a_fifo(tmp_path: Path):
    os.mkfifo(tmp_path / "m.fmu")
    assert open_fmu(tmp_path / "m.fmu") == (None, [fmu_violation(
        "archive-unreadable", "the FMU is neither a regular file nor a folder")])


def test_an_empty_fmu_file(tmp_path: Path):
    (tmp_path / "m.fmu").write_bytes(b"")
    assert open_fmu(tmp_path / "m.fmu") == (None, [fmu_violation(
        "archive-unreadable", "the FMU is an empty file, not a ZIP archive")])


def test_xml_instead_of_a_zip_archive(tmp_path: Path):
    (tmp_path / "m.fmu").write_bytes(b"<?xml")
    assert open_fmu(tmp_path / "m.fmu") == (None, [fmu_violation(
        "archive-unreadable", "the FMU is not a ZIP archive (it looks like XML): it starts with "
        "bytes 3c 3f 78 6d, not 'PK'", first_bytes="3c3f786d")])


def test_a_zip_archive_without_entries_is_a_zip_archive(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [])
    assert fmu.read_bytes()[:4] == b"PK\x05\x06"
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None
    assert (source.kind, source.names()) == ("zip", [])
    source.close()


# -- entries of a ZIP archive --------------------------------------------------------------------


def test_too_many_entries(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("a", b"a"), ("b", b"b")])
    assert open_fmu(fmu, limits=limits_with(max_members=2)) == (None, [fmu_violation(
        "archive-too-large", "the FMU has 3 or more entries, more than the limit of 2; it is not "
        "checked further", entries=3, limit=2)])


def test_a_member_over_the_member_limit(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("big.bin", os.urandom(5000))])
    source, violations = open_fmu(fmu, limits=limits_with(max_member=4000))
    assert violations == [entry_violation(
        "archive-too-large", "{subject} is 5000 bytes uncompressed, more than the per-member "
        "limit of 4000 bytes", "big.bin", size=5000, limit=4000)]
    assert source is not None and source.excluded() == {"big.bin": "archive-too-large"}
    source.close()


def test_an_undecodable_compression_method(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("odd.bin", b"o" * 50)],
                   method=zipfile.ZIP_STORED)
    patch_entry(fmu, "odd.bin", method=98)  # PPMd
    source, violations = open_fmu(fmu)
    assert violations == [
        entry_violation("archive-compression-method", "{subject} uses compression method 98 "
                        "(ppmd); FMI allows only stored (0) and deflate (8)", "odd.bin",
                        method=98),
        entry_violation("archive-unreadable", "{subject} cannot be read: compression method 98 "
                        "(ppmd) is not supported", "odd.bin", method=98,
                        part="undecodable-method"),
    ]
    source.close()


def test_names_in_cp437_are_measured_in_cp437(tmp_path: Path):
    """An entry name without the UTF-8 flag is cp437: 'é' is one byte of the local header, so
    the entry after it does not overlap it (counted in UTF-8 it would)."""
    fmu = make_zip(tmp_path / "m.fmu", [("a.txt", b"abc"), (MODEL_DESCRIPTION, MD)],
                   method=zipfile.ZIP_STORED)
    patch_entry(fmu, "a.txt", new_name=b"\x82.txt")   # cp437 0x82 is 'é'
    source, violations = open_fmu(fmu)
    assert violations == []
    assert source is not None and source.names() == [MODEL_DESCRIPTION, "\u00e9.txt"]
    assert source.read("\u00e9.txt") == b"abc"
    source.close()


def test_a_corrupt_member_says_why_it_cannot_be_read(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("b.bin", b"b" * 100)],
                   method=zipfile.ZIP_STORED)
    data = bytearray(fmu.read_bytes())
    at = data.find(b"b" * 100)
    data[at:at + 10] = b"c" * 10
    fmu.write_bytes(bytes(data))
    source, violations = open_fmu(fmu)
    assert violations == [] and source is not None
    data_read, found = source.try_read("b.bin")
    assert data_read is None
    assert found == [Violation("{subject} cannot be read: Bad CRC-32 for file 'b.bin' "
                               "(BadZipFile)", Location(file="b.bin"),
                               evidence(error="BadZipFile"), subject="b.bin",
                               rule="archive-unreadable")]
    source.close()


def test_names_that_differ_in_case_name_each_other(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [(MODEL_DESCRIPTION, MD), ("Readme.txt", b"a"),
                                        ("readme.txt", b"b"), ("README.txt", b"c")])
    source, violations = open_fmu(fmu)
    assert violations == [entry_violation(
        "archive-duplicate-entry", "{subject} and 'Readme.txt', 'readme.txt' differ only in "
        "letter case; they overwrite each other when extracted on Windows or macOS",
        "README.txt", names=["README.txt", "Readme.txt", "readme.txt"])]
    source.close()


# -- extraction ----------------------------------------------------------------------------------


def test_a_member_that_cannot_be_extracted(tmp_path: Path):
    fmu = make_zip(tmp_path / "m.fmu", [("a", b"file"), ("a/b", b"below")])
    source, violations = open_fmu(fmu)
    assert violations == [entry_violation(
        "archive-duplicate-entry", "{subject} is both a file and a folder; it cannot be "
        "extracted", "a")]
    dest = Path(tempfile.mkdtemp(prefix="lsdae-test-"))
    try:
        assert source.extract_to(dest) == [Violation(
            "{subject} cannot be extracted: File exists", Location(file="a/b"), subject="a/b",
            rule="archive-unreadable", part="path-or-system-error")]
        assert (dest / "a").read_bytes() == b"file"
    finally:
        shutil.rmtree(dest, ignore_errors=True)
        source.close()


# -- an unpacked folder --------------------------------------------------------------------------


def test_a_folder_with_too_many_entries(tmp_path: Path):
    (tmp_path / MODEL_DESCRIPTION).write_bytes(MD)
    (tmp_path / "a").write_bytes(b"a")
    (tmp_path / "b").write_bytes(b"b")
    assert open_fmu(tmp_path, limits=limits_with(max_members=2)) == (None, [fmu_violation(
        "archive-too-large", "the FMU has 3 or more entries, more than the limit of 2; it is not "
        "checked further", entries=3, limit=2)])


def test_a_link_out_of_the_folder_names_its_target(tmp_path: Path):
    folder = tmp_path / "fmu"
    folder.mkdir()
    (folder / MODEL_DESCRIPTION).write_bytes(MD)
    (tmp_path / "secret").write_bytes(b"s")
    os.symlink(tmp_path / "secret", folder / "link")
    source, violations = open_fmu(folder)
    assert violations == [entry_violation(
        "unsafe-archive-path", "{subject} is a symbolic link to a place outside the FMU folder; "
        "it is never followed", "link", target=os.path.realpath(tmp_path / "secret"),
        part="link-entry")]
    source.close()


def test_a_folder_that_cannot_be_listed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    (tmp_path / MODEL_DESCRIPTION).write_bytes(MD)
    (tmp_path / "sub" / "deeper").mkdir(parents=True)
    (tmp_path / "sub" / "deeper" / "x.txt").write_bytes(b"x")
    locked = os.path.join(os.path.realpath(tmp_path), "sub", "deeper")
    scandir = os.scandir

    def refusing(path):
        if os.fspath(path) == locked:
            raise PermissionError(13, "Permission denied")
        return scandir(path)

    monkeypatch.setattr(os, "scandir", refusing)
    source, violations = open_fmu(tmp_path)
    assert violations == [entry_violation(
        "archive-unreadable", "{subject} cannot be listed: Permission denied", "sub/deeper",
        part="path-or-system-error")]
    assert source is not None and source.names() == [MODEL_DESCRIPTION]


def test_a_folder_entry_that_cannot_be_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    (tmp_path / MODEL_DESCRIPTION).write_bytes(MD)
    (tmp_path / "bad.bin").write_bytes(b"x")
    inspect = folder_module._inspect_folder_entry

    def failing(inv, root, rel, entry, pending):
        if rel == "bad.bin":
            raise OSError(5, "Input/output error")
        return inspect(inv, root, rel, entry, pending)

    monkeypatch.setattr(folder_module, "_inspect_folder_entry", failing)
    source, violations = open_fmu(tmp_path)
    assert violations == [entry_violation(
        "archive-unreadable", "{subject} cannot be read: Input/output error", "bad.bin",
        part="path-or-system-error")]
    assert source is not None and source.excluded() == {"bad.bin": "archive-unreadable"}
    assert source.names() == [MODEL_DESCRIPTION]


def test_default_limits_are_positive():
    limits = default_limits()
    assert min(limits.max_total_uncompressed, limits.max_member, limits.max_members,
               limits.ratio_min_size) > 0 and limits.max_ratio > 0
