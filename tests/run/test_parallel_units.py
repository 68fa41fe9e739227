"""conformance/run/parallel.py in this process: the order of the reports, the FMUs an interrupted
run did not check, the durations, and the finding of an FMU whose check never completed (the -j
runs themselves are in test_parallel_progress.py)."""
from __future__ import annotations

import logging

import pytest

from conformance.report.catalogue import default_catalogue, with_options
from conformance.report.findings import FmuReport, Location, Severity, evidence
from conformance.run import parallel
from conformance.run.engine import EngineOptions
from conformance.run.parallel import check_all, check_one, crashed
from conformance.run.progress import Progress

CATALOGUE = default_catalogue()
STATIC = EngineOptions(probes=False)
#: what an internal error's message ends with: its basis is a limit of lsdae's (the catalogue)
SAID = f" (lsdae's own limit, not a verdict on the FMU: {CATALOGUE['internal-error'].basis.word})"


class Recorded(Progress):
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def start(self, path: str) -> None:
        self.events.append(("start", path))

    def finish(self, path: str) -> None:
        self.events.append(("finish", path))

    def close(self) -> None:
        self.events.append(("close", ""))


def _fake(calls: list, *, fail=(), stop=()):
    def worker(path, options, catalogue):
        calls.append((path, options, catalogue))
        if path in stop:
            raise KeyboardInterrupt
        if path in fail:
            raise RuntimeError("worker failed")
        return FmuReport(path, "d", ()), float(len(path))
    return worker


def test_every_path_is_checked_in_order_with_its_duration():
    calls: list = []
    progress = Recorded()
    durations: dict[str, float] = {}
    report = check_all(["a", "bb", "ccc"], options=STATIC, catalogue=CATALOGUE,
                       progress=progress, durations=durations, worker=_fake(calls))
    assert [f.path for f in report.fmus] == ["a", "bb", "ccc"]
    assert report.not_checked == ()
    assert durations == {"a": 1.0, "bb": 2.0, "ccc": 3.0}
    assert calls == [("a", STATIC, None), ("bb", STATIC, None), ("ccc", STATIC, None)]
    assert progress.events == [("start", "a"), ("finish", "a"), ("start", "bb"),
                               ("finish", "bb"), ("start", "ccc"), ("finish", "ccc"),
                               ("close", "")]
    assert dict(report.options)["probes"] is False


def test_a_catalogue_of_its_own_is_sent_to_the_worker():
    calls: list = []
    own = with_options(CATALOGUE, {"DAE740": {"rtol": 1e-3}})
    check_all(["a"], options=STATIC, catalogue=own, worker=_fake(calls))
    assert calls[0][2] is own


def test_an_interrupted_run_keeps_what_finished_and_lists_the_rest():
    calls: list = []
    progress = Recorded()
    durations: dict[str, float] = {}
    report = check_all(["a", "bb", "ccc", "d"], options=STATIC, catalogue=CATALOGUE,
                       progress=progress, durations=durations,
                       worker=_fake(calls, stop=("ccc",)))
    assert [f.path for f in report.fmus] == ["a", "bb"]
    assert report.not_checked == ("ccc", "d") and report.interrupted
    assert durations == {"a": 1.0, "bb": 2.0}
    assert progress.events[-1] == ("close", "")


def test_an_exception_in_the_worker_is_an_internal_error_of_that_fmu_alone():
    calls: list = []
    durations: dict[str, float] = {}
    report = check_all(["a", "bb"], options=STATIC, catalogue=CATALOGUE, durations=durations,
                       worker=_fake(calls, fail=("a",)))
    broken, fine = report.fmus
    assert fine.findings == () and durations == {"a": 0.0, "bb": 2.0}
    (finding,) = broken.findings
    assert (finding.code, finding.name, finding.severity) == ("DAE099", "internal-error",
                                                              Severity.WARNING)
    assert finding.message == ("lsdae failed while checking this FMU: RuntimeError: worker "
                               f"failed{SAID}")
    assert broken.path == "a" and broken.draft is None


def test_a_bad_selection_is_refused_before_any_fmu_is_checked():
    calls: list = []
    with pytest.raises(ValueError):
        check_all(["a"], options=EngineOptions(select=("NOPE999",)), catalogue=CATALOGUE,
                  worker=_fake(calls))
    assert calls == []


def test_a_check_that_never_completed_is_one_internal_error_finding():
    report = crashed("x.fmu", "it died", STATIC, CATALOGUE)
    assert report == FmuReport(path="x.fmu", draft=None, findings=(report.findings[0],))
    (finding,) = report.findings
    assert (finding.code, finding.name, finding.severity, finding.message, finding.location,
            finding.evidence) == ("DAE099", "internal-error", Severity.WARNING, f"it died{SAID}",
                                  Location(), evidence(stage="worker"))
    raised = crashed("x.fmu", "it died", EngineOptions(severity=(("internal-error", "error"),),
                                                        ignore=("internal-error",)), CATALOGUE)
    assert raised.findings[0].severity == Severity.ERROR


def test_one_worker_checks_one_fmu_and_times_it(fmu):
    path = str(fmu("a"))
    report, seconds = check_one(path, STATIC, None)
    assert report.path == path and report.rules_run and seconds > 0
    own = with_options(CATALOGUE, {"DAE740": {"rtol": 1e-3}})
    again, _ = check_one(path, STATIC, own)
    assert again == report
    assert parallel._shipped(CATALOGUE) is None and parallel._shipped(own) is own


def test_workers_in_processes_get_the_options_and_catalogue_and_a_failure_is_a_finding():
    from tests.run import workers

    own = with_options(CATALOGUE, {"DAE740": {"rtol": 1e-3}})
    progress = Recorded()
    durations: dict[str, float] = {}
    report = check_all(["a", "raise-b", "c"], options=EngineOptions(probes=False, seed=5),
                       catalogue=own, jobs=2, progress=progress, durations=durations,
                       worker=workers.describe)
    a, b, c = report.fmus
    assert [f.path for f in report.fmus] == ["a", "raise-b", "c"]
    assert dict(a.info) == dict(c.info) == {"catalogue": f"{len(own)} rules", "seed": 5}
    (finding,) = b.findings
    assert (finding.name, finding.message) == (
        "internal-error", f"lsdae failed while checking this FMU: RuntimeError: worker "
                          f"failed{SAID}")
    assert durations == {"a": 0.5, "raise-b": 0.0, "c": 0.5}
    assert progress.events[0] == ("start", "3 FMUs in 2 processes")
    assert sorted(progress.events[1:-1]) == [("finish", "a"), ("finish", "c"),
                                             ("finish", "raise-b")]


def test_what_the_runs_log(caplog):
    caplog.set_level(logging.DEBUG, logger="conformance.run.parallel")
    calls: list = []
    check_all(["a", "bb", "ccc"], options=STATIC, catalogue=CATALOGUE,
              worker=_fake(calls, fail=("a",), stop=("bb",)))
    assert caplog.messages == ["checking a failed", "interrupted after 1 of 3 FMUs"]
