"""``lsdae merge``: the shards' reports joined are the unsharded report, in every format."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from conformance import __version__
from tests.fixtures import build_scene
from tests.clikit import every_format, lsdae, outputs


def _shards(paths: list[str], count: int, folder: Path, *options: str) -> list[str]:
    files = []
    for index in range(1, count + 1):
        out = folder / f"shard{index}.json"
        code, _, err = lsdae("check", *paths, *options, "--shard", f"{index}/{count}",
                             "--exit-zero", "--format", f"json:{out}")
        assert code == 0, err
        files.append(str(out))
    return files


@pytest.fixture(scope="module")
def fleet(scene_fmus, fixture_fmus):
    """Every rule fixture and the scenes (binaries not loaded), in a mixed order."""
    return fixture_fmus[:110] + scene_fmus + fixture_fmus[110:]


@pytest.mark.parametrize("count,which", [(3, "fleet"), (8, "scene_fmus")])
def test_merged_shards_are_the_unsharded_report_in_every_format(request, tmp_path, count,
                                                                which):
    """225 FMUs in 3 shards; 5 in 8 (three shards empty)."""
    fleet = request.getfixturevalue(which)
    code, _, err = lsdae("check", *fleet, "--no-probes", *every_format(tmp_path / "whole"))
    assert code in (0, 1), err
    shards = _shards(fleet, count, tmp_path, "--no-probes")
    merged, _, err = lsdae("merge", *reversed(shards), *every_format(tmp_path / "merged"))
    assert merged == code, err
    whole, joined = outputs(tmp_path / "whole"), outputs(tmp_path / "merged")
    for name in whole:
        assert joined[name] == whole[name], f"the merged {name} report differs"


def test_merged_probe_shards_are_the_unsharded_report(tmp_path):
    """With the binaries checked: probe findings carry measured numbers in their evidence."""
    paths = [str(build_scene("HelloWorldDAE")),
             str(build_scene("SimpleDAE", defines=["DEFECT_WRONG_JACOBIAN"])),
             str(build_scene("VanDerPolDAE"))]
    code, _, err = lsdae("check", *paths, *every_format(tmp_path / "whole"))
    assert code == 1, err
    shards = _shards(paths, 2, tmp_path)
    merged, _, err = lsdae("merge", *shards, *every_format(tmp_path / "merged"))
    assert merged == code, err
    whole, joined = outputs(tmp_path / "whole"), outputs(tmp_path / "merged")
    assert json.loads(whole["json"])["fmus"][1]["findings"], "the defect was not found"
    for name in whole:
        assert joined[name] == whole[name], f"the merged {name} report differs"


@pytest.fixture(scope="module")
def three(scene_fmus, fixture_fmus, tmp_path_factory):
    """Three shard reports of one run, and the paths they were made from."""
    folder = tmp_path_factory.mktemp("three")
    paths = fixture_fmus[:20] + scene_fmus[:2]
    return _shards(paths, 3, folder, "--no-probes"), paths


def _edited(source: str, folder: Path, edit) -> str:
    data = json.loads(Path(source).read_text())
    edit(data)
    out = folder / f"edited-{Path(source).name}"
    out.write_text(json.dumps(data))
    return str(out)


def _set(path: str, value):
    def edit(data):
        *keys, last = path.split(".")
        target = data
        for key in keys:
            target = target[int(key)] if key.isdigit() else target[key]
        target[last] = value
    return edit


def _text(folder: Path, name: str, text: str) -> str:
    (folder / name).write_text(text, encoding="utf-8")
    return str(folder / name)


BAD = {
    "one shard missing": lambda s, f: s[:2],
    "a shard twice": lambda s, f: [s[0], s[1], s[1], s[2]],
    "not JSON": lambda s, f: [*s[:2], _text(f, "notes.md", "# notes\n")],
    "not a file": lambda s, f: [*s[:2], str(f / "missing.json")],
    "not an lsdae report": lambda s, f: [*s[:2], _text(f, "pyproject.toml", "[tool.lsdae]\n"),
                                         s[2]],
    "JSON of something else": lambda s, f: [*s[:2], _edited(s[2], f, lambda d: d.clear())],
    "an unsharded report": lambda s, f: [*s[:2], _edited(s[2], f, lambda d: d.pop("shard"))],
    "another lsdae version": lambda s, f: [*s[:2], _edited(s[2], f, _set("version", "0.0.1"))],
    "other options": lambda s, f: [*s[:2], _edited(s[2], f, _set("options.seed", 7))],
    "other settings": lambda s, f: [*s[:2], _edited(s[2], f, _set("shard.settings", "0"))],
    "another catalogue": lambda s, f: [_edited(x, f, _set("shard.catalogue", "0")) for x in s],
    "other inputs": lambda s, f: [*s[:2], _edited(s[2], f, _set("shard.inputs_digest", "0"))],
    "another shard count": lambda s, f: [*s[:2], _edited(s[2], f, _set("shard.count", 4))],
    "an FMU in two shards": lambda s, f: [
        s[0], s[1], _edited(s[2], f, lambda d: (d["fmus"].append(d["fmus"][0]),
                                                 d["shard"]["positions"].append(
                                                     json.loads(Path(s[1]).read_text())
                                                     ["shard"]["positions"][0]),
                                                 d["shard"]["durations"].append(0.0)))],
    "positions damaged": lambda s, f: [*s[:2], _edited(s[2], f, _set("shard.positions", [0]))],
    "an interrupted shard": lambda s, f: [
        *s[:2], _edited(s[2], f, _set("interrupted", {"not_checked": ["x.fmu"]}))],
    "a baselined shard": lambda s, f: [
        *s[:2], _edited(s[2], f, _set("options.baseline", {"file": "b.json"}))],
}

# The one line each prints: {s1}..{s3} the shard reports, {e1}, {e3} edited copies of shards 1
# and 3, {f} the test's folder.
MESSAGES = {
    "one shard missing": "shard 3 of 3 missing: give the JSON report of every shard",
    "a shard twice": "shard 2/3 is given twice: {s2} and {s2}",
    "not JSON": "{f}/notes.md is not JSON: Expecting value: line 1 column 1 (char 0)",
    "not a file": "cannot read {f}/missing.json: No such file or directory",
    "not an lsdae report": "{f}/pyproject.toml is not JSON: Expecting value: line 1 column 2 "
                           "(char 1)",
    "JSON of something else": '{e3}: not an lsdae JSON report (no "tool": "lsdae")',
    "an unsharded report": "{e3} is not a shard report (it was written without --shard I/N)",
    "another lsdae version": f"{{e3}} was written by lsdae 0.0.1; this is lsdae {__version__}: "
                             "merge with the version that checked",
    "other options": "{e3} (shard 3/3) does not belong with {s1} (shard 1/3): the options "
                     "differ",
    "other settings": "{e3} (shard 3/3) does not belong with {s1} (shard 1/3): the lsdae "
                      "version, rule catalogue or options differ",
    "another catalogue": "{e1} (shard 1/3) was checked with another rule catalogue than this "
                         "lsdae's (another installation or rules/): merge where the shards ran",
    "other inputs": "{e3} (shard 3/3) does not belong with {s1} (shard 1/3): the FMUs given "
                    "(paths, order or sizes) differ",
    "another shard count": "{e3} (shard 3/4) does not belong with {s1} (shard 1/3): the number "
                           "of shards differ",
    "an FMU in two shards": "an FMU is in two shards: {fmu3} in {e3} (shard 3/3) and {fmu2} in "
                            "{s2} (shard 2/3)",
    "positions damaged": "{e3}: the shard section is damaged",
    "an interrupted shard": "{e3} (shard 3/3) was interrupted (1 FMUs not checked): run that "
                            "shard again",
    "a baselined shard": "{e3} (shard 3/3) has a baseline applied; a shard report must not (give "
                         "the baseline to lsdae merge)",
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_inputs_that_do_not_belong_together_are_a_usage_error(three, tmp_path, case):
    shards, _ = three
    code, out, err = lsdae("merge", *BAD[case](shards, tmp_path), "--format", "json")
    first = json.loads(Path(shards[2]).read_text())["fmus"][0]["path"]
    placed = json.loads(Path(shards[1]).read_text())["fmus"][0]["path"]
    names = {"s1": shards[0], "s2": shards[1], "s3": shards[2], "f": str(tmp_path),
             "e1": str(tmp_path / "edited-shard1.json"),
             "e3": str(tmp_path / "edited-shard3.json"), "fmu3": first, "fmu2": placed}
    assert (code, out, err) == (2, "", f"lsdae: {MESSAGES[case].format(**names)}\n")


def test_the_three_shards_do_merge(three, tmp_path):
    """The reports the bad cases edit are good ones: unedited, they merge."""
    shards, paths = three
    out = tmp_path / "merged.json"
    code, _, err = lsdae("merge", *shards, "--format", f"json:{out}")
    assert code in (0, 1), err
    assert [f["path"] for f in json.loads(out.read_text())["fmus"]] == paths
    assert json.loads(out.read_text())["version"] == __version__


def test_merge_exit_codes_follow_check(three, tmp_path):
    shards, paths = three
    quiet = ("--format", f"json:{tmp_path / 'm.json'}")
    code, _, _ = lsdae("check", *paths, "--no-probes", *quiet)
    assert code == 1   # the fixtures hold errors
    assert lsdae("merge", *shards, *quiet)[0] == 1
    assert lsdae("merge", *shards, "--fail-on", "never", *quiet)[0] == 0
    assert lsdae("merge", *shards, "--exit-zero", *quiet)[0] == 0
    baseline = tmp_path / "baseline.json"
    lsdae("check", *paths, "--no-probes", "--write-baseline", str(baseline), *quiet)
    assert lsdae("merge", *shards, "--baseline", str(baseline), *quiet)[0] == 0
    checked = tmp_path / "checked.json"
    lsdae("check", *paths, "--no-probes", "--baseline", str(baseline),
          "--format", f"json:{checked}")
    assert (tmp_path / "m.json").read_text() == checked.read_text()


def test_a_shard_applies_no_baseline_the_merge_does(three, tmp_path):
    _, paths = three
    baseline = tmp_path / "baseline.json"
    lsdae("check", *paths, "--no-probes", "--write-baseline", str(baseline), "--format",
          f"json:{tmp_path / 'w.json'}")
    shards = _shards(paths, 2, tmp_path, "--no-probes", "--baseline", str(baseline))
    for shard in shards:
        data = json.loads(Path(shard).read_text())
        assert "baseline" not in data["options"]
        assert not any(f["evidence"].get("baselined") for fmu in data["fmus"]
                       for f in fmu["findings"] if isinstance(f["evidence"], dict))
    code, _, _ = lsdae("check", *paths, "--no-probes", "--baseline", str(baseline),
                       *every_format(tmp_path / "whole"))
    merged, _, err = lsdae("merge", *shards, "--baseline", str(baseline),
                           *every_format(tmp_path / "merged"))
    assert merged == code == 0, err
    assert outputs(tmp_path / "merged") == outputs(tmp_path / "whole")
