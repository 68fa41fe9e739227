"""The endurance probes (DAE760-DAE762), the --endurance levels, and a late crash's call count.

The defect variants (tests/fixtures/defects/endurance.py) strike after 5000 FMI calls on one
instance (LATE_AFTER in scenes/common/fmi3_framework.c); test_defects.py checks that each is
caught by its rule only, these tests check what the findings carry.
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from conformance.report.catalogue import Catalogue, default_catalogue
from conformance.commands.cli import main
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Finding, FmuReport, thaw
from conformance.probes.endurance import run as endurance_run
from conformance.probes.instruments.api import Point, ProbeContext, ProbeSkipped
from conformance.probes.endurance.memory import memory_grows
from conformance.probes.endurance.sustained import KINDS, evaluation_fails_late
from conformance.probes.endurance.calls import INSTANCE_CYCLE
from conformance.probes.endurance.run import FACT, PathRun, RunSettings, lap_points
from conformance.runtime.callrecord import CallRecord
from tests.checkkit import checked
from tests.fixtures import build_scene, chain

ENDURANCE = ("DAE760", "DAE761", "DAE762")
LATE_AFTER = 5000      # scenes/common/fmi3_framework.c: calls on one instance before it strikes
MEMORY_OPTIONS = default_catalogue()["memory-grows"].option_values


def _check(scene: str, *defines: str, **options) -> FmuReport:
    return checked(build_scene(scene, defines=list(defines)), options=EngineOptions(**options))


def _only(report: FmuReport, code: str) -> Finding:
    found = [f for f in report.findings if f.code == code]
    assert len(found) == 1, [(f.code, f.message) for f in report.findings]
    return found[0]


# -- a late crash: binary-crashed with the call count ------------------------------------------


def test_late_crash_is_binary_crashed_with_the_call_count_and_is_not_repeated():
    report = _check("SimpleDAE", "DEFECT_LATE_CRASH")
    crash = _only(report, "DAE701")
    ev = thaw(crash.evidence)
    assert ev["probe"] == "DAE760" and ev["call_in_progress"] is True
    assert ev["call"].startswith("fmi3")
    # the path instance's fmi3InstantiateModelExchange and LATE_AFTER calls returned, the next
    # one crashed; before the path, the importer's optional calls were tried on a fresh
    # instance (endurance_calls.StepCalls.prepare: about a hundred calls)
    assert LATE_AFTER + 1 < ev["calls_in_probe"] < LATE_AFTER + 200
    assert ev["call_count"] > ev["calls_in_probe"]  # the point probes ran before, same worker
    # memory-grows judges the same run: the fresh worker does not run it (and crash) again
    assert [f.code for f in report.findings] == ["DAE701"]
    assert "DAE761" in dict(report.rules_skipped)
    assert {"DAE760", "DAE762"} <= set(report.rules_run)


def test_a_crash_outside_the_endurance_probes_carries_no_call_count():
    report = _check("HelloWorldDAE", "DEFECT_SEGFAULT_GETFLOAT64", endurance="off")
    crashes = [f for f in report.findings if f.code == "DAE701"]
    assert crashes and all("call_count" not in dict(f.evidence) for f in crashes)


def test_call_record_counts_the_calls_of_the_worker_and_of_the_probe():
    record = CallRecord()
    record.set_probe("setup")
    for n in range(1, 8):
        record.enter("fmi3SetTime", n)
        record.leave()
    record.set_probe("DAE760")
    record.enter("fmi3GetFloat64", 8)
    assert CallRecord.parse(record.buffer) == ("DAE760", "fmi3GetFloat64", True)
    counts = CallRecord.counts(record.buffer)
    assert counts == (8, 7)
    assert counts.completed(True) == 7 and counts.completed_in_probe(True) == 0
    record.leave()
    assert counts.completed(False) == 8 and counts.completed_in_probe(False) == 1
    assert CallRecord.counts(b"") == (0, 0)
    # what FMI calls grew the address space by, and the call that grew it last
    assert CallRecord.growth(record.buffer) == (0, "")
    record.grew("fmi3GetFloat64", 3 << 30)
    assert CallRecord.growth(record.buffer) == (3 << 30, "fmi3GetFloat64")
    assert CallRecord.parse(record.buffer)[:2] == ("DAE760", "fmi3GetFloat64")


# -- evaluation-fails-late ----------------------------------------------------------------------


def test_late_error_names_the_call_the_count_and_the_fresh_instance():
    finding = _only(_check("HelloWorldDAE", "DEFECT_LATE_ERROR"), "DAE760")
    ev = thaw(finding.evidence)
    assert ev["status"] == "fmi3Error" and ev["call"].startswith("fmi3")
    assert ev["calls_before"] == LATE_AFTER + 1   # fmi3InstantiateModelExchange + LATE_AFTER
    assert ev["fresh_instance"] == "ok"
    assert ev["level"] == "quick" and ev["lap"] >= 2
    assert finding.subject == ev["call"]


def test_a_clean_scene_makes_the_whole_budget_of_calls():
    report = _check("HelloWorldDAE", select=("DAE76",))
    assert report.findings == ()
    info = thaw(report.info)["endurance"]
    budget = default_catalogue()["evaluation-fails-late"].option_values["calls_quick"]
    assert info["level"] == "quick" and info["stopped"] == "budget"
    assert budget <= info["path_calls"] < budget + 10 and info["laps"] > 10
    assert info["cycles"] == default_catalogue()["DAE762"].option_values["cycles_quick"]


def _with_options(changes: dict[str, dict[str, object]]) -> Catalogue:
    rules = []
    for rule in default_catalogue():
        if rule.code in changes:
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, **changes[rule.code]}.items())))
        rules.append(rule)
    return Catalogue(rules)


def test_long_level_uses_the_long_budget():
    catalogue = _with_options({"DAE760": {"calls_long": 3000}, "DAE762": {"cycles_long": 3}})
    report = check_fmu(build_scene("SimpleDAE"), catalogue=catalogue,
                       options=EngineOptions(select=("DAE76",), endurance="long"))
    assert report.findings == ()
    info = thaw(report.info)["endurance"]
    assert info["level"] == "long" and info["budget_calls"] == 3000
    assert 3000 <= info["path_calls"] < 3010 and info["cycles"] == 3


# -- memory-grows -------------------------------------------------------------------------------


def test_leak_is_reported_with_bytes_per_call_and_the_samples():
    finding = _only(_check("Robertson", "DEFECT_LEAK", select=("DAE76",)), "DAE761")
    ev = thaw(finding.evidence)
    # 1 KiB per fmi3GetFloat64 (and the allocator's 16): the function and its bytes per call,
    # fitted on each function's calls; the others' shares stay near zero
    assert (finding.subject, ev["function"]) == ("fmi3GetFloat64", "fmi3GetFloat64")
    assert 1024 <= ev["bytes_per_call"] < 1024 + 64
    assert all(abs(b) < 64 for n, b in ev["fitted"].items() if n != "fmi3GetFloat64")
    # the resident set grows with every call of any kind: about 1 KiB over five calls a step
    assert all(100 < q < 600 for q in ev["quarter_slopes"])
    assert ev["growth_kib"] >= ev["min_growth_kib"]
    assert finding.message.startswith(f"the C heap in use grows by {ev['bytes_per_call']:,} "
                                      "bytes per call of 'fmi3GetFloat64' along the path")
    assert ev["threshold_bytes_per_call"] == MEMORY_OPTIONS["bytes_per_call_quick"]
    calls = [c for c, _ in ev["samples"]]
    assert len(calls) >= 8 and calls == sorted(calls) and ev["samples"][0] == [0, 0]
    assert ev["samples"][-1][1] > ev["growth_kib"]     # the second half grew by growth_kib


def _context(facts: dict) -> ProbeContext:
    return ProbeContext(model=None, manifest=None, draft="alpha1", seed=0,  # type: ignore[arg-type]
                        rng=np.random.default_rng(0), points=[], dae=None, ode=None,
                        new_instance=lambda mode: None, facts=facts)  # type: ignore[arg-type,return-value]


def test_memory_is_read_on_linux_only(monkeypatch):
    monkeypatch.setattr(endurance_run.sys, "platform", "darwin")
    assert endurance_run.resident_bytes() is None
    settings = RunSettings("quick", calls=100, values=10_000, seconds=1.0, samples=40,
                           max_growth_mib=256.0)
    ctx = _context({FACT: PathRun(settings, memory_note="resident memory is Linux only")})
    with pytest.raises(ProbeSkipped):
        list(memory_grows(ctx, **MEMORY_OPTIONS))


def test_a_run_too_short_to_judge_memory_is_skipped():
    settings = RunSettings("quick", calls=100, values=10_000, seconds=1.0, samples=40,
                           max_growth_mib=256.0)
    ctx = _context({FACT: PathRun(settings, calls=12, stopped="failure",
                                  samples=[(0, 1 << 20), (10, 1 << 21)])})
    with pytest.raises(ProbeSkipped):
        list(memory_grows(ctx, **MEMORY_OPTIONS))


# The samples of a correct Chain at N = 10,000 (quick level, 748 calls: the budget in values):
# a page now and then, and one 2.7 MiB step of the heap when the path instantiates anew.
CHAIN_10000 = [(0, 0), *((18 * k, 304 + 4 * (k // 3)) for k in range(1, 32)),
               *((586 + 18 * k, 3024 + 4 * (k // 3)) for k in range(9))]


def _judged(samples: list[tuple[int, int]], calls: int,
            heap: list[int] | None = None) -> list:
    """memory-grows on a run of these (calls, KiB grown) samples of the resident set, and of the
    C heap in use (KiB grown, one per sample) where given."""
    settings = RunSettings("quick", calls=50_000, values=10**7, seconds=60.0, samples=40,
                           max_growth_mib=256.0)
    run = PathRun(settings, calls=calls, stopped="budget", budget_calls=calls,
                  samples=[(c, (45 << 20) + kib * 1024) for c, kib in samples],
                  heap=[(9 << 20) + kib * 1024 for kib in heap or ()])
    return list(memory_grows(_context({FACT: run, "endurance.settings": settings}),
                             **MEMORY_OPTIONS))


def test_an_allocator_step_in_a_short_run_is_not_a_leak():
    assert _judged(CHAIN_10000, 748) == []


@pytest.mark.parametrize("bytes_per_call", [3_000, 12_000, 100_000])
def test_a_leak_in_a_short_run_is_memory_grows(bytes_per_call):
    # the same short run, leaking from the first call, with the same step on top
    leaking = [(c, kib + c * bytes_per_call // 1024) for c, kib in CHAIN_10000]
    found = _judged(leaking, 748)
    assert len(found) == 1
    ev = thaw(found[0].evidence)
    assert all(q > MEMORY_OPTIONS["min_growth_kib"] / 4 for q in ev["quarter_growth_kib"])


@pytest.mark.parametrize("heap_follows, found", [(False, 0), (True, 1)])
def test_resident_growth_the_heap_does_not_show_is_no_leak(heap_follows, found):
    """The short run of a large model whose resident set grows 3 KiB per call (the allocator
    keeping the pages of large instances made and freed, as the Chain at 10,000 did): no
    finding while the C heap in use stays flat; the same growth in the heap is a leak."""
    leaking = [(c, kib + c * 3_000 // 1024) for c, kib in CHAIN_10000]
    heap = [kib if heap_follows else 0 for _, kib in leaking]
    assert len(_judged(leaking, 748, heap=heap)) == found


def test_a_run_the_safety_net_stopped_is_judged_by_no_rule():
    # the wall clock is a safety net: its end is "not run: time budget", never a verdict,
    # whatever the samples or the calls made would say
    settings = RunSettings("quick", calls=50_000, values=10**9, seconds=0.5, samples=40,
                           max_growth_mib=256.0)
    grown = [(k * 1000, (1 << 20) + k * (1 << 20)) for k in range(40)]   # 1 KiB per call
    run = PathRun(settings, calls=39_000, stopped="time", samples=grown, budget_calls=50_000)
    options = default_catalogue()["DAE760"].option_values
    for probe, kwargs in ((memory_grows, MEMORY_OPTIONS), (evaluation_fails_late, options)):
        with pytest.raises(ProbeSkipped, match="^time budget"):
            list(probe(_context({FACT: run, "endurance.settings": settings}), **kwargs))


@pytest.mark.parametrize("n", [100, 1000, 3000])
def test_the_budget_of_a_large_model_is_counted_in_values_not_seconds(n):
    # every step passes arrays of about 2N values: the run stops on values_quick, a count
    # from the model's size, the same on every machine
    options = default_catalogue()["DAE760"].option_values
    report = check_fmu(chain.build_chain(n), options=EngineOptions(select=("DAE76",)))
    assert report.findings == () and not report.rules_not_run
    info = thaw(report.info)["endurance"]
    # x set and der(x) read, w and u set, r and y read; the state vector and its nominals;
    # directional and adjoint derivatives, each N + 2 knowns (x, w, u) and N + 2 unknowns
    # (r, der(x), y)
    assert info["calls"] == ["fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates",
                             "fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative",
                             INSTANCE_CYCLE]
    per_step = 2 * 1 + (n + 1) + (n + 1) + 2 + 2 * (2 * n + 4)
    steps = options["values_quick"] // per_step
    assert info["stopped"] == "budget"
    assert info["budget_calls"] == min(options["calls_quick"], steps * 9)
    # the budget is checked before each step, and an instance cycle ends each lap
    assert info["budget_calls"] <= info["path_calls"] < info["budget_calls"] + 20


# -- instances-not-independent ------------------------------------------------------------------


def test_global_state_is_found_by_the_survey_against_instances_alone():
    # the states in one C global: the first instance, read again after a later one was set
    # to another point, computes with the later one's states (conformance/probes/independence)
    finding = _only(_check("SimpleDAE", "DEFECT_GLOBAL_STATE", select=("DAE76",)), "DAE762")
    ev = thaw(finding.evidence)
    assert finding.subject == "shared-" + ev["compared"].split(" ")[0]
    assert ev["comparisons"][0]["compared"] == ev["compared"]
    rows = {"der(x1)", "der(x2)", "__residual0", "__residual1", "y1", "y2"}
    items = {d["item"] for c in ev["comparisons"] for d in c["differences"]}
    assert items and items <= rows | {f"d({r}) along every known" for r in rows}
    assert all(d["alone"] != d["actual"] for c in ev["comparisons"] for d in c["differences"])


def test_stale_state_is_found_after_a_free_instantiate_cycle():
    finding = _only(_check("HelloWorldDAE", "DEFECT_STALE_STATES", select=("DAE76",)), "DAE762")
    ev = thaw(finding.evidence)
    assert ev["kind"] == "cycle" and ev["cycle"] == 1 and ev["cycles_run"] == 1
    assert "x" in {d["variable"] for d in ev["differences"]}
    assert set(KINDS) >= {ev["kind"]}


# -- the level "off" ----------------------------------------------------------------------------


def test_off_skips_the_endurance_stage_with_a_reason():
    report = _check("HelloWorldDAE", "DEFECT_LATE_ERROR", endurance="off")
    skipped = dict(report.rules_skipped)
    assert all(code in skipped for code in ENDURANCE)
    assert not set(ENDURANCE) & set(report.rules_run)
    assert not [f for f in report.findings if f.code in ENDURANCE]
    assert "endurance" not in thaw(report.info)


def test_cli_option_and_config_key(tmp_path, monkeypatch, capsys):
    fmu = str(build_scene("HelloWorldDAE"))
    out = tmp_path / "r.json"

    def skipped(*argv: str) -> set[str]:
        assert main(["check", fmu, "--select", "DAE76", "--format", "json", "-o", str(out),
                     *argv]) == 0
        entries = json.loads(out.read_text())["fmus"][0]["rules_skipped"]
        return {e["code"] for e in entries}

    monkeypatch.chdir(tmp_path)
    assert skipped("--endurance", "off") == set(ENDURANCE)
    (tmp_path / "pyproject.toml").write_text('[tool.lsdae]\nendurance = "off"\n')
    assert skipped() == set(ENDURANCE)
    assert skipped("--endurance", "quick") == set()     # the command line wins
    (tmp_path / "pyproject.toml").write_text('[tool.lsdae]\nendurance = "forever"\n')
    assert main(["check", fmu, "--select", "DAE76"]) == 2
    assert "endurance" in capsys.readouterr().err


# -- the path ---------------------------------------------------------------------------------


def test_the_path_is_a_closed_polygon_through_the_points():
    a = Point(0.0, {1: 0.0, 2: 10.0}, "start")
    b = Point(0.4, {1: 4.0, 2: 10.0}, "near-1")
    lap = lap_points([a, b], steps=4)
    assert len(lap) == 8
    assert lap[0].t == 0.0 and lap[0].values == a.values
    assert lap[2].t == pytest.approx(0.2) and lap[2].values[1] == pytest.approx(2.0)
    assert lap[4].values == b.values and lap[6].values[1] == pytest.approx(2.0)
    assert min(p.t for p in lap) >= 0.0
    assert lap_points([a]) == [a] and lap_points([]) == []
