"""One check per question: the report of an FMU checked with given options, computed once per
test session and handed to every test that asks the same question.

A probe check costs seconds (a worker process, the simulation, the endurance run); many tests
ask the same question of the same FMU (a defect variant that test_defects.py checks in full and
a family test checks again, a fixed FMU two tests compare). A report is immutable
(``conformance.report.findings``: frozen dataclasses, evidence as tuples), so one object can
serve them all.

The key is the question: the path as given (the report carries it), the file's content (a
folder: every file's name and content), the options and the catalogue (the default one only).
The session has one folder for them (``tests/conftest.py`` sets :data:`SHARED`; under
pytest-xdist the parent of each worker's basetemp, so both workers share it): the first process
to ask computes the report under a file lock and pickles it; the other reads it. Without the
folder (outside pytest) the reports are kept in this process only. An FMU a test writes itself
(a fixed FMU in ``tmp_path``) asks the same question as another test's when it is the same
file at the same path: :func:`by_content` gives it a path named by its content.

Tests that are about the run itself (determinism, worker counts, timing, deaths, limits) call
``check_fmu`` directly: they need a fresh run, not an answer.
"""
from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from pathlib import Path

from conformance.report.findings import FmuReport
from conformance.run.engine import EngineOptions, check_fmu

#: The session's folder for reports shared between pytest-xdist workers (None: this process).
SHARED: Path | None = None

_REPORTS: dict[str, FmuReport] = {}


def _content(path: Path) -> bytes:
    """The digest of what is checked: a file's bytes, or a folder's file names and bytes."""
    digest = hashlib.sha256()
    if path.is_dir():
        for item in sorted(p for p in path.rglob("*") if p.is_file()):
            digest.update(item.relative_to(path).as_posix().encode() + b"\0")
            digest.update(item.read_bytes())
    else:
        digest.update(path.read_bytes())
    return digest.digest()


def _key(path: Path, options: EngineOptions) -> str:
    question = repr((str(path), _content(path).hex(), options))
    return hashlib.sha256(question.encode()).hexdigest()[:32]


def by_content(path: Path) -> Path:
    """A copy of the file ``path`` in the session's folder, named by its content (``path``
    itself outside a session)."""
    if SHARED is None:
        return path
    data = path.read_bytes()
    target = SHARED / "by-content" / f"{hashlib.sha256(data).hexdigest()[:32]}{path.suffix}"
    if not target.is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_suffix(f".{os.getpid()}.tmp")
        partial.write_bytes(data)
        os.replace(partial, target)
    return target


def checked(path: Path | str, *, options: EngineOptions) -> FmuReport:
    """``check_fmu(path, options=options)``, once per session for each (path, content,
    options); the default catalogue."""
    path = Path(path)
    key = _key(path, options)
    if key in _REPORTS:
        return _REPORTS[key]
    if SHARED is None:
        report = _REPORTS[key] = check_fmu(path, options=options)
        return report
    SHARED.mkdir(parents=True, exist_ok=True)
    stored = SHARED / f"{key}.pickle"
    with open(SHARED / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)     # the other worker waits for the same report
        if stored.is_file():
            report = pickle.loads(stored.read_bytes())
        else:
            report = check_fmu(path, options=options)
            partial = stored.with_suffix(f".{os.getpid()}.tmp")
            partial.write_bytes(pickle.dumps(report))
            os.replace(partial, stored)
    _REPORTS[key] = report
    return report
