"""Ctrl-C during a run of many FMUs: the finished reports are written, marked as interrupted,
and lsdae exits within a second (130), also with -j."""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from conformance.run.engine import EngineOptions
from conformance.run.parallel import check_all, check_one
from conformance.report.catalogue import default_catalogue
from tests.fixtures import build_scene

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


def _default_sigint() -> None:
    """Ctrl-C as on a terminal: a suite started in the background (``make test &``, or a
    pytest-xdist worker) passes SIGINT on ignored, and Python keeps an ignored SIGINT."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _read_into(stream, sink: bytearray) -> None:
    for chunk in iter(lambda: stream.read1(4096), b""):
        sink.extend(chunk)


def _workers_of(pid: int) -> list[int]:
    """The probe workers still alive that the process ``pid`` started (their environment
    names their parent: LSDAE_PROBE_PARENT)."""
    mark = f"LSDAE_PROBE_PARENT={pid}".encode()
    alive = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if mark in (entry / "environ").read_bytes().split(b"\0"):
                    alive.append(int(entry.name))
            except OSError:
                pass
    return alive


@pytest.mark.parametrize("jobs, workers", [("1", "auto"), ("2", "auto"), ("1", "2")],
                         ids=["one-job", "two-jobs", "two-probe-workers"])
def test_ctrl_c_writes_the_finished_reports_and_exits_within_a_second(tmp_path, jobs, workers):
    # short names, so that the progress line names the clean FMU whatever the checkout's path
    clean, hanging = "clean.fmu", "hanging.fmu"
    shutil.copy(build_scene("HelloWorldDAE"), tmp_path / clean)
    shutil.copy(build_scene("SimpleDAE", defines=["DEFECT_HANG_DIRECTIONAL"]), tmp_path / hanging)
    out = tmp_path / "report.json"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(
        [sys.executable, "-m", "conformance", "check", clean, hanging, hanging,
         "-j", jobs, "--probe-workers", workers, "--format", f"json:{out}", "--format",
         "console", "--color", "never", "--progress", "always"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True, preexec_fn=_default_sigint)
    stdout, stderr = bytearray(), bytearray()
    readers = [threading.Thread(target=_read_into, args=(proc.stdout, stdout), daemon=True),
               threading.Thread(target=_read_into, args=(proc.stderr, stderr), daemon=True)]
    for reader in readers:
        reader.start()
    try:
        # wait for the progress line of the clean FMU, however loaded the machine; the hanging
        # one then waits for its per-probe limit (60 s), and the second one after it
        deadline = time.monotonic() + 120
        while f"checked {clean}".encode() not in stderr:
            assert proc.poll() is None, "the run ended before it could be interrupted"
            assert time.monotonic() < deadline, bytes(stderr).decode(errors="replace")
            time.sleep(0.1)
        assert proc.poll() is None, "the run ended before it could be interrupted"
        if jobs == "1":   # the hanging FMU's worker runs (what must not outlive the check)
            while not _workers_of(proc.pid):
                assert time.monotonic() < deadline, "no probe worker started"
                time.sleep(0.05)
        sent = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal sends on Ctrl-C
        proc.wait(timeout=10)
        took = time.monotonic() - sent
        for reader in readers:
            reader.join(timeout=10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, bytes(stderr).decode(errors="replace")
    assert took < 2.0, f"exit took {took:.2f} s after Ctrl-C"  # ~0.3 s; room for a busy CI
    data = json.loads(out.read_text())
    assert [f["path"] for f in data["fmus"]] == [clean]
    assert data["interrupted"]["not_checked"] == [hanging, hanging]
    assert b"interrupted" in stdout and b"Traceback" not in stderr
    if jobs == "1":   # no worker of either lane outlives the check (with -j the pool's own
        deadline = time.monotonic() + 5   # processes start them)
        while _workers_of(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _workers_of(proc.pid) == []
