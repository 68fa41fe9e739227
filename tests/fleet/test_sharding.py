"""``lsdae check --shard I/N``: every FMU in exactly one shard, the same split everywhere."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conformance.run.sharding import assign, input_names, input_size, parse_shard
from tests.fleet.conftest import lsdae

REPO = Path(__file__).resolve().parents[2]

names = st.lists(st.text(alphabet="abcdefgh/._-", min_size=1, max_size=12), min_size=0,
                 max_size=60, unique=True)


@given(names=names, data=st.data(), count=st.integers(min_value=1, max_value=20))
@settings(max_examples=300, deadline=None)
def test_every_input_is_in_exactly_one_shard(names, data, count):
    sizes = data.draw(st.lists(st.integers(min_value=0, max_value=10**9), min_size=len(names),
                               max_size=len(names)))
    shard_of = assign(names, sizes, count)
    assert len(shard_of) == len(names)
    assert all(1 <= k <= count for k in shard_of)
    members = [[i for i, k in enumerate(shard_of) if k == s] for s in range(1, count + 1)]
    assert sorted(i for m in members for i in m) == list(range(len(names)))


@given(names=names, data=st.data(), count=st.integers(min_value=1, max_value=12))
@settings(max_examples=200, deadline=None)
def test_the_split_does_not_depend_on_the_order_of_the_arguments(names, data, count):
    sizes = data.draw(st.lists(st.integers(min_value=0, max_value=10**6), min_size=len(names),
                               max_size=len(names)))
    order = data.draw(st.permutations(range(len(names))))
    first = dict(zip(names, assign(names, sizes, count)))
    again = assign([names[i] for i in order], [sizes[i] for i in order], count)
    assert dict(zip([names[i] for i in order], again)) == first


@given(sizes=st.lists(st.integers(min_value=1, max_value=1000), min_size=1, max_size=80),
       count=st.integers(min_value=1, max_value=10))
@settings(max_examples=200, deadline=None)
def test_the_split_is_balanced_by_size(sizes, count):
    """Greedy largest-first: no shard exceeds the even share by more than the largest FMU."""
    shard_of = assign([f"m{i}" for i in range(len(sizes))], sizes, count)
    loads = [sum(s for s, k in zip(sizes, shard_of) if k == shard) for shard in
             range(1, count + 1)]
    assert max(loads) <= sum(sizes) / count + max(sizes)


def test_equal_and_empty_fmus_are_spread_by_number():
    assert sorted(assign([f"m{i}" for i in range(9)], [0] * 9, 3)) == [1, 1, 1, 2, 2, 2, 3, 3, 3]


@pytest.mark.parametrize("text,expected", [("1/1", (1, 1)), ("2/8", (2, 8)), (" 3 / 3 ", (3, 3))])
def test_parse_shard(text, expected):
    assert parse_shard(text) == expected


@pytest.mark.parametrize("text", ["0/3", "4/3", "x", "1/0", "", "1/", "/3", "-1/3", "1.5/3",
                                  "1/3/5"])
def test_parse_shard_refuses(text):
    with pytest.raises(ValueError):
        parse_shard(text)


def test_sizes_of_files_and_folders(tmp_path):
    (tmp_path / "a.fmu").write_bytes(b"x" * 123)
    folder = tmp_path / "b"
    (folder / "sub").mkdir(parents=True)
    (folder / "modelDescription.xml").write_bytes(b"y" * 10)
    (folder / "sub" / "f").write_bytes(b"z" * 5)
    assert input_size(tmp_path / "a.fmu") == 123
    assert input_size(folder) == 15
    assert input_size(tmp_path / "missing.fmu") == 0


def test_names_do_not_depend_on_where_the_inputs_are(tmp_path, monkeypatch):
    relative = ["fmus/a.fmu", "fmus/deep/b", "other/c.fmu"]
    monkeypatch.chdir(tmp_path)
    assert input_names(relative) == ["fmus/a.fmu", "fmus/deep/b", "other/c.fmu"]
    assert input_names([str(tmp_path / p) for p in relative]) == input_names(relative)
    assert input_names(["x/y/one.fmu"]) == ["one.fmu"]


def _shard_paths(paths: list[str], count: int, tmp_path: Path) -> list[list[str]]:
    shards = []
    for index in range(1, count + 1):
        out = tmp_path / f"shard{index}.json"
        code, _, err = lsdae("check", *paths, "--no-probes", "--shard", f"{index}/{count}",
                             "--fail-on", "never", "--format", f"json:{out}")
        assert code == 0, err
        data = json.loads(out.read_text())
        assert data["shard"]["index"] == index and data["shard"]["count"] == count
        assert [paths[p] for p in data["shard"]["positions"]] == [f["path"] for f in
                                                                 data["fmus"]]
        shards.append([f["path"] for f in data["fmus"]])
    return shards


@pytest.mark.parametrize("count", [1, 2, 3, 7, 40])
def test_the_shard_jobs_check_every_fmu_once(fixture_fmus, tmp_path, count):
    paths = fixture_fmus[:30]
    shards = _shard_paths(paths, count, tmp_path)
    assert sorted(p for s in shards for p in s) == sorted(paths)
    if count > len(paths):
        assert [] in shards   # an empty shard writes a valid, empty report


def test_the_split_is_the_same_from_another_folder(fixture_fmus, tmp_path, monkeypatch):
    """Relative paths from one folder, absolute from another: the same FMUs per shard."""
    paths = fixture_fmus[:12]
    common = Path(os.path.commonpath(paths))
    monkeypatch.chdir(common)
    relative = [os.path.relpath(p, common) for p in paths]
    here = _shard_paths(relative, 3, tmp_path / "rel")
    monkeypatch.chdir(tmp_path)
    there = _shard_paths(paths, 3, tmp_path / "abs")
    assert [[os.path.relpath(p, common) for p in s] for s in there] == here


def test_an_empty_shard_exits_zero_with_an_empty_report(scene_fmus, tmp_path):
    out = tmp_path / "empty.json"
    code, _, err = lsdae("check", scene_fmus[0], "--no-probes", "--shard", "2/2",
                         "--format", f"json:{out}")
    assert code == 0, err
    data = json.loads(out.read_text())
    assert data["fmus"] == [] and data["shard"]["positions"] == []


@pytest.mark.parametrize("value", ["0/3", "4/3", "x", "1/0", "3"])
def test_a_bad_shard_is_a_usage_error(value, scene_fmus):
    done = subprocess.run([sys.executable, "-m", "conformance", "check", scene_fmus[0],
                           "--no-probes", "--shard", value], capture_output=True, text=True,
                          cwd=REPO)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert done.stdout == ""
