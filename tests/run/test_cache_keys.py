"""The keys of the result cache and of a shard's input list (conformance/run/result_cache.py,
conformance/run/sharding.py) in this process: what goes into them, byte for byte, and what the
cache says when an entry is not used or cannot be written."""
from __future__ import annotations

import hashlib
import io
import json
import logging
import os
from pathlib import Path

from conformance.report.findings import Finding, FmuReport, Location, Severity, evidence
from conformance.run.result_cache import FORMAT, ResultCache, content_hash
from conformance.run.sharding import assign, input_names, input_size, inputs_digest


def test_a_folder_is_hashed_entry_by_entry_in_path_order(tmp_path: Path):
    """Kind, relative path, then size and bytes of a file, the target of a link (never
    followed), nothing more for a folder; each entry ends with a newline."""
    root = tmp_path / "fmu"
    (root / "b").mkdir(parents=True)
    (root / "b" / "f.txt").write_bytes(b"hello")
    (root / "a.xml").write_bytes(b"<x/>")
    os.symlink("b/f.txt", root / "link")
    expected = hashlib.sha256(b"fmu-folder\0"
                              b"F\0a.xml\0" b"4\0<x/>\n"
                              b"D\0b\n"
                              b"F\0b/f.txt\0" b"5\0hello\n"
                              b"L\0link\0b/f.txt\n").hexdigest()
    assert content_hash(root) == expected
    assert content_hash(root / "a.xml") == hashlib.sha256(b"fmu-file\0<x/>").hexdigest()
    assert content_hash(tmp_path / "missing") is None
    assert content_hash(root / "link") is None            # neither a file nor a folder


def test_a_link_target_that_is_not_utf8_is_hashed_as_its_bytes(tmp_path: Path):
    root = tmp_path / "fmu"
    root.mkdir()
    os.symlink(os.fsdecode(b"t\xff"), root / "link")
    expected = hashlib.sha256(b"fmu-folder\0L\0link\0t\xff\n").hexdigest()
    assert content_hash(root) == expected


def test_a_shard_input_list_has_one_digest_of_names_and_sizes():
    assert inputs_digest(["a.fmu", "b/c.fmu"], [3, 10]) == hashlib.sha256(
        b'[["a.fmu",3],["b/c.fmu",10]]').hexdigest()


def test_inputs_are_named_relative_to_their_common_folder_and_weighed(tmp_path: Path):
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "a.fmu").write_bytes(b"12345")
    (tmp_path / "y" / "d").mkdir(parents=True)
    (tmp_path / "y" / "d" / "m.xml").write_bytes(b"123")
    (tmp_path / "y" / "d" / "n").write_bytes(b"1")
    assert input_names([]) == []
    assert input_names([str(tmp_path / "x" / "a.fmu"), str(tmp_path / "y" / "d")]) == [
        "x/a.fmu", "y/d"]
    assert input_size(tmp_path / "x" / "a.fmu") == 5
    assert input_size(tmp_path / "y" / "d") == 4
    assert input_size(tmp_path / "none") == 0
    assert assign(["a", "b", "c"], [5, 3, 1], 2) == [1, 2, 2]
    assert assign(["a"], [5], 3) == [1]


def _report() -> FmuReport:
    return FmuReport("a.fmu", None, (Finding("DAE1", "n", Severity.INFO, "wärme",
                                             Location(file="f", line=2, snippet="<a>"),
                                             evidence(x=1)),))


def test_an_entry_is_stored_under_its_key_and_read_back(tmp_path: Path, monkeypatch):
    """In UTF-8 whatever the locale's encoding (here made Latin-1, as cp1252 on Windows)."""
    monkeypatch.setattr(io, "text_encoding", lambda encoding, stacklevel=2: encoding or "latin-1")
    cache = ResultCache(tmp_path / "c", "settings")
    key = cache.key("content")
    assert key == hashlib.sha256(f"lsdae-cache {FORMAT}\0settings\0content".encode()).hexdigest()
    assert cache.put("content", _report())
    file = tmp_path / "c" / key[:2] / f"{key}.json"
    entry = json.loads(file.read_text(encoding="utf-8"))
    assert "wärme" in file.read_text(encoding="utf-8")
    assert (entry["lsdae-cache"], entry["key"]) == (FORMAT, key)
    assert cache.get("content") == _report()
    assert cache.get("other") is None
    assert [p.name for p in file.parent.iterdir()] == [file.name]


def test_an_entry_not_used_and_a_cache_not_written_are_said(tmp_path: Path, caplog):
    caplog.set_level(logging.INFO, logger="conformance.run.result_cache")
    cache = ResultCache(tmp_path / "c", "settings")
    cache.put("content", _report())
    key = cache.key("content")
    file = tmp_path / "c" / key[:2] / f"{key}.json"
    file.write_text(json.dumps({"lsdae-cache": FORMAT, "key": "other", "fmu": {}}))
    assert cache.get("content") is None
    assert caplog.messages == [f"cache entry {file} not used: ValueError: the entry is not "
                               "the one its name says"]
    caplog.clear()
    blocked = tmp_path / "blocked"
    blocked.write_text("")
    other = ResultCache(blocked, "settings")
    assert other.put("content", _report()) is False
    (message,) = caplog.messages
    assert message.startswith(f"cannot write the cache entry {blocked / key[:2] / key}.json: ")
