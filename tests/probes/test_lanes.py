"""Two probe workers at once (conformance/probes/machinery/lanes.py): the same findings as one
worker, on the defects whose verdicts cross from one family to another; the split; the interrupt."""
from __future__ import annotations

import logging
import re
import threading
import time
from types import SimpleNamespace

import pytest

from conformance.probes.machinery import lanes
from conformance.report.findings import thaw
from conformance.probes.instruments.api import PLANNED_OPTIONS
from conformance.probes.instruments.entry_comparison import DIRECTIONAL_RULE, directional_options
from conformance.probes.machinery.registry import FAMILIES, FAMILY_OF, FIRST, LAST, ENDURANCE
from conformance.probes.machinery.lanes import Lanes
from conformance.report.catalogue import default_catalogue
from conformance.run.engine import EngineOptions
from tests.checkkit import checked
from tests.fixtures import DEFECTS, build_defect, chain

PROBES = sorted((r for r in default_catalogue() if r.code in FAMILY_OF), key=lambda r: r.code)

# Defects whose verdict one family leaves to, or takes from, another: the first cause folded
# across the lanes (instances-not-independent in the second, its consequences in both), the
# simulation that leaves a gap to ode-dae-inconsistent, to the event-indicator rules and to
# next-event-time-not-ahead, event-indicators-failed that leaves a refused time to
# evaluation-failed (planned in the other lane), the start values read first, the
# Initialization-Mode survey (second lane) that trusts directional derivatives by the options
# of directional-derivative-mismatch (first lane), and a crash that restarts one lane's worker.
# (A binary that crashes in every probe is not among them: each lane has max_restarts of its
# own, see test_each_lane_restarts_its_own_workers.)
CROSSING = (
    "DAE762-SimpleDAE-shared-mode", "DAE762-SimpleDAE-DEFECT_GLOBAL_STATE",
    "DAE762-HelloWorldDAE-DEFECT_STALE_STATES", "DAE747-SimpleDAE-DEFECT_ODE_DAE_INCONSISTENT",
    "DAE733-EventDAE-DEFECT_INDICATORS_STALE", "DAE735-EventDAE-DEFECT_NEXT_EVENT_PAST=0.1",
    "DAE724-EventDAE-discrete-refused", "DAE724-SimpleDAE-time-refused",
    "DAE713-SimpleDAE-state-start", "DAE752-SimpleDAE-DEFECT_INITIAL_DIRECTIONAL",
    "DAE805-HelloWorldDAE-DEFECT_LATE_ODE_DRIFT", "DAE701-SimpleDAE-DEFECT_LATE_CRASH",
)
BY_ID = {d.id: d for d in DEFECTS}


def _verdicts(report):
    """Findings and rules not run; of the messages all but the FMI calls made "in this worker"
    (a death's evidence), which counts the calls of the other probes of the same worker."""
    return (sorted((f.code, str(f.severity), f.subject or "", f.location.file or "",
                    f.location.line or 0, re.sub(r" \([\d,]+ in this worker\)", "", f.message))
                   for f in report.findings),
            sorted(report.rules_not_run))


@pytest.mark.parametrize("defect_id", CROSSING)
def test_two_workers_find_what_one_finds(defect_id):
    fmu = build_defect(BY_ID[defect_id])
    one = checked(fmu, options=EngineOptions(probes=True))     # small: one worker (auto)
    two = checked(fmu, options=EngineOptions(probes=True, probe_workers=2))
    assert _verdicts(two) == _verdicts(one)
    assert BY_ID[defect_id].code in {f.code for f in two.findings}


def _crashed_probes(report) -> set[str]:
    """The probes of the one binary-crashed finding: the same crash in several probes is one
    defect, its other probes listed in its evidence (issue 29); lsdae's narrowing of the crash
    to one variable (a worker of its own after the probes) is no probe."""
    (crash,) = [f for f in report.findings if f.code == "DAE701"]
    ev = thaw(crash.evidence)
    assert ev["variables"] == ["g1"]   # narrowed
    places = [ev["place"], *(a["where"] for a in ev.get("also", []))]
    return {place.split()[1] for place in places if place.startswith("probe ")}


def test_each_lane_restarts_its_own_workers():
    """fmi3GetFloat64 crashes on every call: one worker reaches the crash in the first
    max_restarts + 1 probes and gives up; two lanes each reach theirs. Either way one finding."""
    fmu = build_defect(BY_ID["DAE701-HelloWorldDAE-DEFECT_SEGFAULT_GETFLOAT64"])
    restarts = default_catalogue()["DAE701"].option_values["max_restarts"]
    one = checked(fmu, options=EngineOptions(probes=True))
    two = checked(fmu, options=EngineOptions(probes=True, probe_workers=2))
    crashed = [_crashed_probes(r) for r in (one, two)]
    assert len(crashed[0]) == restarts + 1 and len(crashed[1]) == 2 * (restarts + 1)
    assert crashed[0] < crashed[1]
    assert {FAMILY_OF[c] in lanes.FIRST_LANE for c in crashed[1] - crashed[0]} == {True}
    assert {f.code for f in two.findings} == {"DAE701"}


def test_the_crossing_defects_exist():
    assert set(CROSSING) <= set(BY_ID)


def test_a_large_fmu_is_probed_by_two_workers_with_the_findings_of_one(caplog):
    """Chain at N = 500 (1,006 variables, at LARGE_MODEL): two lanes by default; a correct
    FMU, so the same (empty) findings and the same info as one worker."""
    fmu = chain.build_chain(500)
    caplog.set_level(logging.DEBUG, logger="conformance.probes.machinery.driver")
    two = checked(fmu, options=EngineOptions(probes=True))
    one = checked(fmu, options=EngineOptions(probes=True, probe_workers=1))
    assert _verdicts(two) == _verdicts(one) == ([], [])
    assert set(two.info) == set(one.info)
    if caplog.records:   # a fresh check (checkkit may have it from another test)
        assert {getattr(r, "probe_stats", {}).get("lane") for r in caplog.records
                if hasattr(r, "probe_stats")} == {0, 1}


# ------------------------------------------------------------------------------ the split

def test_every_family_is_in_one_lane_and_the_first_lane_is_known():
    assert lanes.FIRST_LANE <= set(FAMILIES)
    first, second = lanes.split(PROBES, 2)
    assert {r.code for r in first} | {r.code for r in second} == {r.code for r in PROBES}
    assert not {r.code for r in first} & {r.code for r in second}
    assert {FAMILY_OF[r.code] for r in first} == set(lanes.FIRST_LANE)


def test_each_lane_keeps_the_order_and_the_first_and_last_probes_stay_in_place():
    order = [*[r for r in PROBES if r.code in FIRST], *[r for r in PROBES if r.code not in
             FIRST | LAST | ENDURANCE], *[r for r in PROBES if r.code in LAST],
             *[r for r in PROBES if r.code in ENDURANCE]]
    for lane in lanes.split(order, 2):
        assert lane == [r for r in order if r in lane]
    second = lanes.split(order, 2)[1]
    assert second[0].code in FIRST and second[-1].code in ENDURANCE


def test_one_lane_when_one_worker_or_one_lane_would_be_empty():
    assert lanes.split(PROBES, 1) == [PROBES]
    only_first = [r for r in PROBES if FAMILY_OF[r.code] in lanes.FIRST_LANE]
    assert lanes.split(only_first, 2) == [only_first]


@pytest.mark.parametrize("size, chosen, workers", [
    (lanes.LARGE_MODEL - 1, 0, 1), (lanes.LARGE_MODEL, 0, 2), (10, 2, 2),
    (50_000, 1, 1), (0, 0, 1)])
def test_workers_by_the_models_size_unless_chosen(size, chosen, workers):
    model = SimpleNamespace(variables=[None] * size)
    assert lanes.workers_for(model, chosen) == workers


def test_the_options_of_directional_derivative_mismatch_reach_the_other_lane():
    """The Initialization-Mode survey runs in the second lane; what it calls confirmed is
    what directional-derivative-mismatch, in the first, was told."""
    ctx = SimpleNamespace(facts={PLANNED_OPTIONS: {DIRECTIONAL_RULE: {
        "rtol": 0.5, "margin": 7.0, "ulps": 3.0, "other": 1}}})
    assert directional_options(ctx) == {"rtol": 0.5, "margin": 7.0, "ulps": 3.0}
    defaults = directional_options(SimpleNamespace(facts={}))
    assert defaults["rtol"] != 0.5


# ---------------------------------------------------------------------- running at once

class _Driver:
    def __init__(self, drive=None):
        self.stopped = threading.Event()
        self._drive = drive or (lambda: self.stopped.wait(30))

    def drive(self):
        self._drive()

    def stop(self):
        self.stopped.set()


def test_an_interrupt_stops_every_lane_before_it_goes_on():
    def interrupted():
        time.sleep(0.05)
        raise KeyboardInterrupt
    first, second = _Driver(interrupted), _Driver()
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        Lanes([first, second]).drive()
    assert first.stopped.is_set() and second.stopped.is_set()
    assert time.monotonic() - started < 10     # the second lane was not waited out
    assert not any(t.name.startswith("lsdae-probe-lane") for t in threading.enumerate())


def test_a_defect_of_ours_in_the_other_lane_is_raised_after_both_ended():
    def broken():
        raise RuntimeError("a defect of ours")
    first = _Driver(lambda: time.sleep(0.05))
    with pytest.raises(RuntimeError, match="a defect of ours"):
        Lanes([first, _Driver(broken)]).drive()
