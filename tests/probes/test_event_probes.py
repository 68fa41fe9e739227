"""The Event Mode probes (DAE734-DAE737) and the calls never made before (DAE738, DAE739), each
against a family of its defect: other scenes (with and without events), both modes, other
sizes, other calls. tests/probes/test_defects.py holds one member of each family; the clean
scenes and the corpus, which must trigger none of them, are tests/probes/test_clean_scenes.py
and the last test here."""
from __future__ import annotations

import pytest

from conformance.report.findings import thaw
from conformance.run.engine import EngineOptions, check_fmu
from tests.checkkit import checked
from tests.fixtures import build_scene, corpus_names

EVENT_RULES = ("DAE734", "DAE735", "DAE736", "DAE737", "DAE738", "DAE739", "DAE807")


def _findings(scene: str, *defines: str, may_skip: tuple[str, ...] = ()
              ) -> dict[str, list[dict]]:
    """code -> evidence of each finding of the event and call rules (only those run); every
    one of them runs but ``may_skip``. The report is kept for the next test that asks the
    same (the walk-and-simulation test asks two of the family's)."""
    report = checked(build_scene(scene, defines=list(defines)),
                     options=EngineOptions(probes=True, select=EVENT_RULES, endurance="off"))
    out: dict[str, list[dict]] = {}
    for f in report.findings:
        out.setdefault(f.code, []).append(dict(f.evidence))
    skipped = [code for code, _ in report.rules_skipped
               if code in EVENT_RULES and code not in may_skip]
    assert not skipped, report.rules_skipped
    return out


def _modes(found: dict[str, list[dict]], code: str) -> set[str]:
    """The modes a rule's findings were seen in: each finding's own, and those of the places
    folded into it (one fault seen in both modes is one finding, ``also`` in its evidence)."""
    modes = set()
    for e in found.get(code, []):
        modes.add(e["mode"])
        for other in e.get("also", ()):
            where = dict(other)["where"]
            modes.add("ode" if "ODE" in where else "dae")
    return modes


@pytest.mark.parametrize("scene", ["EventDAE", "SimpleDAE", "Robertson"])
def test_unwritten_update_outputs_in_both_modes_with_and_without_events(scene):
    # no iteration completes, so there is nothing to compare for values-stale-after-event
    found = _findings(scene, "DEFECT_EVENT_OUTPUTS_UNWRITTEN", may_skip=("DAE736",))
    assert set(found) == {"DAE734"}, found
    assert _modes(found, "DAE734") == {"dae", "ode"}
    assert all("discreteStatesNeedUpdate" in e["unwritten"] for e in found["DAE734"])


@pytest.mark.parametrize("dt", ["0", "1e-9", "0.1", "100"])
@pytest.mark.parametrize("scene", ["EventDAE", "SimpleDAE", "HelloWorldDAE"])
def test_next_event_time_at_or_before_now_whatever_how_far(scene, dt):
    found = _findings(scene, f"DEFECT_NEXT_EVENT_PAST={dt}", may_skip=("DAE807",))
    assert set(found) == {"DAE735"}, found
    assert _modes(found, "DAE735") == {"dae", "ode"}
    for e in found["DAE735"]:
        assert e["next_event_time"] <= e["t"]
        assert e["t"] - e["next_event_time"] == pytest.approx(float(dt), abs=1e-12)


def test_next_event_time_behind_only_on_the_trajectory_is_the_simulations():
    found = _findings("EventDAE", "DEFECT_STALE_TIME_EVENT")
    assert set(found) == {"DAE807"}, found
    assert _modes(found, "DAE807") == {"dae", "ode"}
    for e in found["DAE807"]:
        assert e["t"] - e["next_event_time"] == pytest.approx(0.05)
        assert e["t"] == pytest.approx(0.6931, abs=1e-3)     # the state event, x = 0.5


@pytest.mark.parametrize("dt", ["0", "0.1"])
def test_the_same_fault_in_walk_and_simulation_is_one_finding(dt):
    found = _findings("EventDAE", f"DEFECT_NEXT_EVENT_PAST={dt}", may_skip=("DAE807",))
    assert set(found) == {"DAE735"}, found


def test_values_stale_after_the_event_in_both_modes():
    found = _findings("EventDAE", "DEFECT_EVENT_STALE")
    assert set(found) == {"DAE736"}, found
    assert _modes(found, "DAE736") == {"dae", "ode"}
    for e in found["DAE736"]:
        assert e["t"] >= 0.75 - 1e-12           # the time event, where b switches
        assert abs(e["at_event"] - e["fresh"]) > e["tolerance"]


@pytest.mark.parametrize("scene", ["EventDAE", "SimpleDAE", "Robertson"])
def test_spurious_states_changed_flag_with_and_without_events(scene):
    found = _findings(scene, "DEFECT_STATES_CHANGED_SPURIOUS")
    assert set(found) == {"DAE737"}, found
    assert _modes(found, "DAE737") == {"dae", "ode"}


@pytest.mark.parametrize("scene", ["SimpleDAE", "EventDAE", "Robertson"])
def test_stop_time_refused_in_every_mode(scene):
    found = _findings(scene, "DEFECT_STOP_TIME_REFUSED")
    assert set(found) == {"DAE738"}, found
    assert _modes(found, "DAE738") == {"dae", "ode"}
    assert all(e["stop_time"] > e["start_time"] for e in found["DAE738"])


@pytest.mark.parametrize("define, calls, spec", [
    ("DEFECT_SETBOOLEAN_ANY_VR", {"fmi3SetBoolean"}, {"SG-09"}),
    ("DEFECT_KNOWN_UNCHECKED", {"fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative"},
     {"PD-05"}),
    ("DEFECT_SEED_SIZE_UNCHECKED",
     {"fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative"}, {"PD-01"}),
])
@pytest.mark.parametrize("scene", ["SimpleDAE", "EventDAE"])
def test_each_illegal_call_accepted_is_found(scene, define, calls, spec):
    """One kind of illegal call accepted is one defect (issue 29): one finding, the other
    functions and modes that accept it listed in its evidence."""
    found = _findings(scene, define)
    assert set(found) == {"DAE739"}, found
    (e,) = found["DAE739"]
    assert e["spec"] in spec
    places = [e["place"], *(a["where"] for a in thaw(e.get("also", ())))]
    assert {p.split(",")[0].split(" (")[0] for p in places} == calls
    if define != "DEFECT_SETBOOLEAN_ANY_VR":
        assert {p.split(", ")[1] for p in places} == {"DAE mode", "ODE mode"}


def test_a_crash_on_an_illegal_call_is_the_binarys_crash_after_every_other_probe():
    report = check_fmu(build_scene("SimpleDAE", defines=["DEFECT_CRASH_ON_ILLEGAL_KNOWN"]),
                       options=EngineOptions(probes=True, endurance="off"))
    crashes = [dict(f.evidence) for f in report.findings if f.code == "DAE701"]
    assert [f.code for f in report.findings] == ["DAE701"], report.findings
    assert crashes[0]["call"] in ("fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative")
    assert crashes[0]["probe"] == "DAE739"
    assert report.findings[0].part == "crash-on-illegal-call"
    # every other probe ran first, on a binary that had not crashed yet
    assert {"DAE734", "DAE738", "DAE740", "DAE741", "DAE801", "DAE805"} <= set(report.rules_run)


@pytest.mark.parametrize("scene", ["EventDAE", "SimpleDAE", *corpus_names()])
def test_correct_fmus_trigger_none(scene):
    report = check_fmu(build_scene(scene),
                       options=EngineOptions(probes=True, select=EVENT_RULES, endurance="off"))
    assert report.findings == (), [(f.code, f.message) for f in report.findings]
