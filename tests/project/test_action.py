"""The GitHub Action: metadata valid against GitHub's schema, and its script run end to end."""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from tests.fixtures import BOOLEAN_DAE, INT_DAE, make_fmu

REPO = Path(__file__).resolve().parents[2]
ACTION = REPO / "action.yml"
SCRIPT = REPO / "scripts" / "action_run.py"


def _check_jsonschema() -> str | None:
    beside = Path(sys.executable).parent / "check-jsonschema"
    return str(beside) if beside.exists() else shutil.which("check-jsonschema")


needs_validator = pytest.mark.skipif(_check_jsonschema() is None,
                                     reason="check-jsonschema is not installed")


@needs_validator
def test_action_metadata_is_valid():
    done = subprocess.run([_check_jsonschema(), "--builtin-schema", "vendor.github-actions",
                           str(ACTION)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def _valid_readme_workflow(heading: str, tmp_path) -> str:
    """The first yaml block of the README section ``heading``, valid as a GitHub workflow."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme.split(heading, 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```yaml\n(.*?)```", section, re.S)
    assert blocks, f"README's section {heading!r} has no yaml example"
    workflow = tmp_path / "workflow.yml"
    workflow.write_text(blocks[0])
    done = subprocess.run([_check_jsonschema(), "--builtin-schema", "vendor.github-workflows",
                           str(workflow)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    return blocks[0]


@needs_validator
def test_readme_example_workflow_is_valid(tmp_path):
    assert "github/codeql-action/upload-sarif" in _valid_readme_workflow("## GitHub Action",
                                                                         tmp_path)


def test_every_input_reaches_the_script():
    from ruamel.yaml import YAML

    meta = YAML(typ="safe").load(ACTION.read_text())
    env = next(s for s in meta["runs"]["steps"] if s.get("id") == "check")["env"]
    for name in meta["inputs"]:
        assert f"${{{{ inputs.{name} }}}}" in env.values(), name
    script = SCRIPT.read_text()
    for var in env:
        assert var in script, var
    for name in ("errors", "warnings", "infos", "fmus"):
        assert name in meta["outputs"]


@pytest.fixture
def workspace(tmp_path):
    """A repository with a clean FMU folder, a faulty one and a packed .fmu."""
    ws = tmp_path / "ws"
    make_fmu(ws / "fmus" / "good")
    make_fmu(ws / "fmus" / "bad", edits=((BOOLEAN_DAE, INT_DAE),))
    source = make_fmu(tmp_path / "packsrc")
    packed = ws / "deep" / "er" / "Packed.fmu"
    packed.parent.mkdir(parents=True)
    with zipfile.ZipFile(packed, "w", zipfile.ZIP_DEFLATED) as zf:
        for f in sorted(source.rglob("*")):
            if f.is_file():
                zf.write(f, f.relative_to(source).as_posix())
    return ws


def _run(ws: Path, *args: str, **inputs: str) -> tuple[int, str, dict[str, str], str]:
    summary, output = ws.parent / "summary.md", ws.parent / "output.txt"
    for f in (summary, output):
        f.write_text("")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("LSDAE_", "GITHUB_"))}
    env.update({"LSDAE_ACTION_SKIP_INSTALL": "1", "GITHUB_STEP_SUMMARY": str(summary),
                "GITHUB_OUTPUT": str(output), "RUNNER_TEMP": str(ws.parent), "CI": "true",
                "LSDAE_ACTION_PATH": str(REPO),
                "PYTHONPATH": str(REPO)})   # the lsdae of this checkout, not one installed
    env.update({f"LSDAE_{k.upper()}": v for k, v in inputs.items()})
    done = subprocess.run([sys.executable, str(SCRIPT), *args], cwd=ws, env=env,
                          capture_output=True, text=True, timeout=300)
    values = dict(line.split("=", 1) for line in output.read_text().splitlines() if "=" in line)
    return done.returncode, done.stdout + done.stderr, values, summary.read_text()


def test_action_script_end_to_end(workspace):
    code, log, out, summary = _run(workspace, fmus="fmus/* **/*.fmu", fail_on="error",
                                   probes="false", junit="reports/junit.xml",
                                   sarif="reports/lsdae.sarif")
    assert code == 1, log
    assert out["fmus"] == "3" and int(out["errors"]) >= 1, out
    assert {"warnings", "infos", "baselined", "report-dir"} <= set(out)
    assert re.search(r"^::error ", log, re.M), log  # annotations for the runner
    assert "fmus/bad" in summary and "fmus/good" in summary
    assert "deep/er/Packed.fmu" in summary
    report_dir = workspace / out["report-dir"]
    for name in ("lsdae.json", "lsdae.md", "lsdae.html"):
        assert (report_dir / name).is_file(), name
    data = json.loads((report_dir / "lsdae.json").read_text())
    assert [f["path"] for f in data["fmus"]] == ["fmus/bad", "fmus/good",
                                                  "deep/er/Packed.fmu"]
    suites = ElementTree.parse(workspace / "reports" / "junit.xml").getroot()
    assert suites.tag in ("testsuites", "testsuite")
    sarif = json.loads((workspace / "reports" / "lsdae.sarif").read_text())
    assert sarif["version"] == "2.1.0" and sarif["runs"][0]["results"]


def test_action_fail_on_never_and_warning(workspace):
    code, log, out, _ = _run(workspace, fmus="fmus/good", fail_on="never", probes="false")
    assert (code, out["errors"], out["fmus"]) == (0, "0", "1"), log
    code, log, out, _ = _run(workspace, fmus="fmus/bad", fail_on="never", probes="false")
    assert code == 0 and int(out["errors"]) >= 1, log
    code, _, _, _ = _run(workspace, fmus="fmus/good", fail_on="warning", probes="false",
                         select="DAE091", ignore="")
    assert code == 0


def test_action_baseline_input(workspace):
    subprocess.run([sys.executable, "-m", "conformance", "check", "fmus/bad", "--no-probes",
                    "--write-baseline", "lsdae-baseline.json"], cwd=workspace, check=True,
                   capture_output=True)
    code, log, out, _ = _run(workspace, fmus="fmus/bad", probes="false",
                             baseline="lsdae-baseline.json")
    assert code == 0, log
    assert out["errors"] == "0" and int(out["baselined"]) >= 1


@pytest.mark.parametrize("inputs", [
    {"fmus": "nothing/*.fmu"}, {"fmus": "fmus/*", "fail_on": "sometimes"},
    {"fmus": "fmus/*", "probes": "maybe"},
])
def test_action_usage_errors(workspace, inputs):
    code, log, _, _ = _run(workspace, **inputs)
    assert code == 2
    assert "::error title=lsdae::" in log


def test_action_fix_input_writes_the_fixed_fmus_and_the_diff(workspace):
    manifest = workspace / "fmus" / "good" / "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
    manifest.write_bytes(manifest.read_bytes().replace(b'support in FMI."', b'support in FMI"'))
    before = manifest.read_bytes()
    _, log, out, _ = _run(workspace, fmus="fmus/*", probes="false", fix="true")
    fixed = workspace / out["report-dir"] / "fixed"
    diff = (fixed / "lsdae-fix.diff").read_text()
    assert "+++ b/extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml" in diff, log
    assert (fixed / "fmus__good").is_dir()
    assert manifest.read_bytes() == before          # the repository itself is not changed


def test_action_shards_and_merge_give_the_unsharded_report(workspace):
    """The matrix of the README: shard jobs, then one merge job over their lsdae.json."""
    everything = dict(fmus="fmus/* **/*.fmu", probes="false", cache="false")
    code, _, _, _ = _run(workspace, report_dir="whole", **everything)
    for index in (1, 2):
        shard_code, log, out, summary = _run(workspace, report_dir=f"shard{index}",
                                             shard=f"{index}/2", fail_on="never", **everything)
        assert shard_code == 0, log
        assert not re.search(r"^::error ", log, re.M), "a shard job annotates (the merge does)"
        assert summary == ""
    merged, log, out, summary = _run(workspace, merge="shard*/lsdae.json", report_dir="merged",
                                     junit="merged/junit.xml", sarif="merged/lsdae.sarif")
    assert merged == code == 1, log
    assert out["fmus"] == "3" and int(out["errors"]) >= 1, out
    assert re.search(r"^::error ", log, re.M), log
    assert "fmus/bad" in summary and "deep/er/Packed.fmu" in summary
    assert (workspace / "merged" / "lsdae.json").read_text() == \
        (workspace / "whole" / "lsdae.json").read_text()
    assert (workspace / "merged" / "junit.xml").is_file()


def test_action_cache_key(workspace):
    _, _, first, _ = _run(workspace, "--cache-key", fmus="fmus/*", shard="2/4")
    assert first["key"].startswith("lsdae-") and "2of4" in first["key"]
    _, _, again, _ = _run(workspace, "--cache-key", fmus="fmus/*", shard="2/4")
    assert again["key"] == first["key"]
    (workspace / "fmus" / "good" / "modelDescription.xml").write_text("<changed/>")
    _, _, changed, _ = _run(workspace, "--cache-key", fmus="fmus/*", shard="2/4")
    assert changed["key"] != first["key"]
    output = (workspace.parent / "output.txt").read_text()
    prefix = re.search(r"restore-keys<<(\w+)\n(.*)\n\1\n", output).group(2)
    assert changed["key"].startswith(prefix) and first["key"].startswith(prefix)
    assert Path(changed["dir"]).is_absolute()


def test_action_cache_input_keeps_results_in_the_cache_folder(workspace, tmp_path):
    cache = tmp_path / "restored-cache"
    code, log, _, _ = _run(workspace, fmus="fmus/*", probes="false", cache="true",
                           cache_dir=str(cache))
    stored = {p: p.stat().st_mtime_ns for p in cache.rglob("*.json")}
    assert len(stored) == 2, log
    again, log, _, _ = _run(workspace, fmus="fmus/*", probes="false", cache="true",
                            cache_dir=str(cache))
    assert again == code, log
    assert {p: p.stat().st_mtime_ns for p in cache.rglob("*.json")} == stored, \
        "the second run wrote its results again: they were not taken from the cache"
    _run(workspace, fmus="fmus/*", probes="false", cache="false", cache_dir=str(tmp_path / "n"))
    assert not (tmp_path / "n").exists()


@needs_validator
def test_readme_matrix_workflow_is_valid(tmp_path):
    """The README's workflow over hundreds of FMUs: shard jobs with the cache, one merge job."""
    workflow = _valid_readme_workflow("## Checking hundreds of FMUs", tmp_path)
    from ruamel.yaml import YAML

    jobs = YAML(typ="safe").load(workflow)["jobs"]
    shards = jobs["check"]["strategy"]["matrix"]["shard"]
    check = next(s for s in jobs["check"]["steps"] if "shard" in s.get("with", {}))["with"]
    assert check["shard"] == f"${{{{ matrix.shard }}}}/{len(shards)}"
    assert check["cache"] == "true"
    merge = next(s for s in jobs["merge"]["steps"] if "merge" in s.get("with", {}))["with"]
    assert jobs["merge"]["needs"] == "check" and merge["junit"] and merge["sarif"]
