"""The verdicts of probes that decide from values already recorded, judged in this process on
hand-made records: no FMU, no worker.

* start-value-not-applied (readback/start_values.py): a snapshot of what fresh instances held
  against the XML starts;
* memory-grows (endurance/memory.py): the samples of a path run;
* the simulation verdicts (simulation/verdicts.py): hand-made trajectories.
"""
from __future__ import annotations

import dataclasses

from types import SimpleNamespace

import numpy as np
import pytest

from conformance.probes.instruments.api import ProbeContext, ProbeSkipped
from conformance.probes.instruments.instantiation import Held, Instantiated
from conformance.probes.readback import start_values as S
from conformance.report import causes
from conformance.report.findings import Location, thaw
from conformance.runtime.errors import FmiError


def _var(name: str, vr: int, type_: str = "Float64", initial: str = "exact", line: int = 0):
    return SimpleNamespace(name=name, vr=vr, type=type_, initial=initial, line=line or vr + 10,
                           path=f"/fmiModelDescription/ModelVariables/{type_}[{vr}]")


def _ctx(variables=(), facts=None) -> ProbeContext:
    model = SimpleNamespace(by_vr={v.vr: v for v in variables}, file="modelDescription.xml")
    return ProbeContext(model=model, manifest=None, draft="alpha1", seed=0,  # type: ignore
                        rng=np.random.default_rng(0), points=[], dae=None, ode=None,
                        new_instance=lambda mode: None, facts=facts or {})


def _snapshot(monkeypatch, snapshot: Instantiated) -> list:
    """The probe's snapshot replaced by ``snapshot``; the contexts it was taken for."""
    asked: list = []
    monkeypatch.setattr(S, "instantiated_values", lambda ctx: asked.append(ctx) or snapshot)
    return asked


OPTIONS = {"rtol": 1e-12, "float32_rtol": 2e-7}


# ------------------------------------------------------------------ start-value-not-applied

def test_a_float_off_by_more_than_rtol_differs_and_within_does_not():
    assert not S.differs("Float64", 1.0 + 1e-13, 1.0, rtol=1e-12, float32_rtol=1.0)
    assert S.differs("Float64", 1.0 + 1e-11, 1.0, rtol=1e-12, float32_rtol=1.0)
    # exactly at the tolerance: not a difference (the comparison is strict)
    assert not S.differs("Float64", 2.0, 1.0, rtol=0.5, float32_rtol=0.0)
    assert S.differs("Float64", 2.0, 1.0, rtol=0.49, float32_rtol=1.0)
    # the scale is the larger of the two
    assert not S.differs("Float64", 1.0, 2.0, rtol=0.5, float32_rtol=0.0)
    assert not S.differs("Float64", -2.0, -1.0, rtol=0.5, float32_rtol=0.0)
    # Float32 by float32_rtol only
    assert not S.differs("Float32", 2.0, 1.0, rtol=0.0, float32_rtol=0.5)
    assert S.differs("Float32", 2.0, 1.0, rtol=1.0, float32_rtol=0.49)
    assert S.differs("Float64", float("inf"), float("inf"), **OPTIONS)
    assert S.differs("Float32", float("nan"), 0.0, rtol=1.0, float32_rtol=1.0)
    assert not S.differs("Float64", 0, 0.0, **OPTIONS)


def test_booleans_and_others_compare_exactly():
    assert not S.differs("Boolean", 2, True, **OPTIONS)
    assert S.differs("Boolean", 0, True, **OPTIONS)
    assert not S.differs("Boolean", 0, False, **OPTIONS)
    assert not S.differs("Int32", 3, 3, **OPTIONS) and S.differs("Int32", 3, 4, **OPTIONS)
    assert S.differs("Enumeration", 1, 2, **OPTIONS)


def test_mismatched_lists_the_elements_that_differ():
    h = Held(_var("g", 3), [1.0, 2.0, 3.0, 4.0], [1.0, 2.5, 3.0, 5.0])
    assert S.mismatched(h, **OPTIONS) == [1, 3]
    assert S.mismatched(Held(_var("g", 3), [1.0]), **OPTIONS) == []
    b = Held(_var("b", 4, "Boolean"), [True, False], [1, 1])
    assert S.mismatched(b, **OPTIONS) == [1]


def test_a_snapshot_with_a_reason_is_skipped_with_it(monkeypatch):
    _snapshot(monkeypatch, Instantiated(reason="no fmi3InstantiateModelExchange"))
    with pytest.raises(ProbeSkipped, match="^no fmi3InstantiateModelExchange$"):
        list(S.start_value_not_applied(_ctx(), **OPTIONS))


def test_nothing_read_is_skipped_naming_the_first_refusal(monkeypatch):
    first = FmiError("fmi3GetFloat64", "fmi3Error")
    later = FmiError("fmi3GetInt32", "not called")
    later.after = first
    items = [Held(_var("a", 1), [1.0], error=later), Held(_var("b", 2), [1.0], error=first)]
    _snapshot(monkeypatch, Instantiated(items=items, dae=[Held(_var("a", 1), [1.0])]))
    with pytest.raises(ProbeSkipped) as info:
        list(S.start_value_not_applied(_ctx(), **OPTIONS))
    assert str(info.value) == ("nothing could be read after instantiation (fmi3GetFloat64 "
                               "returned fmi3Error)")
    items = [Held(_var("a", 1), [1.0], error=first)]
    _snapshot(monkeypatch, Instantiated(items=items))
    with pytest.raises(ProbeSkipped) as info:
        list(S.start_value_not_applied(_ctx(), **OPTIONS))
    assert str(info.value) == ("nothing could be read after instantiation (fmi3GetFloat64 "
                               "returned fmi3Error)")
    _snapshot(monkeypatch, Instantiated(items=[Held(_var("a", 1), [1.0])]))
    with pytest.raises(ProbeSkipped) as info:
        list(S.start_value_not_applied(_ctx(), **OPTIONS))
    assert str(info.value) == "nothing could be read"


def test_a_scalar_held_wrong_in_ode_mode_is_one_finding_with_its_evidence(monkeypatch):
    x = _var("x", 1, initial="approx", line=21)
    ok = _var("ok", 2)
    asked = _snapshot(monkeypatch, Instantiated(items=[Held(x, [1.5], [2.5]),
                                                       Held(ok, [1.0], [1.0 + 1e-10])]))
    ctx = _ctx([x, ok])
    (v,) = S.start_value_not_applied(ctx, rtol=1e-9, float32_rtol=1e-6)
    assert asked == [ctx]
    assert v.message == (
        "after fmi3InstantiateModelExchange, before any fmi3Set*, fmi3GetFloat64 returns 2.5 "
        "for {subject}, whose XML start is 1.5 (initial=\"approx\"), in ODE mode: an importer "
        "that trusts the XML starts from another point than the binary")
    assert v.subject == "x"
    assert v.location == Location(file="modelDescription.xml", line=21, path=x.path)
    assert thaw(v.evidence) == {
        "value_reference": 1, "type": "Float64", "initial": "approx", "start": 1.5,
        "held": 2.5, "elements_differing": 1, "elements": 1,
        "state": "Instantiated (no fmi3Set* called but the switch's)", "modes": "ODE",
        "held_by_mode": {"ODE": 2.5}, "rtol": 1e-9, "element": None}
    assert v.cause == causes.through("x")


def test_an_array_element_a_float32_and_dae_mode_only(monkeypatch):
    g = _var("g", 3, "Float32")
    _snapshot(monkeypatch, Instantiated(items=[Held(g, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0])],
                                        dae=[Held(g, [1.0, 2.0, 3.0], [1.0, 7.0, 9.0])]))
    (v,) = S.start_value_not_applied(_ctx([g]), rtol=1e-9, float32_rtol=1e-6)
    assert v.message == (
        "after fmi3InstantiateModelExchange and the enable parameter set true in Configuration "
        "Mode, before any other fmi3Set*, fmi3GetFloat32 returns 7.0 for {subject} (element 1, "
        "2 of 3 differ), whose XML start is 2.0 (initial=\"exact\"), in DAE mode only (ODE "
        "mode holds it): an importer that trusts the XML starts from another point than the "
        "binary")
    ev = thaw(v.evidence)
    assert (ev["element"], ev["elements_differing"], ev["elements"], ev["rtol"]) == (1, 2, 3, 1e-6)
    assert ev["held_by_mode"] == {"DAE": 7.0} and ev["modes"] == "DAE"


def test_both_modes_wrong_name_both_ode_first_and_types_show_as_read(monkeypatch):
    e = _var("e", 5, "Enumeration")
    flag = _var("flag", 6, "Boolean")
    label = _var("label", 7, "String")
    _snapshot(monkeypatch, Instantiated(
        items=[Held(e, [2], [1]), Held(flag, [True], [False]), Held(label, ["a"], ["b"])],
        dae=[Held(e, [2], [3]), Held(flag, [True], [True])]))
    found = {v.subject: v for v in S.start_value_not_applied(_ctx([e, flag, label]),
                                                             **OPTIONS)}
    assert list(found) == ["e", "flag", "label"]
    assert "fmi3GetInt64 returns 1 for {subject}, whose XML start is 2 " in found["e"].message
    assert "in ODE and DAE mode:" in found["e"].message
    ev = thaw(found["e"].evidence)
    assert ev["held_by_mode"] == {"ODE": 1, "DAE": 3} and ev["modes"] == "ODE and DAE"
    assert ev["rtol"] is None and ev["element"] is None   # exact: no tolerance
    assert ("fmi3GetBoolean returns false for {subject}, whose XML start is true "
            "(initial=\"exact\"), in ODE mode:") in found["flag"].message
    assert 'fmi3GetString returns "b" for {subject}, whose XML start is "a"' in \
        found["label"].message
    assert thaw(found["label"].evidence)["held_by_mode"] == {"ODE": "b"}


def test_an_array_of_two_names_its_element(monkeypatch):
    g = _var("g", 3)
    _snapshot(monkeypatch, Instantiated(items=[Held(g, [1.0, 2.0], [1.0, 2.5])]))
    (v,) = S.start_value_not_applied(_ctx([g]), **OPTIONS)
    assert "returns 2.5 for {subject} (element 1, 1 of 2 differ), whose XML start is 2.0" in \
        v.message
    assert thaw(v.evidence)["element"] == 1


def test_mismatched_compares_floats_within_the_tolerance_of_their_type():
    h = Held(_var("f", 3, "Float64"), [1.0, 2.0], [1.0 + 1e-13, 2.0 + 1e-3])
    assert S.mismatched(h, **OPTIONS) == [1]
    h32 = Held(_var("f", 4, "Float32"), [0.1], [0.10000000149011612])
    assert S.mismatched(h32, **OPTIONS) == []


def test_values_are_shown_as_the_xml_writes_them():
    assert S._show(True) == "true" and S._show(False) == "false"
    assert S._show("a b") == '"a b"' and S._show(0.1) == "0.1" and S._show(3) == "3"
    assert S._plain(np.float32(0.5)) == "0.5" and S._plain(None) is None
    assert S._plain(True) is True and S._plain("s") == "s" and S._plain(2) == 2


# ------------------------------------------------------------------ memory-grows

from conformance.probes.endurance.calls import INSTANCE_CYCLE  # noqa: E402
from conformance.probes.endurance.memory import memory_grows  # noqa: E402
from conformance.probes.endurance.run import FACT, PathRun, RunSettings  # noqa: E402

MIB = 1 << 20
RUN = RunSettings("quick", calls=1000, values=10**6, seconds=60.0, samples=16,
                  max_growth_mib=64.0)
MEMORY = dict(bytes_per_call_quick=100.0, bytes_per_call_long=10.0, min_growth_kib=64.0,
              min_function_growth_kib=32.0)
# 16 samples: fmi3GetFloat64 made 100 times per sample and a little more now and then, so
# that its calls and fmi3SetFloat64's can be told apart; 3,000 calls in all
GETS = [100 * k + 7 * (k % 3) for k in range(16)]
SETS = [100 * k for k in range(16)]
CALLS = [g + s for g, s in zip(GETS, SETS)]
SAMPLES_KIB = [[0, 0], [207, 104], [414, 208], [600, 292], [807, 397], [1014, 501],
               [1200, 585], [1407, 690], [1614, 794], [1800, 878], [2007, 983], [2214, 1087],
               [2400, 1171], [2607, 1276], [2814, 1380], [3000, 1464]]


def _memory_ctx(run: PathRun, level: str = "quick") -> ProbeContext:
    ctx = _ctx(facts={FACT: run})
    ctx.endurance = level
    return ctx


def _leaking(per_get: float = 1000.0, per_set: float = 0.0, **kw) -> PathRun:
    rss = [(40 << 20) + int(per_get * g + per_set * s) for g, s in zip(GETS, SETS)]
    return PathRun(RUN, calls=CALLS[-1], stopped="budget", samples=list(zip(CALLS, rss)),
                   counts=[[g, s] for g, s in zip(GETS, SETS)],
                   functions=["fmi3GetFloat64", "fmi3SetFloat64"], budget_calls=1000, **kw)


def _judge(run: PathRun, level: str = "quick", **options) -> list:
    return list(memory_grows(_memory_ctx(run, level), **{**MEMORY, **options}))


def test_a_leak_in_one_function_is_named_with_its_bytes_per_call():
    (v,) = _judge(_leaking())
    assert v.message == (
        "the worker's resident memory grows by 1,000 bytes per call of {subject} along the path "
        "(670 KiB over the last 1,386 of 3,000 calls on one instance): the FMU allocates "
        "without freeing")
    assert v.subject == "fmi3GetFloat64" and v.location == Location(file="modelDescription.xml")
    assert thaw(v.evidence) == {
        "function": "fmi3GetFloat64", "bytes_per_call": 1000,
        "functions": {"fmi3GetFloat64": 1000}, "fitted": {"fmi3GetFloat64": 1000,
                                                          "fmi3SetFloat64": 0},
        "measured": "resident set (VmRSS)", "quarter_slopes": [497, 502],
        "quarter_growth_kib": [381, 294], "growth_kib": 675, "threshold_bytes_per_call": 100.0,
        "min_growth_kib": 64.0, "min_function_growth_kib": 32.0, "calls": 3000,
        "stopped": "budget", "level": "quick", "samples": SAMPLES_KIB,
        "sample_unit": "[FMI calls, KiB grown since the first sample]",
        "method": "the growth over the second half of the samples, and across each of its "
                  "quarters, then least squares on each function's calls (their mix changes "
                  "between samples: one function in turn is made more often)"}


def test_two_leaking_functions_name_the_larger_and_list_the_other():
    (v,) = _judge(_leaking(per_get=300.0, per_set=1000.0))
    assert v.subject == "fmi3SetFloat64"
    assert v.message.startswith("the worker's resident memory grows by 1,000 bytes per call of "
                                "{subject} along the path (")
    assert v.message.endswith(", and by fmi3GetFloat64 300 bytes per call: the FMU allocates "
                              "without freeing")
    ev = thaw(v.evidence)
    assert ev["functions"] == {"fmi3SetFloat64": 1000, "fmi3GetFloat64": 300}
    assert list(ev["functions"]) == ["fmi3SetFloat64", "fmi3GetFloat64"]


def test_the_heap_in_use_is_judged_where_it_was_sampled():
    heap = [(9 << 20) + 1000 * g for g in GETS]
    (v,) = _judge(_leaking(per_get=0.0, heap=heap))
    assert v.message.startswith("the C heap in use grows by 1,000 bytes per call of {subject}")
    assert thaw(v.evidence)["measured"] == "C heap in use (mallinfo2)"
    # a heap of another length than the samples is not used: the resident set is flat
    assert _judge(_leaking(per_get=0.0, heap=heap[:-1])) == []


@pytest.mark.parametrize("level, threshold, found", [
    ("quick", 999.0, True), ("quick", 1001.0, False),
    ("long", 999.0, True), ("long", 1001.0, False)])
def test_the_threshold_of_the_level_decides(level, threshold, found):
    option = "bytes_per_call_quick" if level == "quick" else "bytes_per_call_long"
    other = "bytes_per_call_long" if level == "quick" else "bytes_per_call_quick"
    got = _judge(_leaking(), level, **{option: threshold, other: 1.0 if found else 1e9})
    assert len(got) == int(found)
    if found:
        assert thaw(got[0].evidence)["threshold_bytes_per_call"] == threshold
        assert thaw(got[0].evidence)["level"] == "quick"   # the run's own level


def test_a_function_leak_below_its_minimum_falls_back_to_the_growth_per_call():
    # 675 KiB over the second half: under min_function_growth_kib 700, no function is named;
    # the growth per call of any kind (about 500 bytes) is judged against the threshold
    (v,) = _judge(_leaking(), min_function_growth_kib=700.0)
    assert v.subject is None
    assert v.message.startswith("the worker's resident memory grows by 49")
    assert " bytes per FMI call along the path (0.7 MiB over the last 1,386 of 3,000 calls " \
           "on one instance): the FMU allocates without freeing" in v.message
    assert _judge(_leaking(), min_function_growth_kib=700.0, min_growth_kib=676.0) == []
    # each quarter must show a quarter of the growth: 294 KiB of 1176 / 4 = 294 ...
    assert len(_judge(_leaking(), min_function_growth_kib=700.0, min_growth_kib=1170.0)) == 0
    assert len(_judge(_leaking(), min_function_growth_kib=700.0, min_growth_kib=600.0)) == 1


def test_a_share_under_half_the_minimum_names_no_function():
    # fmi3SetFloat64's share (100 bytes per call, 65 KiB) is under half of 140 KiB: not named,
    # and fmi3GetFloat64's 1,000 bytes per call are
    (v,) = _judge(_leaking(per_get=1000.0, per_set=100.0), min_function_growth_kib=140.0)
    assert "and by" not in v.message and v.subject == "fmi3GetFloat64"


def test_a_uniform_growth_per_call_is_judged_without_functions():
    rss = [(40 << 20) + 600 * c for c in CALLS]
    run = PathRun(RUN, calls=3000, stopped="budget", samples=list(zip(CALLS, rss)))
    (v,) = _judge(run)
    assert v.message == (
        "the worker's resident memory grows by 600 bytes per FMI call along the path (0.8 MiB "
        "over the last 1,386 of 3,000 calls on one instance): the FMU allocates without "
        "freeing")
    ev = thaw(v.evidence)
    assert (ev["bytes_per_call"], ev["quarter_slopes"], ev["quarter_growth_kib"],
            ev["growth_kib"]) == (600, [600, 600], [461, 352], 812)
    assert ev["method"] == ("least squares over the second half of the samples; each of its "
                            "quarters must show the rate too")
    assert "function" not in ev and v.subject is None
    assert _judge(run, bytes_per_call_quick=601.0) == []
    assert len(_judge(run, bytes_per_call_quick=599.0)) == 1
    assert _judge(run, min_growth_kib=813.0) == []
    # the C heap sampled alongside: the same growth there is a leak, a flat heap is not
    heap = [(9 << 20) + 600 * c for c in CALLS]
    assert len(_judge(PathRun(RUN, calls=3000, stopped="budget",
                              samples=list(zip(CALLS, rss)), heap=heap))) == 1
    assert _judge(PathRun(RUN, calls=3000, stopped="budget", samples=list(zip(CALLS, rss)),
                          heap=[9 << 20] * 16)) == []


def test_runs_that_cannot_be_judged_say_why():
    with pytest.raises(ProbeSkipped, match="^no /proc$"):
        _judge(PathRun(RUN, memory_note="no /proc"))
    with pytest.raises(ProbeSkipped, match="^time budget: the path run was stopped after "):
        _judge(PathRun(RUN, calls=5, stopped="time", budget_calls=9))
    few = PathRun(RUN, calls=1234, stopped="failure", samples=[(0, 1), (10, 2), (20, 3)])
    with pytest.raises(ProbeSkipped) as info:
        _judge(few)
    assert str(info.value) == ("the path run ended after 1,234 FMI calls (failure): too few "
                               "memory samples (3) to judge")


def _stopped(**kw) -> PathRun:
    samples = [(100, 40 * MIB), (600, 43 * MIB), (1100, 106 * MIB)]
    return PathRun(RUN, calls=2000, stopped="memory", samples=samples, **kw)


def test_a_run_stopped_for_memory_is_the_finding_naming_where_it_grew():
    run = _stopped(functions=["fmi3GetFloat64", INSTANCE_CYCLE],
                   counts=[[10, 1], [260, 2], [510, 3]],
                   grown_by={"fmi3InstantiateModelExchange": 50 * MIB,
                             "fmi3GetFloat64": 50 * MIB, "fmi3SetFloat64": 2 * MIB,
                             "a": 1024, "b": 2048, "c": 3072, "d": 4096})
    (v,) = _judge(run)
    # the tie between the two largest goes to the name that sorts last; the instance cycle
    # counts fmi3InstantiateModelExchange: 2 cycles between the first and the last sample
    assert v.message == (
        "the worker's resident memory grew by 66.0 MiB in 1,000 FMI calls on one instance "
        "along the path (about 69,206 bytes per call), and the path run was stopped there, at "
        "max_growth_mib = 64 MiB; the address space grew inside fmi3InstantiateModelExchange "
        "above all (about 34,603,008 bytes per call of it): the FMU allocates without freeing")
    assert v.subject == "fmi3InstantiateModelExchange"
    assert thaw(v.evidence) == {
        "function": "fmi3InstantiateModelExchange", "bytes_per_call_of_function": 34603008,
        "grown_inside_kib": {"fmi3GetFloat64": 51200, "fmi3InstantiateModelExchange": 51200,
                             "fmi3SetFloat64": 2048, "d": 4, "c": 3},
        "bytes_per_call": 69206, "growth_kib": 67584, "threshold_bytes_per_call": 100.0,
        "min_growth_kib": 64.0, "max_growth_mib": 64.0, "calls": 2000, "stopped": "memory",
        "level": "quick", "samples": [[100, 0], [600, 3072], [1100, 67584]],
        "sample_unit": "[FMI calls, KiB grown since the first sample]",
        "method": "growth from the first sample to the stop, over the calls between; the "
                  "function: where the library measured the address space grow"}


def test_a_run_stopped_for_memory_without_a_measured_function():
    (v,) = _judge(_stopped())
    assert v.message.endswith("at max_growth_mib = 64 MiB: the FMU allocates without freeing")
    ev = thaw(v.evidence)
    assert ev["function"] is None and ev["bytes_per_call_of_function"] is None
    assert v.subject is None


@pytest.mark.parametrize("functions, counts, per", [
    (["fmi3SetFloat64"], [[0], [5], [10]], "about 0 bytes per call of it"),     # not a column
    (["fmi3GetFloat64"], [[7]], "about 0 bytes per call of it"),                # one sample
    (["fmi3GetFloat64"], [[7], [7], [7]], "about 0 bytes per call of it"),      # none made
    (["fmi3GetFloat64"], [[7], [8], [11]], "about 17,301,504 bytes per call of it"),
    (["fmi3GetFloat64"], [[7], [11]], "about 17,301,504 bytes per call of it"),   # two samples
    (["fmi3GetFloat64"], [[7], [7], [8]], "about 69,206,016 bytes per call of it"),  # one call
])
def test_the_growth_per_call_of_the_function_needs_its_calls(functions, counts, per):
    (v,) = _judge(_stopped(functions=functions, counts=counts,
                           grown_by={"fmi3GetFloat64": MIB}))
    assert f"grew inside fmi3GetFloat64 above all ({per})" in v.message


# ------------------------------------------------------------------ the simulation verdicts

from conformance.numerics import settings as st  # noqa: E402
from conformance.numerics.settings import Settings, Trajectory  # noqa: E402
from conformance.probes.instruments.api import (EVENT_INDICATOR_FAULT, NEXT_EVENT_FAULT,  # noqa: E402
                                                ODE_DAE_FAULT, PLANNED)
from conformance.probes.simulation import runs as R  # noqa: E402
from conformance.probes.simulation import verdicts as V  # noqa: E402
from conformance.report.catalogue import default_catalogue  # noqa: E402

SIM = {r.code: r.option_values for r in default_catalogue()}
MANIFEST = SimpleNamespace(file="manifest.xml", root_line=2, algebraic=[
    SimpleNamespace(vr=5, line=11, path="/m/AlgebraicVariable[1]"),
    SimpleNamespace(vr=6, line=12, path="/m/AlgebraicVariable[2]")])
ROOT = Location(file="manifest.xml", line=2)
NAMES = {1: "x", 5: "w1", 6: "w2"}
# the modelDescription of the state x and the algebraic variable w1, for the trajectory gaps
MODEL = SimpleNamespace(file="modelDescription.xml", by_vr={
    1: SimpleNamespace(name="x", vr=1, line=21, path="/fmiModelDescription/x"),
    5: SimpleNamespace(name="w1", vr=5, line=24, path="/fmiModelDescription/w1")})
X_DECLARED = Location(file="modelDescription.xml", line=21, path="/fmiModelDescription/x")


def _sim_ctx(dae=None, ode=None, facts=None, enable="ok", manifest=MANIFEST, points=(),
             dae_inst=None) -> ProbeContext:
    layout = SimpleNamespace(enable_status=enable, algebraic=[5, 6], states=[1],
                             name=lambda vr: NAMES.get(vr, f"v{vr}"),
                             derivatives=[2], residuals=[7, 8], ode_derivatives=[2])
    all_facts = {"layout": layout,
                 "simulation.dae": dae if dae is not None else ProbeSkipped("no DAE run"),
                 "simulation.ode": ode if ode is not None else ProbeSkipped("no ODE run"),
                 **(facts or {})}
    return ProbeContext(model=None, manifest=manifest, draft="alpha1", seed=0,  # type: ignore
                        rng=np.random.default_rng(0), points=list(points), dae=dae_inst,
                        ode=None, new_instance=lambda mode: None, facts=all_facts)


def _run(mode: str, status: str = st.OK, *, values=(1.0, 1.0, 1.0), times=None, **kw):
    values = np.asarray(values, dtype=float).reshape(-1, 1)
    times = list(times if times is not None else np.linspace(0.0, 1.0, len(values)))
    kw.setdefault("t_end", times[-1])
    return Trajectory(mode=mode, names=["x"], kinds=["state"], times=times, values=values,
                      status=status, stop_time=2.5, rtol=1e-6, atol=[1e-8], steps=10,
                      jacobian="directional derivatives", **kw)


def _run_evidence(traj, **extra):
    return {"mode": traj.mode, "t_start": traj.t_start, "t_reached": traj.t_end,
            "stop_time": 2.5, "rtol": 1e-6,
            "atol": "atol_factor * rtol * nominal of each variable", "steps": 10,
            "jacobian": "directional derivatives", "event": thaw(R.run_evidence(traj))["event"],
            **extra}


def test_no_consistent_start_is_simulation_failed_with_the_newton_message():
    init = _run("dae", st.INIT, values=[1.0], message="Newton diverged", init={"iterations": 9})
    ctx = _sim_ctx(init)
    (v,) = V.simulation_failed(ctx, **SIM["DAE801"])
    assert isinstance(ctx.facts["simulation.settings"], Settings)
    assert v.message == ("no consistent initial point in DAE mode: from the FMU's initial "
                         "values, Newton's method with the FMU's dg/dw fails (Newton diverged)")
    assert v.location == ROOT and v.subject == "dae:init" and v.part == "no-consistent-start"
    assert thaw(v.evidence) == _run_evidence(init, init={"iterations": 9})


def test_a_solver_failure_names_the_integrator_of_the_mode():
    dae = _run("dae")
    ode = _run("ode", st.SOLVER, message="CVODE gave up", event={"t": 0.5, "after_event": True},
               init={"a": 1})
    (v,) = V.simulation_failed(_sim_ctx(dae, ode), **SIM["DAE801"])
    assert v.message == "CVODE cannot integrate the FMU in ODE mode: CVODE gave up (stop time 2.5)"
    assert v.subject == "ode:solver" and v.part is None and v.location == ROOT
    assert thaw(v.evidence) == _run_evidence(ode, init={"a": 1})
    dae = _run("dae", st.SOLVER, message="IDA stopped", event={"t": 0.5, "after_event": True})
    (v,) = V.simulation_failed(_sim_ctx(dae), **SIM["DAE801"])
    assert v.message == "IDA cannot integrate the FMU in DAE mode: IDA stopped (stop time 2.5)"
    assert v.subject == "dae:solver" and v.part == "restart-after-event"
    assert list(V.simulation_failed(_sim_ctx(_run("dae"), _run("ode")), **SIM["DAE801"])) == []
    # other statuses are other rules'
    assert list(V.simulation_failed(_sim_ctx(_run("dae", st.BUDGET)),
                                    **SIM["DAE801"])) == []


def _singular(involved, **event):
    return _run("dae", st.SINGULAR, message="dg/dw became singular",
                event={"t": 0.123456789012, "condition": 1e13, "threshold": 1e12,
                       "involved": involved, **event}, init={"condition": 1.0})


def test_singular_along_the_trajectory_names_the_first_algebraic_variable_involved():
    traj = _singular(["w2", "w1"])
    (v,) = V.singular_along_trajectory(_sim_ctx(traj))
    assert v.message == ("dg/dw becomes singular along the DAE-mode trajectory at t = "
                         "0.123456789: the DAE is not index 1 there and the integration was "
                         "stopped")
    assert v.location == Location(file="manifest.xml", line=12, path="/m/AlgebraicVariable[2]")
    assert v.subject == "w2" and v.part is None
    assert thaw(v.evidence) == _run_evidence(
        traj, t=0.123456789012, condition=1e13, threshold=1e12,
        scale="1 / smallest singular value of dg/dw, columns scaled by nominal values, rows by "
              "each residual's total sensitivity")


def test_singular_without_a_variable_or_its_element_is_at_the_manifests_root():
    (v,) = V.singular_along_trajectory(_sim_ctx(_singular([])))
    assert v.location == ROOT and v.subject is None
    (v,) = V.singular_along_trajectory(_sim_ctx(_singular(["nowhere"])))
    assert v.location == ROOT and v.subject == "nowhere"
    (v,) = V.singular_along_trajectory(_sim_ctx(_singular(["w1"]), manifest=None))
    assert v.location == Location(file="modelDescription.xml") and v.subject == "w1"
    assert list(V.singular_along_trajectory(_sim_ctx(_run("dae")))) == []


class _FailingPoints:
    def evaluate(self, point, unknowns):
        raise FmiError("fmi3GetFloat64", "fmi3Error")


def test_a_failure_during_the_run_is_its_finding_unless_the_points_show_it():
    dae = _run("dae", st.FMU_FAILED, message="fmi3GetFloat64 returned fmi3Error",
               event={"t": 0.25, "call": "fmi3GetFloat64"}, recovered=3)
    ode = _run("ode", st.FMU_FAILED, message="NaN", event={}, t_end=0.75)
    found = list(V.evaluation_failed_during_simulation(_sim_ctx(dae, ode)))
    assert [v.message for v in found] == [
        "the FMU failed during the DAE-mode simulation at t = 0.25: fmi3GetFloat64 returned "
        "fmi3Error",
        "the FMU failed during the ODE-mode simulation at t = 0.75: NaN"]
    assert [v.subject for v in found] == ["dae:fmi3GetFloat64", "ode:"]
    assert found[0].location == ROOT
    assert thaw(found[0].evidence) == _run_evidence(dae, recovered=3)
    assert list(V.evaluation_failed_during_simulation(
        _sim_ctx(dae, points=[object()], dae_inst=_FailingPoints()))) == []
    assert list(V.evaluation_failed_during_simulation(_sim_ctx(_run("dae")))) == []


def test_a_run_out_of_steps_is_simulation_budget_exceeded():
    dae = _run("dae", st.BUDGET, message="max_steps reached", event={"limit": "max_steps"},
               t_end=1.23456789012)
    (v,) = V.simulation_budget_exceeded(_sim_ctx(dae))
    assert v.message == ("the DAE-mode simulation was stopped at t = 1.23456789 of 2.5: "
                         "max_steps reached")
    assert v.subject == "dae:max_steps" and v.location == ROOT
    assert thaw(v.evidence) == _run_evidence(dae)
    (v,) = V.simulation_budget_exceeded(_sim_ctx(_run("dae"), _run("ode", st.BUDGET)))
    assert v.subject == "ode:"
    assert list(V.simulation_budget_exceeded(_sim_ctx(_run("dae")))) == []


def test_a_next_event_time_behind_an_event_is_named_with_its_count():
    dae = _run("dae", events_behind=[(0.5, 0.25), (0.75, 0.75)], events_behind_count=7)
    (v,) = V.next_event_time_behind_during_simulation(_sim_ctx(dae, _run("ode")))
    assert v.message == (
        "at the event at t = 0.5 of the DAE-mode simulation, fmi3UpdateDiscreteStates announces "
        "nextEventTime = 0.25, not after the event (7 such event(s) in the run): the run can "
        "only drop it")
    assert v.subject == "dae:nextEventTime" and v.location == ROOT
    assert thaw(v.evidence) == _run_evidence(dae, t=0.5, next_event_time=0.25, behind=0.25,
                                             events_behind=[[0.5, 0.25], [0.75, 0.75]], count=7,
                                             place="DAE-mode simulation, t = 0.5")
    assert v.cause == causes.NEXT_EVENT_NOT_AHEAD   # the walk's finding of the same fault
    with pytest.raises(ProbeSkipped) as info:
        list(V.next_event_time_behind_during_simulation(
            _sim_ctx(dae, facts={NEXT_EVENT_FAULT: "x" * 200})))
    assert str(info.value) == ("next-event-time-not-ahead reports the fault already (" +
                               "x" * 160 + ")")
    assert list(V.next_event_time_behind_during_simulation(_sim_ctx(_run("dae")))) == []



def test_a_trajectory_gap_is_located_where_its_variable_is_declared():
    # an algebraic variable at its <AlgebraicVariable>, any other at its modelDescription
    # element, a name no variable has at the manifest's root
    ctx = dataclasses.replace(_sim_ctx(), model=MODEL)
    assert V._declared_location(ctx, "w2") == Location(file="manifest.xml", line=12,
                                                       path="/m/AlgebraicVariable[2]")
    assert V._declared_location(ctx, "x") == X_DECLARED
    assert V._declared_location(ctx, "nowhere") == ROOT
    assert V._declared_location(_sim_ctx(), "x") == ROOT   # no model read

# ode-dae-trajectory-mismatch: DAE mode at 1, ODE mode drifting to 1.00004 (gap 39.6 units)
MISMATCH = dict(factor=10.0, confirm_rtol_ratio=0.1, confirm_levels=2, confirm_shrink=0.5)
ODE_DRIFT = [1.0, 1.00002, 1.00004]


def _confirming(monkeypatch, outcomes):
    """simulate_mode replaced: each call pops the next (dae value, ode value) at t = 1, or an
    exception, or a ready Trajectory; the settings asked for are recorded."""
    asked = []

    def simulate_mode(ctx, mode, settings):
        asked.append((mode, settings.rtol, settings.wall_seconds))
        out = outcomes.pop(0)
        if isinstance(out, Exception):
            raise out
        if isinstance(out, Trajectory):
            return out
        return _run(mode, values=[1.0, 1.0, out])
    monkeypatch.setattr(V, "simulate_mode", simulate_mode)
    return asked


def test_a_gap_the_tighter_runs_do_not_shrink_is_the_finding(monkeypatch):
    asked = _confirming(monkeypatch, [1.0, 1.00004, 1.0, 1.000039])
    dae, ode = _run("dae"), _run("ode", values=ODE_DRIFT)
    ctx = dataclasses.replace(_sim_ctx(dae, ode), model=MODEL)
    (v,) = V.ode_dae_trajectory_mismatch(ctx, **MISMATCH)
    wall = R.settings_of(ctx).wall_seconds
    assert asked == [("dae", 1e-7, wall / 4), ("ode", 1e-7, wall / 4),
                     ("dae", pytest.approx(1e-8), wall / 4),
                     ("ode", pytest.approx(1e-8), wall / 4)]
    assert v.message == ("DAE mode and ODE mode give different trajectories: x differs by 39.6 "
                         "tolerance units at t = 1 (limit 10), and not less with tighter "
                         "tolerances")
    assert v.subject == "x" and v.location == X_DECLARED and v.part is None
    assert v.cause == causes.through("x")
    ev = thaw(v.evidence)
    assert ev["worst"]["variable"] == "x" and ev["worst"]["t"] == 1.0
    assert (ev["worst"]["dae"], ev["worst"]["ode"]) == (1.0, 1.00004)
    assert ev["gaps"] == {"x": pytest.approx(39.6, abs=0.05)}
    assert (ev["limit"], ev["rtol"], ev["compared_times"], ev["left_out"]) == (10.0, 1e-6, 3, [])
    assert ev["gap_unit"] == ("rtol * max(|dae|, |ode|) + atol_i, atol_i = atol_factor * rtol "
                              "* nominal_i")
    assert (ev["dae_status"], ev["ode_status"]) == ("ok", "ok")
    assert [c["rtol"] for c in ev["confirmation"]] == [1e-7, pytest.approx(1e-8)]
    assert ev["confirmation"][0] == {"rtol": 1e-7, "dae": 1.0, "ode": 1.00004,
                                     "difference": pytest.approx(4e-5)}
    assert ev["confirmation"][1]["difference"] == pytest.approx(3.9e-5)


def test_a_gap_that_shrinks_with_the_tolerance_is_the_integrators_error(monkeypatch):
    # a difference of 2e-5 at rtol 1e-7 is half of the first 4e-5: confirm_shrink 0.5 holds
    asked = _confirming(monkeypatch, [1.0, 1.00002])
    ctx = _sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT))
    assert list(V.ode_dae_trajectory_mismatch(ctx, **MISMATCH)) == []
    assert len(asked) == 2
    _confirming(monkeypatch, [1.0, 1.0000201, 1.0, 1.0000201])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                         **MISMATCH)
    assert len(thaw(v.evidence)["confirmation"]) == 2


def test_no_confirmation_without_levels_and_a_gap_at_the_limit_is_none():
    dae, ode = _run("dae"), _run("ode", values=ODE_DRIFT)
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                         **dict(MISMATCH, confirm_levels=0))
    assert thaw(v.evidence)["confirmation"] == []
    largest = thaw(v.evidence)["gaps"]["x"]
    assert list(V.ode_dae_trajectory_mismatch(
        _sim_ctx(dae, ode), **dict(MISMATCH, factor=largest, confirm_levels=0))) == []


def test_a_confirmation_that_cannot_run_is_noted_and_ends_the_tries(monkeypatch):
    asked = _confirming(monkeypatch, [ProbeSkipped("no instance")])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                         **MISMATCH)
    assert thaw(v.evidence)["confirmation"] == [{"rtol": 1e-7,
                                                 "note": "not confirmed: no instance"}]
    assert len(asked) == 1
    _confirming(monkeypatch, [FmiError("fmi3Instantiate", "fmi3Error")])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                         **MISMATCH)
    assert thaw(v.evidence)["confirmation"] == [
        {"rtol": 1e-7, "note": "not confirmed: fmi3Instantiate returned fmi3Error"}]


def test_a_confirmation_run_that_ends_early_is_noted(monkeypatch):
    short = _run("dae", st.SOLVER, values=[1.0, 1.0], times=[0.0, 0.5])
    _confirming(monkeypatch, [short, 1.0])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                         **MISMATCH)
    assert thaw(v.evidence)["confirmation"] == [
        {"rtol": 1e-7, "note": "not confirmed: the DAE-mode run ended at t = 0.5 "
                               "(solver-failure)"}]
    renamed = Trajectory(mode="ode", names=["y"], kinds=["state"], times=[0.0, 0.5, 1.0],
                         values=np.ones((3, 1)), t_end=1.0, status=st.OK)
    _confirming(monkeypatch, [1.0, renamed])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                         **MISMATCH)
    assert thaw(v.evidence)["confirmation"][0]["note"] == (
        "not confirmed: the ODE-mode run ended at t = 1 (ok)")


def test_a_confirmation_the_safety_net_stopped_decides_nothing(monkeypatch):
    stopped = _run("dae", st.TIME_BUDGET, event={"value": 30.0})
    _confirming(monkeypatch, [stopped, 1.0])
    with pytest.raises(R.OutOfTime) as info:
        list(V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT)),
                                           **MISMATCH))
    assert str(info.value).endswith("(a confirmation run at rtol 1e-07)")
    assert str(info.value).startswith("time budget: the DAE-mode run was stopped at t = 1 of 2.5")


def test_a_tolerance_that_cannot_be_tightened_is_not_confirmed(monkeypatch):
    asked = _confirming(monkeypatch, [])
    dae = _run("dae")
    dae.rtol, dae.atol = 1e-12, [1e-20]
    ode = _run("ode", values=[1.0, 1.0 + 2e-11, 1.0 + 4e-11])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                         **dict(MISMATCH, confirm_rtol_ratio=0.05))
    # 1e-12 * 0.05 = 5e-14 is below 1e-13: noted, not run; the next level is tried too
    assert asked == []
    assert [c["note"] for c in thaw(v.evidence)["confirmation"]] == [
        "not confirmed: the tolerance cannot be tightened"]


def test_the_runs_must_have_something_in_common_and_no_faulty_indicators():
    with pytest.raises(ProbeSkipped, match="^the FMU has no usable enable parameter, hence no "
                                           "ODE mode$"):
        list(V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), _run("ode"), enable="absent"),
                                           **MISMATCH))
    apart = _run("ode", times=[2.0, 3.0, 4.0])
    with pytest.raises(ProbeSkipped, match="^the two runs have no output time or variable in "
                                           "common$"):
        list(V.ode_dae_trajectory_mismatch(_sim_ctx(_run("dae"), apart), **MISMATCH))
    fault = {EVENT_INDICATOR_FAULT: "y" * 200}
    for dae, ode in ((_run("dae", state_events=1), _run("ode", values=ODE_DRIFT)),
                     (_run("dae"), _run("ode", values=ODE_DRIFT, time_events=1))):
        with pytest.raises(ProbeSkipped) as info:
            list(V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode, facts=fault), **MISMATCH))
        assert str(info.value) == ("the runs root-find on event indicators that are faulty in "
                                   "DAE mode (" + "y" * 160 + "); that finding is the cause of "
                                   "any gap")
    # faulty indicators but no events in either run: judged
    assert len(list(V.ode_dae_trajectory_mismatch(
        _sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT), facts=fault),
        **dict(MISMATCH, confirm_levels=0)))) == 1


def test_a_gap_at_the_initial_point_is_the_rules_own_unless_another_owns_it():
    dae, ode = _run("dae"), _run("ode", values=[1.0001, 1.0001, 1.0001])
    (v,) = V.ode_dae_trajectory_mismatch(dataclasses.replace(_sim_ctx(dae, ode), model=MODEL),
                                         **MISMATCH)
    assert v.message == ("DAE mode and ODE mode give different trajectories: x differs by 99 "
                         "tolerance units at t = 0 (limit 10), already at the initial point")
    assert v.part == "initial-gap" and v.location == X_DECLARED
    assert thaw(v.evidence)["confirmation"] == []
    with pytest.raises(ProbeSkipped) as info:
        list(V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode, facts={ODE_DAE_FAULT: "z" * 200}),
                                           **MISMATCH))
    assert str(info.value) == ("the two modes differ at the initial point already, the first "
                               "cause of the gap (" + "z" * 160 + ")")
    with pytest.raises(ProbeSkipped) as info:
        list(V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode, facts={PLANNED: ("DAE762",)}),
                                           **MISMATCH))
    assert str(info.value) == ("the two runs' fresh instances start from different states (x), "
                               "so the gap is not the modes'; instances-not-independent judges "
                               "the instances")
    # planned, but the states agree within the limit: the gap is the rule's
    near = _run("ode", values=[1.000005, 1.0001, 1.0001])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, near, facts={PLANNED: ("DAE762",)}),
                                         **dict(MISMATCH, confirm_levels=0))
    assert v.message.endswith(", and not less with tighter tolerances")


def test_states_apart_by_exactly_the_limit_are_the_same_states():
    dae = _run("dae")
    ode = _run("ode", values=[1.00002, 1.00002, 1.00002])
    gap = thaw(next(iter(V.ode_dae_trajectory_mismatch(
        _sim_ctx(dae, ode), **dict(MISMATCH, factor=1.0))))
        .evidence)["gaps"]["x"]
    start = SimpleNamespace(gaps={"x": gap, "w": 1e9})
    traj = Trajectory(mode="dae", names=["x", "w"], kinds=["state", "algebraic"], times=[0.0],
                      values=np.ones((1, 2)))
    assert V._same_states(start, traj, gap) and not V._same_states(start, traj, gap * 0.999)
    ctx = _sim_ctx(dae, ode, facts={PLANNED: ("DAE762",)})
    assert V._initial_gap_owner(ctx, start, gap) == ""
    assert V._initial_gap_owner(ctx, start, gap * 0.999).startswith(
        "the two runs' fresh instances start from different states (x)")


def test_a_gap_born_at_the_first_event_of_either_run_is_after_events():
    dae = _run("dae", values=[1.0, 1.0, 1.0, 1.0, 1.0], event_times=[0.9], state_events=1)
    ode = _run("ode", values=[1.0, 1.0, 1.0, 1.1, 1.1], event_times=[0.75], state_events=1)
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode), **dict(MISMATCH, confirm_levels=0))
    assert v.part == "after-events"     # born at 0.75, the ODE run's event: not before it
    ode.event_times = [0.5]
    dae.event_times = [0.9]
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode), **dict(MISMATCH, confirm_levels=0))
    assert v.part == "after-events"
    # an event before any output time: nothing before it to compare, after events
    ode.event_times = [-1.0]
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode), **dict(MISMATCH, confirm_levels=0))
    assert v.part == "after-events"


# ------------------------------------------------------------------ memory-grows at its limits

from conformance.numerics.compare import compare  # noqa: E402
from conformance.numerics.growth import attribute, growth  # noqa: E402

KIB = 1024


def _uniform(per_call: float = 600.0, heap=None) -> PathRun:
    rss = [(40 << 20) + int(per_call * c) for c in CALLS]
    return PathRun(RUN, calls=3000, stopped="budget", samples=list(zip(CALLS, rss)),
                   heap=heap if heap is not None else [])


def _late_burst(per_call: float = 1000.0, counts: bool = False) -> PathRun:
    """fmi3GetFloat64 made 5 times as often in the third quarter of the samples as in the
    fourth: the growth of the second half is concentrated in its first quarter."""
    steps = [100] * 8 + [500] * 4 + [100] * 4
    gets = [sum(steps[:k]) + 3 * (k % 3) for k in range(16)]
    sets = [100 * k for k in range(16)]
    calls = [g + s for g, s in zip(gets, sets)]
    rss = [(40 << 20) + int(per_call * g) for g in gets]
    return PathRun(RUN, calls=calls[-1], stopped="budget", samples=list(zip(calls, rss)),
                   counts=[[g, s] for g, s in zip(gets, sets)] if counts else [],
                   functions=["fmi3GetFloat64", "fmi3SetFloat64"] if counts else [])


def _found(run: PathRun, series=None):
    return growth([c for c, _ in run.samples], series or [r for _, r in run.samples])


def test_each_threshold_of_the_growth_per_call_holds_at_equality():
    run = _uniform()
    found = _found(run)
    assert len(_judge(run, bytes_per_call_quick=found.sustained_slope)) == 1
    assert len(_judge(run, min_growth_kib=found.total / KIB)) == 1
    assert _judge(run, min_growth_kib=found.total / KIB * 1.0001) == []


def test_each_quarter_must_grow_by_a_quarter_of_the_minimum():
    run = _late_burst()
    found = _found(run)
    q = min(found.quarter_totals)
    assert found.total >= 4.5 * q                        # the burst: one quarter grew little
    assert len(_judge(run, min_growth_kib=4 * q / KIB)) == 1        # exactly a quarter: enough
    assert _judge(run, min_growth_kib=4.5 * q / KIB) == []          # under a quarter: none


def test_a_heap_that_grew_by_exactly_the_minimum_confirms_the_leak():
    heap = [(9 << 20) + 300 * c for c in CALLS]
    run = _uniform(heap=heap)
    total = _found(run, heap).total
    assert len(_judge(run, min_growth_kib=total / KIB)) == 1
    assert _judge(run, min_growth_kib=total / KIB * 1.0001) == []


def test_a_heap_that_hardly_grew_is_no_leak_and_one_of_another_length_is_not_read():
    slow = [(9 << 20) + c for c in CALLS]                # 1 byte per call: 1.4 KiB in all
    assert _judge(_uniform(heap=slow)) == []
    (v,) = _judge(_uniform(heap=[9 << 20] * 15))
    assert v.location == Location(file="modelDescription.xml") and v.subject is None


def test_the_function_minimum_holds_at_equality():
    run = _leaking()
    kept = _found(run)
    (v,) = _judge(run, min_function_growth_kib=kept.total / KIB)
    assert v.subject == "fmi3GetFloat64"
    # a function's share just at its bytes per call is leaking too
    shares = attribute(run.counts, [r for _, r in run.samples])
    (v,) = _judge(run, bytes_per_call_quick=shares.per_unit[0])
    assert v.subject == "fmi3GetFloat64"


def test_the_function_quarters_hold_at_a_quarter_of_the_minimum():
    run = _late_burst(counts=True)
    kept = _found(run)
    q = min(kept.quarter_totals)
    (v,) = _judge(run, min_function_growth_kib=4 * q / KIB)
    assert v.subject == "fmi3GetFloat64"
    # between a fifth and a quarter: the function is not named (the burst is no leak of it)
    found = _judge(run, min_function_growth_kib=4.5 * q / KIB)
    assert all(v.subject is None for v in found)


def test_a_share_counts_from_half_the_minimum():
    run = _leaking(per_get=1000.0, per_set=300.0)
    shares = attribute(run.counts, [r for _, r in run.samples])
    set_share = shares.totals[1]
    (v,) = _judge(run, min_function_growth_kib=2 * set_share / KIB)
    assert v.message.endswith(", and by fmi3SetFloat64 300 bytes per call: the FMU allocates "
                              "without freeing")
    (v,) = _judge(run, min_function_growth_kib=2.5 * set_share / KIB)
    assert "and by" not in v.message
    # a single share well above half the minimum but under the minimum itself is leaking
    (v,) = _judge(_leaking(), min_function_growth_kib=500.0)
    assert v.subject == "fmi3GetFloat64"


def test_three_leaking_functions_are_listed_after_the_first():
    gets = GETS
    sets = [100 * k + 5 * (k % 4) for k in range(16)]
    ders = [50 * k + 11 * (k % 5) for k in range(16)]
    calls = [a + b + c for a, b, c in zip(gets, sets, ders)]
    rss = [(40 << 20) + 1000 * a + 400 * b + 300 * c for a, b, c in zip(gets, sets, ders)]
    run = PathRun(RUN, calls=calls[-1], stopped="budget", samples=list(zip(calls, rss)),
                  counts=[list(t) for t in zip(gets, sets, ders)],
                  functions=["fmi3GetFloat64", "fmi3SetFloat64", "fmi3GetDerivatives"])
    (v,) = _judge(run)
    assert v.message.endswith(", and by fmi3SetFloat64 400 bytes per call; fmi3GetDerivatives "
                              "300 bytes per call: the FMU allocates without freeing")


def test_an_earlier_death_in_the_path_run_is_not_run_again():
    ctx = _ctx(facts={})
    ctx.endurance, ctx.died = "quick", ("DAE761",)
    with pytest.raises(ProbeSkipped) as info:
        list(memory_grows(ctx, **MEMORY))
    assert str(info.value) == ("the path run ended an earlier worker during DAE761 (see its "
                               "binary-* finding): not run again")


def test_a_run_stopped_after_one_call_counts_that_call():
    run = PathRun(RUN, calls=1, stopped="memory", samples=[(100, 40 * MIB), (101, 106 * MIB)])
    (v,) = _judge(run)
    assert "66.0 MiB in 1 FMI calls on one instance along the path (about 69,206,016 bytes " \
           "per call)" in v.message
    assert v.location == Location(file="modelDescription.xml")


# ------------------------------------------------------------------ simulation verdicts at their limits

def test_each_mode_is_judged_even_when_the_first_is_not():
    ode = _run("ode", st.FMU_FAILED, message="NaN", event={"t": 0.5})
    (v,) = V.evaluation_failed_during_simulation(_sim_ctx(_run("dae"), ode))
    assert v.subject == "ode:"
    behind = _run("ode", events_behind=[(0.5, 0.5)], events_behind_count=1)
    (v,) = V.next_event_time_behind_during_simulation(_sim_ctx(_run("dae"), behind))
    assert v.subject == "ode:nextEventTime"


def test_the_confirmation_runs_on_this_probes_context(monkeypatch):
    seen = []

    def simulate_mode(ctx, mode, settings):
        seen.append(ctx)
        return _run(mode, values=[1.0, 1.0, 1.0 if mode == "dae" else 1.00004])
    monkeypatch.setattr(V, "simulate_mode", simulate_mode)
    ctx = _sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT))
    list(V.ode_dae_trajectory_mismatch(ctx, **dict(MISMATCH, confirm_levels=1)))
    assert seen == [ctx, ctx]


def test_a_tolerance_of_exactly_1e13_is_still_tightened(monkeypatch):
    asked = _confirming(monkeypatch, [1.0, 1.00004])
    dae = _run("dae")
    dae.rtol, dae.atol = 1e-13, [1e-20]
    ode = _run("ode", values=[1.0, 1.0 + 2e-12, 1.0 + 4e-12])
    list(V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                       **dict(MISMATCH, confirm_rtol_ratio=1.0,
                                              confirm_levels=1)))
    assert [rtol for _, rtol, _ in asked] == [1e-13, 1e-13]
    _confirming(monkeypatch, [])
    dae.rtol = 1e-12
    ode = _run("ode", values=[1.0, 1.0 + 2e-11, 1.0 + 4e-11])
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                         **dict(MISMATCH, confirm_rtol_ratio=0.05))
    assert thaw(v.evidence)["confirmation"] == [
        {"rtol": pytest.approx(5e-14), "note": "not confirmed: the tolerance cannot be tightened"}]


def test_a_difference_shrunk_to_exactly_the_share_is_the_integrators(monkeypatch):
    _confirming(monkeypatch, [1.0, 1.00004])
    ctx = _sim_ctx(_run("dae"), _run("ode", values=ODE_DRIFT))
    assert list(V.ode_dae_trajectory_mismatch(ctx, **dict(MISMATCH, confirm_shrink=1.0))) == []


def test_a_gap_at_the_start_of_exactly_the_limit_is_not_an_initial_gap():
    dae = _run("dae")
    ode = _run("ode", values=[1.000005, 1.00002, 1.00004])
    start = compare(V._first(dae), V._first(ode)).largest
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                         **dict(MISMATCH, factor=start, confirm_levels=0))
    assert v.message.endswith(", and not less with tighter tolerances")


def test_a_gap_before_the_event_of_exactly_the_limit_is_born_after_it():
    dae = _run("dae", values=[1.0, 1.0, 1.0, 1.0, 1.0], event_times=[0.6], state_events=1)
    ode = _run("ode", values=[1.0, 1.0, 1.00001, 1.1, 1.1], event_times=[0.6], state_events=1)
    before = compare(V._until(dae, 0.6), V._until(ode, 0.6)).largest
    (v,) = V.ode_dae_trajectory_mismatch(_sim_ctx(dae, ode),
                                         **dict(MISMATCH, factor=before, confirm_levels=0))
    assert v.part == "after-events"


def test_a_state_the_comparison_left_out_is_not_apart():
    ctx = _sim_ctx(_run("dae"), facts={PLANNED: ("DAE762",)})
    start = SimpleNamespace(gaps={"w1": 50.0})            # x was not compared
    assert V._initial_gap_owner(ctx, start, 0.5) == ""
    assert V._initial_gap_owner(_sim_ctx(_run("dae")), SimpleNamespace(gaps={"x": 50.0}),
                                0.5) == ""               # instances-not-independent not planned
