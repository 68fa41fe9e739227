"""Each command imports only what it uses (issue 11: instant start for pre-commit hooks).

Every case runs ``conformance.commands.cli.main`` in a fresh interpreter and lists the heavy modules
that ended up in ``sys.modules``. A module a command does not use must not be there: the engine is
not loaded by ``--version``, lxml not by ``lsdae rules``, numpy and scipy not by a static check of a
small FMU, multiprocessing not without ``-j``; and the probes' numpy, fmpy and probe families
only in the probe worker, never in the process that runs the command.
"""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.fixtures import build_scene

#: The modules the issue names as heavy, plus lxml for the commands that read no XML.
HEAVY = ("numpy", "scipy", "xmlschema", "fmpy", "matplotlib", "multiprocessing")

_PROBE = """
import contextlib, io, json, sys
from conformance.commands.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _loaded(argv: list[str]) -> tuple[int, set[str]]:
    proc = subprocess.run([sys.executable, "-c", _PROBE, *argv], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout.strip().splitlines()[-1])
    return data["code"], {m.split(".")[0] for m in data["modules"]} | set(data["modules"])


@pytest.fixture(scope="module")
def small_fmu() -> str:
    return str(build_scene("HelloWorldDAE"))


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["rules"],
                                  ["rules", "--format", "markdown"], ["explain", "DAE601"],
                                  ["check", "--help"], ["simulate", "--help"], ["fix", "--help"]],
                         ids=" ".join)
def test_commands_that_read_no_fmu_load_no_heavy_module_and_no_xml_library(argv):
    code, loaded = _loaded(argv)
    assert code == 0
    assert sorted(loaded & {*HEAVY, "lxml", "conformance.run.engine"}) == []


def test_a_static_check_of_a_small_fmu_loads_no_numerical_library(small_fmu, tmp_path):
    code, loaded = _loaded(["check", "--no-probes", small_fmu,
                            "--format", f"json:{tmp_path / 'r.json'}"])
    assert code == 0
    assert sorted(loaded & set(HEAVY)) == []
    assert "conformance.reporters.html" not in loaded  # only the formats asked for


def test_a_full_check_loads_the_binary_only_in_the_probe_worker(small_fmu, tmp_path):
    code, loaded = _loaded(["check", small_fmu, "--format", f"json:{tmp_path / 'r.json'}"])
    assert code == 0
    assert "conformance.probes.machinery.runner" in loaded  # the probes ran, in a worker process
    assert sorted(loaded & set(HEAVY)) == []  # the worker loads numpy, fmpy and the probes
    from conformance.probes.machinery.registry import FAMILIES
    families = {f"conformance.probes.{family}" for family in FAMILIES}
    assert sorted(m for m in loaded if m.rsplit(".", 1)[0] in families or m in families) == []


def test_only_parallel_checks_load_multiprocessing(small_fmu, tmp_path):
    code, loaded = _loaded(["check", "--no-probes", "-j", "2", small_fmu, small_fmu,
                            "--format", f"json:{tmp_path / 'r.json'}"])
    assert code == 0
    assert "multiprocessing" in loaded  # the test would notice a pool that never started
