"""``--cache-dir``: an unchanged FMU is not checked again, and gets the identical result."""
from __future__ import annotations

import json
import os
import shutil
import zipfile
from pathlib import Path

import pytest

import conformance.run.parallel as parallel
from conformance.run import fleet
from conformance.run.result_cache import content_hash
from tests.fixtures import build_scene
from tests.clikit import every_format, lsdae, outputs


@pytest.fixture
def engine_calls(monkeypatch) -> list[str]:
    """The FMUs the engine is asked to check (the runs here use one process, -j 1)."""
    calls: list[str] = []
    real = parallel.check_fmu

    def counted(path, **kw):
        calls.append(str(path))
        return real(path, **kw)

    monkeypatch.setattr(parallel, "check_fmu", counted)
    return calls


@pytest.fixture
def fmus(tmp_path, scene_fmus, fixture_fmus) -> list[str]:
    """Copies (so they can be changed): scenes, zipped and unpacked fixtures."""
    out = []
    for i, source in enumerate([*scene_fmus[:2], *fixture_fmus[:40]]):
        target = tmp_path / "fmus" / f"{i:02d}-{Path(source).name}"
        target.parent.mkdir(parents=True, exist_ok=True)
        if Path(source).is_dir():
            shutil.copytree(source, target, symlinks=True)
        else:
            shutil.copyfile(source, target)
        out.append(str(target))
    return out


def _check(paths, folder: Path, cache: Path, *extra: str) -> int:
    code, _, err = lsdae("check", *paths, "--no-probes", "--cache-dir", str(cache),
                         *extra, *every_format(folder))
    assert code in (0, 1), err
    return code


def test_a_hit_is_the_identical_report_and_does_not_call_the_engine(fmus, tmp_path,
                                                                   engine_calls):
    cache = tmp_path / "cache"
    first = _check(fmus, tmp_path / "first", cache)
    assert len(engine_calls) == len(fmus)
    again = _check(fmus, tmp_path / "again", cache)
    assert len(engine_calls) == len(fmus), "an unchanged FMU was checked again"
    assert again == first
    assert outputs(tmp_path / "again") == outputs(tmp_path / "first")
    uncached = tmp_path / "uncached"
    code, _, _ = lsdae("check", *fmus, "--no-probes", *every_format(uncached))
    assert outputs(uncached) == outputs(tmp_path / "first") and code == first


def _flip(path: str) -> None:
    """Change one byte of the FMU: the last of a .fmu, else of its modelDescription.xml."""
    target = Path(path) if Path(path).is_file() else Path(path) / "modelDescription.xml"
    data = bytearray(target.read_bytes())
    data[-1] ^= 0x01
    target.write_bytes(bytes(data))


def test_one_changed_byte_misses(fmus, tmp_path, engine_calls):
    cache = tmp_path / "cache"
    _check(fmus, tmp_path / "first", cache)
    packed = next(p for p in fmus if p.endswith(".fmu"))
    folder = next(p for p in fmus if Path(p).is_dir())
    engine_calls.clear()
    _flip(packed)
    _flip(folder)
    _check(fmus, tmp_path / "again", cache)
    assert sorted(engine_calls) == sorted([packed, folder])


def test_a_moved_fmu_hits_and_keeps_its_new_path(fmus, tmp_path, engine_calls):
    cache = tmp_path / "cache"
    _check(fmus[:3], tmp_path / "first", cache)
    moved = tmp_path / "elsewhere" / Path(fmus[0]).name
    moved.parent.mkdir()
    shutil.move(fmus[0], moved)
    engine_calls.clear()
    _check([str(moved)], tmp_path / "moved", cache)
    assert engine_calls == []
    data = json.loads((tmp_path / "moved" / "json").read_text())
    assert [f["path"] for f in data["fmus"]] == [str(moved)]


def test_a_file_added_to_a_folder_misses(fmus, tmp_path):
    folder = next(p for p in fmus if Path(p).is_dir())
    before = content_hash(folder)
    (Path(folder) / "documentation").mkdir(exist_ok=True)
    assert content_hash(folder) != before
    (Path(folder) / "documentation" / "index.html").write_text("")
    after = content_hash(folder)
    assert after != before
    (Path(folder) / "documentation" / "index.html").rename(Path(folder) / "documentation" / "b")
    assert content_hash(folder) != after


@pytest.mark.parametrize("extra", [
    ("--select", "DAE2"), ("--ignore", "DAE203"), ("--severity", "DAE203=warning"),
    ("--draft", "alpha1"), ("--seed", "3"), ("--rule-option", "DAE740.rtol=1e-3"),
    ("--endurance", "off"),
])
def test_other_settings_miss(fmus, tmp_path, engine_calls, extra):
    cache = tmp_path / "cache"
    _check(fmus[:4], tmp_path / "first", cache)
    engine_calls.clear()
    _check(fmus[:4], tmp_path / "other", cache, *extra)
    assert len(engine_calls) == 4
    engine_calls.clear()
    _check(fmus[:4], tmp_path / "other-again", cache, *extra)
    assert engine_calls == []


def test_the_probe_workers_are_not_a_setting_of_the_findings(fmus, tmp_path, engine_calls):
    """--probe-workers decides how fast, not what (conformance/probes/machinery/lanes.py): a hit."""
    cache = tmp_path / "cache"
    _check(fmus[:2], tmp_path / "first", cache)
    engine_calls.clear()
    _check(fmus[:2], tmp_path / "two", cache, "--probe-workers", "2")
    assert engine_calls == []


def test_other_code_misses(fmus, tmp_path, engine_calls, monkeypatch):
    """A development checkout keeps its version across edits: the code itself is in the key."""
    cache = tmp_path / "cache"
    _check(fmus[:2], tmp_path / "first", cache)
    engine_calls.clear()
    monkeypatch.setattr(fleet, "code_fingerprint", lambda: "edited")
    _check(fmus[:2], tmp_path / "edited", cache)
    assert len(engine_calls) == 2


def test_the_code_fingerprint_is_stable_and_follows_the_libraries(monkeypatch):
    before = fleet.code_fingerprint()
    assert fleet.code_fingerprint() == before
    monkeypatch.setattr(fleet, "LIBRARIES", (*fleet.LIBRARIES, "lsdae"))
    assert fleet.code_fingerprint() != before


def _entries(cache: Path) -> list[Path]:
    return sorted(cache.glob("*/*.json"))


@pytest.mark.parametrize("damage", [
    lambda p: p.write_text(""),
    lambda p: p.write_text(p.read_text()[: len(p.read_text()) // 2]),
    lambda p: p.write_bytes(os.urandom(300)),
    lambda p: p.write_text(json.dumps({"lsdae-cache": 1, "key": "other", "fmu": {}})),
    lambda p: p.write_text(p.read_text().replace('"findings"', '"f"')),
    lambda p: p.write_text("[1, 2]"),
    lambda p: (p.unlink(), p.mkdir()),
])
def test_a_damaged_entry_is_a_miss(fmus, tmp_path, engine_calls, damage):
    cache = tmp_path / "cache"
    _check(fmus[:3], tmp_path / "first", cache)
    for entry in _entries(cache):
        damage(entry)
    engine_calls.clear()
    _check(fmus[:3], tmp_path / "again", cache)
    assert len(engine_calls) == 3
    assert outputs(tmp_path / "again") == outputs(tmp_path / "first")


def test_writes_leave_no_temporary_files_and_an_unwritable_cache_is_no_failure(fmus, tmp_path):
    cache = tmp_path / "cache"
    _check(fmus, tmp_path / "first", cache)
    assert len(_entries(cache)) == len({content_hash(p) for p in fmus})
    assert not [p for p in cache.rglob("*") if p.is_file() and p.suffix != ".json"]
    assert not list(cache.rglob(".tmp-*"))
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the cache folder should be")
    _check(fmus[:2], tmp_path / "blocked-out", blocked)
    lsdae("check", *fmus[:2], "--no-probes", *every_format(tmp_path / "plain"))
    assert outputs(tmp_path / "blocked-out") == outputs(tmp_path / "plain")


def test_results_of_a_check_that_did_not_complete_are_not_kept(tmp_path, monkeypatch):
    def broken(path, **kw):
        raise RuntimeError("a defect of ours")

    monkeypatch.setattr(parallel, "check_fmu", broken)
    fmu = str(build_scene("HelloWorldDAE"))
    cache = tmp_path / "cache"
    code, _, _ = lsdae("check", fmu, "--no-probes", "--cache-dir", str(cache),
                       "--format", f"json:{tmp_path / 'r.json'}")
    assert code == 2   # an internal error: the FMU was not checked
    assert _entries(cache) == []


def test_a_hit_with_probes_is_the_identical_report(tmp_path, engine_calls):
    """With the binary checked (probe evidence holds measured floats)."""
    fmu = str(build_scene("SimpleDAE", defines=["DEFECT_WRONG_JACOBIAN"]))
    cache = tmp_path / "cache"
    lsdae("check", fmu, "--cache-dir", str(cache), *every_format(tmp_path / "first"))
    lsdae("check", fmu, "--cache-dir", str(cache), *every_format(tmp_path / "again"))
    assert engine_calls == [fmu]
    assert outputs(tmp_path / "again") == outputs(tmp_path / "first")
    assert json.loads(outputs(tmp_path / "first")["json"])["fmus"][0]["findings"]


def test_cache_and_shards_together(fmus, tmp_path, engine_calls):
    """The matrix job's combination: each shard fills and reuses one shared cache."""
    cache = tmp_path / "cache"
    for index in (1, 2):
        lsdae("check", *fmus, "--no-probes", "--shard", f"{index}/2", "--cache-dir", str(cache),
              "--format", f"json:{tmp_path / f's{index}.json'}")
    assert sorted(engine_calls) == sorted(fmus)
    engine_calls.clear()
    code, _, _ = lsdae("check", *fmus, "--no-probes", "--cache-dir", str(cache),
                       *every_format(tmp_path / "whole"))
    assert engine_calls == []
    merged, _, err = lsdae("merge", str(tmp_path / "s1.json"), str(tmp_path / "s2.json"),
                           *every_format(tmp_path / "merged"))
    assert merged == code, err
    assert outputs(tmp_path / "merged") == outputs(tmp_path / "whole")


def test_a_zip_rewritten_with_the_same_bytes_hits(tmp_path):
    """The key is the content, not the file's time stamps."""
    fmu = tmp_path / "a.fmu"
    with zipfile.ZipFile(fmu, "w") as zf:
        zf.writestr(zipfile.ZipInfo("modelDescription.xml", (2020, 1, 1, 0, 0, 0)), "<x/>")
    before = content_hash(fmu)
    data = fmu.read_bytes()
    fmu.unlink()
    fmu.write_bytes(data)
    assert content_hash(fmu) == before


def test_hits_and_misses_in_parallel_processes_keep_the_input_order(fmus, tmp_path):
    cache = tmp_path / "cache"
    _check(fmus[::3], tmp_path / "some", cache)            # a third of them cached
    _check(fmus, tmp_path / "pooled", cache, "-j", "2")
    lsdae("check", *fmus, "--no-probes", *every_format(tmp_path / "plain"))
    assert outputs(tmp_path / "pooled") == outputs(tmp_path / "plain")


def test_an_interrupted_run_keeps_what_it_checked_and_stores_only_that(fmus, tmp_path):
    from dataclasses import replace

    from conformance.report.catalogue import default_catalogue
    from conformance.run.engine import EngineOptions, check_paths
    from conformance.run.fleet import plan

    options, catalogue = EngineOptions(probes=False), default_catalogue()
    cache = tmp_path / "cache"
    run = plan(fmus[:4], shard=None, cache_dir=str(cache), options=options,
               catalogue=catalogue, rule_options={})
    checked = check_paths(run.todo[:2], options=options, catalogue=catalogue)
    report = run.finish(replace(checked, not_checked=tuple(run.todo[2:])), {})
    assert [f.path for f in report.fmus] == fmus[:2]
    assert report.not_checked == tuple(fmus[2:4])
    assert len(_entries(cache)) == 2
    again = plan(fmus[:4], shard=None, cache_dir=str(cache), options=options,
                 catalogue=catalogue, rule_options={})
    assert sorted(again.hits) == [0, 1] and again.todo == fmus[2:4]
