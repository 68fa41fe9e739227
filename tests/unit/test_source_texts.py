"""Source lines of large files: read again from the FMU only when a finding points into them."""
from __future__ import annotations

import zipfile

from conformance.run import source_texts
from conformance.run.engine import EngineOptions, check_fmu
from conformance.intake.fmu import default_limits
from conformance.run.source_texts import SourceTexts
from scenes.build import build_scene


def test_small_files_are_kept_and_large_ones_read_again(tmp_path, monkeypatch):
    fmu = tmp_path / "a.fmu"
    with zipfile.ZipFile(fmu, "w") as zf:
        zf.writestr("modelDescription.xml", b"<big/>\n" * 10)
        zf.writestr("small.xml", b"<small/>")
    monkeypatch.setattr(source_texts, "KEEP_BYTES", 20)
    texts = SourceTexts(fmu, default_limits())
    texts.keep("small.xml", b"<small/>")
    texts.keep("modelDescription.xml", b"stale bytes that are not kept, they are long")
    assert texts.get("small.xml") == b"<small/>"
    assert texts.get("modelDescription.xml") == b"<big/>\n" * 10   # read again from the FMU
    assert texts.get("unknown.xml") is None


def test_a_vanished_fmu_gives_no_source_line(tmp_path, monkeypatch):
    monkeypatch.setattr(source_texts, "KEEP_BYTES", 0)
    texts = SourceTexts(tmp_path / "gone.fmu", default_limits())
    texts.keep("modelDescription.xml", b"<x/>")
    assert texts.get("modelDescription.xml") is None


def _broken_copy(tmp_path):
    """HelloWorldDAE with a variable whose causality is not one of FMI's: a schema finding."""
    fmu = tmp_path / "broken.fmu"
    with zipfile.ZipFile(build_scene("HelloWorldDAE")) as src, zipfile.ZipFile(fmu, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "modelDescription.xml":
                data = data.replace(b"<ModelVariables>", b'<ModelVariables>\n    <Float64 '
                                    b'name="zz" valueReference="999" causality="nonsense"/>', 1)
            dst.writestr(info, data)
    return fmu


def _snippets(fmu) -> list:
    report = check_fmu(fmu, options=EngineOptions(probes=False))
    return [(f.location.line, f.location.snippet) for f in report.findings if f.location.line]


def test_findings_show_the_same_lines_whether_the_bytes_were_kept_or_not(tmp_path, monkeypatch):
    fmu = _broken_copy(tmp_path)
    kept = _snippets(fmu)
    monkeypatch.setattr(source_texts, "KEEP_BYTES", 0)
    read_again = _snippets(fmu)
    assert kept and all(snippet for _, snippet in kept)
    assert any("nonsense" in snippet for _, snippet in kept)
    assert read_again == kept
