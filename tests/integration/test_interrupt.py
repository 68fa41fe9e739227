"""Ctrl-C during a run of many FMUs: the finished reports are written, marked as interrupted,
and lsdae exits within a second (130), also with -j."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conformance.run.engine import EngineOptions
from conformance.run.parallel import check_all, check_one
from conformance.report.catalogue import default_catalogue
from scenes.build import build_scene

REPO = Path(__file__).resolve().parents[2]


def test_check_all_keeps_what_finished_when_interrupted(tmp_path):
    calls = []

    def worker(path, options, catalogue):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return check_one(path, options, catalogue)

    fmu = str(build_scene("HelloWorldDAE"))
    report = check_all([fmu, "second.fmu", "third.fmu"], options=EngineOptions(probes=False),
                       catalogue=default_catalogue(), worker=worker)
    assert [f.path for f in report.fmus] == [fmu]
    assert report.interrupted and report.not_checked == ("second.fmu", "third.fmu")


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_ctrl_c_writes_the_finished_reports_and_exits_within_a_second(tmp_path, jobs):
    clean = build_scene("HelloWorldDAE")
    hanging = build_scene("SimpleDAE", defines=["DEFECT_HANG_DIRECTIONAL"])
    out = tmp_path / "report.json"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(
        [sys.executable, "-m", "conformance", "check", str(clean), str(hanging), str(hanging),
         "-j", jobs, "--format", f"json:{out}", "--format", "console", "--color", "never"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True)
    try:
        time.sleep(8.0)  # the clean FMU is done, the hanging one waits for its 20 s limit
        assert proc.poll() is None, "the run ended before it could be interrupted"
        sent = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal sends on Ctrl-C
        stdout, stderr = proc.communicate(timeout=10)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, stderr.decode()
    assert took < 2.0, f"exit took {took:.2f} s after Ctrl-C"  # ~0.3 s; room for a busy CI
    data = json.loads(out.read_text())
    assert [f["path"] for f in data["fmus"]] == [str(clean)]
    assert data["interrupted"]["not_checked"] == [str(hanging), str(hanging)]
    assert b"interrupted" in stdout and b"Traceback" not in stderr
