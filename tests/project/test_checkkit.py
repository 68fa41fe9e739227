"""tests/checkkit.py: one check per question, across processes, and a new question for a new
content or new options (the sharing of the two pytest-xdist workers, tests/fixtures/README.md)."""
from __future__ import annotations

import multiprocessing
import time
from pathlib import Path

import pytest

from conformance.run.engine import EngineOptions
from tests import checkkit

CALLS = "calls.log"


def _counting_check(folder: Path, seconds: float = 0.0):
    """A stand-in for check_fmu that appends one line per call to ``folder/calls.log`` (a file:
    the calls of other processes count too), takes ``seconds`` and returns a small immutable
    answer."""
    def check(path, *, options):
        time.sleep(seconds)
        with open(folder / CALLS, "a") as log:
            log.write(f"{path}\n")
        content = Path(path).read_bytes() if Path(path).is_file() else b""
        return (str(path), content, options.probes)
    return check


def _calls(folder: Path) -> int:
    log = folder / CALLS
    return len(log.read_text().splitlines()) if log.exists() else 0


@pytest.fixture
def session(tmp_path, monkeypatch):
    """checkkit with its own session folder and the counting stand-in; the process's memory of
    reports emptied, so every question starts unasked."""
    monkeypatch.setattr(checkkit, "SHARED", tmp_path / "checked")
    monkeypatch.setattr(checkkit, "_REPORTS", {})
    monkeypatch.setattr(checkkit, "check_fmu", _counting_check(tmp_path))
    return tmp_path


def test_the_same_question_is_checked_once(session):
    archive = session / "a.fmu"
    archive.write_bytes(b"one")
    first = checkkit.checked(archive, options=EngineOptions(probes=False))
    checkkit._REPORTS.clear()          # another process: only the session folder remembers
    second = checkkit.checked(archive, options=EngineOptions(probes=False))
    assert first == second
    assert _calls(session) == 1


def test_new_content_or_new_options_are_a_new_question(session):
    archive = session / "a.fmu"
    archive.write_bytes(b"one")
    checkkit.checked(archive, options=EngineOptions(probes=False))
    checkkit.checked(archive, options=EngineOptions(probes=True))
    archive.write_bytes(b"two")
    changed = checkkit.checked(archive, options=EngineOptions(probes=False))
    assert changed[1] == b"two"
    assert _calls(session) == 3


def test_a_folder_is_keyed_on_its_files_names_and_bytes(session):
    folder = session / "archive"
    (folder / "sub").mkdir(parents=True)
    (folder / "sub" / "x.xml").write_bytes(b"<a/>")
    options = EngineOptions(probes=False)
    checkkit.checked(folder, options=options)
    (folder / "sub" / "x.xml").rename(folder / "sub" / "y.xml")
    checkkit.checked(folder, options=options)
    assert _calls(session) == 2


def test_by_content_names_the_same_bytes_alike(session):
    one, two = session / "one" / "f.fmu", session / "two" / "f.fmu"
    for path in (one, two):
        path.parent.mkdir()
        path.write_bytes(b"same")
    assert checkkit.by_content(one) == checkkit.by_content(two) != one
    assert checkkit.by_content(one).read_bytes() == b"same"


def _ask(shared: str, folder: str, archive: str, start) -> None:
    checkkit.SHARED = Path(shared)
    checkkit._REPORTS.clear()
    checkkit.check_fmu = _counting_check(Path(folder), seconds=0.3)   # long enough to overlap
    start.wait()
    checkkit.checked(Path(archive), options=EngineOptions(probes=False))


def test_processes_asking_at_once_share_one_check(session):
    """Four processes ask the same question at the same moment: the lock lets one compute it."""
    archive = session / "a.fmu"
    archive.write_bytes(b"one")
    context = multiprocessing.get_context("fork")
    start = context.Barrier(4)
    workers = [context.Process(target=_ask, args=(str(checkkit.SHARED), str(session), str(archive),
                                                  start)) for _ in range(4)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(60)
    assert [worker.exitcode for worker in workers] == [0] * 4
    assert _calls(session) == 1
