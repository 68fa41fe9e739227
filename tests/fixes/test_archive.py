"""The zip rewriter: every entry no fix touched keeps its bytes, name, order and compression."""
from __future__ import annotations

import os
import shutil
import struct
import subprocess
import tempfile
import warnings
import zipfile
from pathlib import Path

import pytest

from conformance.commands.fix import fix_fmu
from conformance.fixes.archive import Package, PackageError
from conformance.intake.fmu import default_limits
from conformance.model.manifest import MANIFEST
from conformance.model.description import MODEL_DESCRIPTION
from tests.fixes.conftest import STATIC, codes
from tests.fixtures import scene_xml

BINARY = "binaries/x86_64-linux/HelloWorldDAE.so"


def _raw(path: Path, info: zipfile.ZipInfo) -> bytes:
    """The compressed bytes of one entry as stored."""
    with open(path, "rb") as f:
        f.seek(info.header_offset)
        header = f.read(30)
        n, m = struct.unpack("<HH", header[26:30])
        f.seek(info.header_offset + 30 + n + m)
        return f.read(info.compress_size)


def _build(path: Path) -> Path:
    xml = scene_xml("HelloWorldDAE")
    manifest = xml[MANIFEST].read_bytes().replace(
        b'support in FMI."', b'support in FMU."')   # DAE104
    data = os.urandom(3000) + bytes(3000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the duplicate is on purpose
        with zipfile.ZipFile(path, "w") as zf:
            zf.writestr(zipfile.ZipInfo(MODEL_DESCRIPTION, (2020, 1, 2, 3, 4, 6)),
                        xml[MODEL_DESCRIPTION].read_bytes(), zipfile.ZIP_DEFLATED, 9)
            zf.writestr(zipfile.ZipInfo(BINARY, (2021, 5, 6, 7, 8, 10)), data,
                        zipfile.ZIP_STORED)
            zf.writestr(zipfile.ZipInfo(MANIFEST, (2022, 1, 1, 0, 0, 0)), manifest,
                        zipfile.ZIP_STORED)
            zf.writestr("resources/table.csv", b"t,x\n0,1\n" * 50, zipfile.ZIP_DEFLATED, 1)
            zf.writestr("resources/table.csv", b"t,x\n0,1\n" * 50, zipfile.ZIP_DEFLATED, 1)
    return path


def test_untouched_entries_are_copied_raw_in_order(tmp_path):
    source = _build(tmp_path / "M.fmu")
    assert {"DAE003", "DAE104"} <= codes(source)
    outcome = fix_fmu(source, options=STATIC)
    out = tmp_path / "F.fmu"
    outcome.package.write(out)
    assert not {"DAE003", "DAE104"} & codes(out)
    before = zipfile.ZipFile(source).infolist()
    after = zipfile.ZipFile(out).infolist()
    assert zipfile.ZipFile(out).testzip() is None
    kept = [i for i in before[:4]]                      # the second table.csv is dropped
    assert [i.filename for i in after] == [i.filename for i in kept]
    for old, new in zip(kept, after):
        assert (new.compress_type, new.date_time, new.external_attr) == \
            (old.compress_type, old.date_time, old.external_attr)
        if old.filename != MANIFEST:
            assert (new.CRC, new.compress_size, new.file_size) == \
                (old.CRC, old.compress_size, old.file_size)
            assert _raw(out, new) == _raw(source, old)
    assert zipfile.ZipFile(out).read(MANIFEST) != zipfile.ZipFile(source).read(MANIFEST)
    if shutil.which("unzip"):   # another reader than Python's accepts the rewritten archive
        done = subprocess.run(["unzip", "-tq", str(out)], capture_output=True, check=False)
        assert done.returncode == 0, done.stdout + done.stderr


def test_duplicates_that_differ_are_kept(tmp_path):
    path = tmp_path / "D.fmu"
    xml = scene_xml("HelloWorldDAE")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with zipfile.ZipFile(path, "w") as zf:
            for name, src in xml.items():
                zf.writestr(name, src.read_bytes())
            zf.writestr("resources/a.txt", b"one")
            zf.writestr("resources/a.txt", b"two")
    outcome = fix_fmu(path, options=STATIC)
    assert not outcome.applied and not outcome.package.modified
    assert "DAE003" in codes(path)


class _Stream:
    """A write-only stream without seek: zipfile then writes data descriptors (flag bit 3)."""

    def __init__(self):
        self.data = bytearray()

    def write(self, b):
        self.data += b
        return len(b)

    def tell(self):
        return len(self.data)

    def flush(self):
        pass


def test_entries_written_with_data_descriptors_are_copied_and_readable(tmp_path):
    xml = scene_xml("HelloWorldDAE")
    manifest = xml[MANIFEST].read_bytes().replace(b'support in FMI."', b'support in FMI"')
    stream = _Stream()
    with zipfile.ZipFile(stream, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(MODEL_DESCRIPTION, xml[MODEL_DESCRIPTION].read_bytes())
        zf.writestr(BINARY, os.urandom(5000))
        zf.writestr(MANIFEST, manifest)
    source = tmp_path / "S.fmu"
    source.write_bytes(bytes(stream.data))
    assert all(i.flag_bits & 0x08 for i in zipfile.ZipFile(source).infolist())
    outcome = fix_fmu(source, options=STATIC)
    out = tmp_path / "F.fmu"
    outcome.package.write(out)
    fixed = zipfile.ZipFile(out)
    assert fixed.testzip() is None
    assert "DAE104" in codes(source) and "DAE104" not in codes(out)
    for old, new in zip(zipfile.ZipFile(source).infolist(), fixed.infolist()):
        assert new.filename == old.filename
        if old.filename != MANIFEST:
            assert _raw(out, new) == _raw(source, old)
            assert fixed.read(new) == zipfile.ZipFile(source).read(old)


# --- the writer on its own: attributes of an edited entry, the temporary sibling -------------

def _zip(path: Path, mode: int = 0o644) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        for name in (MODEL_DESCRIPTION, MANIFEST):
            info = zipfile.ZipInfo(name, (2022, 1, 1, 0, 0, 0))
            info.external_attr = (0o100000 | mode) << 16    # a regular file, rw-r--r--
            zf.writestr(info, b"<old/>\n", zipfile.ZIP_DEFLATED)
    return path


def test_an_edited_entry_keeps_its_mode_time_and_compression(tmp_path):
    source = _zip(tmp_path / "M.fmu")
    out = tmp_path / "F.fmu"
    Package(source, default_limits()).with_files({MANIFEST: b"<new/>\n"}).write(out)
    old = {i.filename: i for i in zipfile.ZipFile(source).infolist()}
    for new in zipfile.ZipFile(out).infolist():
        assert (new.external_attr, new.date_time, new.compress_type) == (
            old[new.filename].external_attr, (2022, 1, 1, 0, 0, 0), zipfile.ZIP_DEFLATED)
    assert zipfile.ZipFile(out).read(MANIFEST) == b"<new/>\n"


def test_a_zip_is_written_through_a_sibling_not_the_system_temp_folder(tmp_path, monkeypatch):
    """os.replace cannot move a file across file systems: the temporary file must lie beside
    the output, whatever TMPDIR says."""
    source = _zip(tmp_path / "M.fmu")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "no-such-folder"))
    out = tmp_path / "F.fmu"
    Package(source, default_limits()).with_files({MANIFEST: b"<new/>\n"}).write(out)
    assert zipfile.ZipFile(out).read(MANIFEST) == b"<new/>\n"


def test_a_failed_write_leaves_nothing_behind_and_says_why(tmp_path):
    source = _zip(tmp_path / "M.fmu")
    data = bytearray(source.read_bytes())
    data[0:4] = b"XXXX"    # the first entry's local header is gone; the directory still names it
    source.write_bytes(bytes(data))
    out = tmp_path / "out" / "F.fmu"
    out.parent.mkdir()
    with pytest.raises(PackageError, match="no local header where the directory says"):
        Package(source, default_limits()).with_files({MANIFEST: b"<new/>\n"}).write(out)
    assert list(out.parent.iterdir()) == []


def test_a_folder_is_built_in_a_hidden_sibling_then_moved(tmp_path, monkeypatch):
    source = tmp_path / "in"
    (source / "extra").mkdir(parents=True)
    (source / MODEL_DESCRIPTION).write_bytes(b"<old/>\n")
    copies = []
    real = shutil.copytree

    def copytree(src, dst, *args, **kw):   # shutil calls itself for subfolders
        copies.append(Path(dst))
        return real(src, dst, *args, **kw)

    monkeypatch.setattr(shutil, "copytree", copytree)
    out = tmp_path / "out"
    Package(source, default_limits()).with_files({MODEL_DESCRIPTION: b"<new/>\n"}).write(out)
    assert (out / MODEL_DESCRIPTION).read_bytes() == b"<new/>\n"
    assert (source / MODEL_DESCRIPTION).read_bytes() == b"<old/>\n"
    assert copies[0].parent == tmp_path
    assert copies[0].name.startswith(".lsdae-fix-") and not copies[0].exists()
