"""conformance/run/fleet.py in this process, without checking FMUs: the shard section of a
shard's report, what an interrupted run leaves unchecked, the cache's note, and the code
fingerprint."""
from __future__ import annotations

import hashlib
from importlib import metadata
from pathlib import Path

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import FmuReport, Report, thaw
from conformance.report.paths import schemas_dir
from conformance.run import fleet
from conformance.run.engine import EngineOptions
from conformance.run.sharding import assign, input_names, input_size, inputs_digest

CATALOGUE = default_catalogue()
OPTIONS = EngineOptions(probes=False)


def _inputs(tmp_path: Path) -> list[str]:
    paths = []
    for name, size in (("a.fmu", 30), ("b.fmu", 10), ("c.fmu", 20), ("d.fmu", 5)):
        (tmp_path / name).write_bytes(b"x" * size)
        paths.append(str(tmp_path / name))
    return paths


def _checked(paths) -> Report:
    return Report("1", tuple(FmuReport(p, None, ()) for p in paths))


def test_a_shard_checks_its_share_and_says_where_it_belongs(tmp_path):
    paths = _inputs(tmp_path)
    names, sizes = input_names(paths), [input_size(p) for p in paths]
    shard_of = assign(names, sizes, 2)
    run = fleet.plan(paths, shard="2/2", cache_dir=None, options=OPTIONS, catalogue=CATALOGUE,
                     rule_options={"DAE740": {"rtol": 1e-3}})
    mine = [i for i, k in enumerate(shard_of) if k == 2]
    assert list(run.selected) == mine == run.todo_positions and run.todo == [paths[i]
                                                                              for i in mine]
    assert (run.shard, run.names, run.sizes) == ((2, 2), names, sizes)
    report = run.finish(_checked(run.todo), {paths[mine[0]]: 1.23456, paths[mine[1]]: 2.0004})
    assert [f.path for f in report.fmus] == run.todo and report.not_checked == ()
    assert thaw(report.shard) == {
        "index": 2, "count": 2, "inputs": 4, "inputs_digest": inputs_digest(names, sizes),
        "settings": fleet.settings_fingerprint(CATALOGUE, OPTIONS),
        "catalogue": fleet.catalogue_fingerprint(CATALOGUE),
        "rule_options": {"DAE740": {"rtol": 1e-3}}, "positions": mine,
        "durations": [1.235, 2.0]}


def test_a_run_without_shard_or_cache_checks_everything_in_order(tmp_path):
    paths = _inputs(tmp_path)
    run = fleet.plan(paths, shard=None, cache_dir=None, options=OPTIONS, catalogue=CATALOGUE,
                     rule_options={})
    assert run.todo == paths and run.selected == (0, 1, 2, 3) and run.cache is None
    report = run.finish(_checked(paths[:2]), {})
    assert [f.path for f in report.fmus] == paths[:2]
    assert report.not_checked == tuple(paths[2:]) and report.shard == ()


def test_the_cache_note_counts_the_fmus(tmp_path, capsys):
    paths = _inputs(tmp_path)
    cache = tmp_path / "cache"
    one = fleet.plan(paths[:1], shard=None, cache_dir=str(cache), options=OPTIONS,
                     catalogue=CATALOGUE, rule_options={})
    one.finish(_checked(paths[:1]), {})
    assert capsys.readouterr().err == (f"lsdae: cache {cache}: 0 of 1 FMU unchanged, not "
                                       "checked again; 1 stored\n")
    both = fleet.plan(paths[:2], shard=None, cache_dir=str(cache), options=OPTIONS,
                      catalogue=CATALOGUE, rule_options={})
    assert sorted(both.hits) == [0] and both.todo == paths[1:2]
    durations: dict[str, float] = {}
    both.finish(_checked(paths[1:2]), durations)
    assert capsys.readouterr().err == (f"lsdae: cache {cache}: 1 of 2 FMUs unchanged, not "
                                       "checked again; 1 stored\n")
    assert durations == {paths[0]: 0.0}


def test_the_code_fingerprint_is_the_package_and_the_schemas():
    """Every .py and .xsd of conformance/ and of the schemas (path and bytes), then the
    libraries' versions."""
    digest = hashlib.sha256()
    package = Path(fleet.__file__).resolve().parents[1]
    for root in (package, schemas_dir()):
        for file in sorted(root.rglob("*")):
            if file.suffix in (".py", ".xsd") and file.is_file():
                digest.update(file.relative_to(root).as_posix().encode() + b"\0")
                digest.update(file.read_bytes())
    for name in fleet.LIBRARIES:
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = "-"
        digest.update(f"{name}={version}\n".encode())
    assert package.name == "conformance"
    assert fleet.code_fingerprint() == digest.hexdigest()


def test_the_settings_fingerprint_is_version_catalogue_and_options_but_the_workers():
    import dataclasses
    import json

    from conformance import __version__

    options = EngineOptions(probes=False, select=("DAE1",), severity=(("DAE101", "info"),),
                            probe_workers=2)
    chosen = {k: v for k, v in dataclasses.asdict(options).items() if k != "probe_workers"}
    text = json.dumps({"version": __version__, "catalogue": fleet.catalogue_fingerprint(CATALOGUE),
                       "options": chosen}, sort_keys=True, default=str)
    assert fleet.settings_fingerprint(CATALOGUE, options) == hashlib.sha256(
        text.encode("utf-8")).hexdigest()
    assert fleet.settings_fingerprint(CATALOGUE, options) == fleet.settings_fingerprint(
        CATALOGUE, dataclasses.replace(options, probe_workers=1))
    assert fleet.catalogue_fingerprint(CATALOGUE) == hashlib.sha256(
        "\n".join(repr(r) for r in CATALOGUE).encode("utf-8")).hexdigest()
