"""The pre-commit hook: its manifest, its files pattern, and mapping files to FMU roots."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conformance.commands.cli import main
from conformance.commands.precommit import fmu_root, fmu_roots
from tests.fixtures import BOOLEAN_DAE, INT_DAE
from tests.repokit import repo_file

HOOKS = repo_file(".pre-commit-hooks.yaml")
MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"


def _hooks() -> list[dict]:
    from ruamel.yaml import YAML  # ships with check-jsonschema, a test dependency

    return YAML(typ="safe").load(HOOKS.read_text())


def test_hook_manifest_has_what_pre_commit_requires():
    hooks = _hooks()
    assert [h["id"] for h in hooks] == ["lsdae", "lsdae-static", "lsdae-fix"]
    for hook in hooks:
        assert {"id", "name", "entry", "language"} <= set(hook)
        assert hook["language"] == "python"
        assert hook["entry"].split()[:2] == (["lsdae", "fix"] if hook["id"] == "lsdae-fix"
                                             else ["lsdae", "pre-commit"])
        assert hook["require_serial"] is True


@pytest.mark.parametrize("path, matches", [
    ("models/Pump.fmu", True),
    ("Pump.fmu", True),
    ("models/Pump/modelDescription.xml", True),
    ("modelDescription.xml", True),
    (f"models/Pump/{MANIFEST}", True),
    ("models/Pump/extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml", False),
    ("models/Pump/binaries/x86_64-linux/Pump.so", False),
    ("docs/oldmodelDescription.xml", False),
    ("models/Pump.fmu.bak", False),
])
def test_files_pattern(path, matches):
    # pre-commit applies `files` with re.search to paths relative to the repository root
    for hook in _hooks():
        assert bool(re.search(hook["files"], path)) is matches


@pytest.mark.parametrize("file, root", [
    ("a/B.fmu", "a/B.fmu"),
    ("a/B/modelDescription.xml", "a/B"),
    (f"a/B/{MANIFEST}", "a/B"),
    ("modelDescription.xml", "."),
    (MANIFEST, "."),
    ("a/B/extra/other/fmi-ls-manifest.xml", None),
    ("a/B/README.md", None),
])
def test_file_to_fmu_root(file, root):
    expected = None if root is None else str(Path(root))
    assert fmu_root(file) == expected


def test_roots_are_unique_existing_and_in_order(fmu, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fmu("one")
    fmu("two")
    (tmp_path / "packed.fmu").write_bytes(b"")
    files = ["two/modelDescription.xml", f"one/{MANIFEST}", "one/modelDescription.xml",
             f"two/{MANIFEST}", "packed.fmu", "gone/modelDescription.xml", "notes.txt"]
    assert fmu_roots(files) == ["two", "one", "packed.fmu"]


def test_entry_point_checks_each_fmu_once(fmu, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fmu("good")
    fmu("bad", edits=((BOOLEAN_DAE, INT_DAE),))
    out = tmp_path / "r.json"
    files = ["good/modelDescription.xml", f"good/{MANIFEST}", f"bad/{MANIFEST}"]
    assert main(["pre-commit", "--no-probes", "--format", f"json:{out}", *files]) == 1
    data = json.loads(out.read_text())
    assert [f["path"] for f in data["fmus"]] == ["good", "bad"]
    assert main(["pre-commit", "--no-probes", "--format", f"json:{out}",
                 "good/modelDescription.xml"]) == 0


def test_entry_point_without_fmus_does_nothing(capsys):
    assert main(["pre-commit", "README.md"]) == 0
    assert main(["pre-commit"]) == 0
    assert capsys.readouterr() == ("", "")


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_hook_pattern_against_a_real_git_index(fmu, tmp_path, monkeypatch):
    """The files a commit would pass (git's own paths) map to the FMU folder."""
    monkeypatch.chdir(tmp_path)
    fmu("Pump")
    subprocess.run(["git", "init", "-q"], check=True)
    subprocess.run(["git", "add", "."], check=True)
    staged = subprocess.run(["git", "diff", "--cached", "--name-only"], check=True,
                            capture_output=True, text=True).stdout.split()
    pattern = _hooks()[0]["files"]
    passed = [p for p in staged if re.search(pattern, p)]
    assert sorted(passed) == sorted(["Pump/modelDescription.xml", f"Pump/{MANIFEST}"])
    assert fmu_roots(passed) == ["Pump"]
