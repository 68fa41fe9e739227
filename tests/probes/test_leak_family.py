"""Leaks, a family (issue 20, point 3; issue 30, point 2): a leak in any FMI call an importer
makes, of any size, judged per function.

``-D DEFECT_LEAK_CALL=<function> -D DEFECT_LEAK_BYTES=<n>`` (scenes/common/fmi3_framework.c)
keeps n bytes, written, on every call of that function. The endurance path run makes every call
an importer makes (conformance/probes/endurance/calls.py) and changes their mix between memory
samples, so that ``memory-grows`` (DAE761, information) fits the growth of the C heap on each
function's calls and names the function: the quick level finds ``bytes_per_call_quick`` bytes
per call (64) in any function called once per step, whatever the others do; below that (16 or
32 bytes, with the allocator's 16 less than 64) it is nobody's finding, and nothing else may be
said about it either. A leak that makes the run stop at ``max_growth_mib`` is the growth up to
the stop, naming the function inside which the library saw the address space grow; a leak so
large that the address space runs out first is ``binary-memory-limit`` (DAE703), naming the call
that took the memory.
"""
from __future__ import annotations

import pytest

from conformance.report.catalogue import default_catalogue
from conformance.report.findings import FmuReport, Severity, thaw
from conformance.run.engine import EngineOptions, check_fmu
from tests.fixtures import build_scene

KIB, MIB = 1024, 1 << 20
OPTIONS = default_catalogue()["memory-grows"].option_values
SELECT = ("DAE70", "DAE76")      # the runner's binary-* rules and the endurance probes
BASE_CALLS = ("fmi3SetTime", "fmi3SetContinuousStates", "fmi3SetFloat64", "fmi3GetFloat64",
              "fmi3GetContinuousStateDerivatives")
CYCLE = "fmi3InstantiateModelExchange/fmi3FreeInstance"

# every function one step of the path calls once (the scene that has it)
PER_STEP = [(call, "SimpleDAE") for call in (
    *BASE_CALLS, "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates",
    "fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative")] + [
    ("fmi3GetEventIndicators", "EventDAE")]
# (call, scene, a size the quick level must find): instantiate and free once per lap
EVERY_CALL = [(call, scene, KIB) for call, scene in PER_STEP] + [
    ("fmi3InstantiateModelExchange", "SimpleDAE", 64 * KIB),
    ("fmi3FreeInstance", "SimpleDAE", 64 * KIB),
]


def _check(scene: str, call: str, size: int, **options) -> FmuReport:
    fmu = build_scene(scene, defines=[f"DEFECT_LEAK_CALL={call}", f"DEFECT_LEAK_BYTES={size}"])
    return check_fmu(fmu, options=EngineOptions(**{"select": SELECT, **options}))


def _found(report: FmuReport) -> dict[str, list]:
    out: dict[str, list] = {}
    for f in report.findings:
        if f.severity >= Severity.WARNING or f.code == "DAE761":
            out.setdefault(f.code, []).append(f)
    return out


def _detail(report: FmuReport) -> str:
    return "\n".join(f"{f.code}: {f.message}" for f in report.findings) + "\n" + "\n".join(
        f"not run {c}: {why}" for c, why in report.rules_not_run)


@pytest.mark.parametrize("call, scene, size", EVERY_CALL, ids=[c for c, _, _ in EVERY_CALL])
def test_a_leak_in_every_call_an_importer_makes_is_memory_grows(call, scene, size):
    report = _check(scene, call, size)
    found = _found(report)
    assert set(found) == {"DAE761"}, _detail(report)
    (finding,) = found["DAE761"]
    ev = thaw(finding.evidence)
    # named: the function itself, or the instance cycle it belongs to
    assert finding.subject == (CYCLE if call in CYCLE else call), _detail(report)
    assert size <= ev["bytes_per_call"] <= size + 64 + (0 if size < KIB else size // 4)
    made = thaw(report.info)["endurance"]["calls"]
    assert call in BASE_CALLS or any(call in name for name in made)


#: leak sizes from 16 bytes to 1 MiB, and what the quick level must say of each in a function
#: called once per step: nothing below bytes_per_call_quick (with the allocator's 16 bytes),
#: the function and its bytes per call from it on, the function that grew when the run stops.
#: Every function at 16 bytes, 64 bytes and 1 MiB; the sizes between in two of them.
SIZES = {16: "nothing", 32: "nothing", 64: "named", 512: "named", MIB: "stopped"}
FAMILY = [(call, scene, size, SIZES[size]) for call, scene in PER_STEP for size in (16, 64, MIB)
          ] + [(call, "SimpleDAE", size, SIZES[size]) for call in ("fmi3GetFloat64", "fmi3SetTime")
               for size in (32, 512)]


@pytest.mark.parametrize("call, scene, size, said", FAMILY,
                         ids=[f"{c}-{size}" for c, _, size, _ in FAMILY])
def test_each_leak_size_in_each_function_is_judged_per_function(call, scene, size, said):
    report = _check(scene, call, size)
    found = _found(report)
    if said == "nothing":
        assert report.findings == (), _detail(report)
        return
    assert set(found) == {"DAE761"}, _detail(report)
    (finding,) = found["DAE761"]
    ev = thaw(finding.evidence)
    assert finding.subject == call and ev["function"] == call, _detail(report)
    if said == "named":
        assert ev["stopped"] == "budget"
        assert size + 8 <= ev["bytes_per_call"] <= size + 40, ev["fitted"]
        assert f"grows by {ev['bytes_per_call']:,} bytes per call of '{call}'" in finding.message
        others = {n: b for n, b in ev["fitted"].items() if n != call}
        assert max(abs(b) for b in others.values()) < OPTIONS["bytes_per_call_quick"], others
    else:
        assert ev["stopped"] == "memory"
        assert f"the address space grew inside {call} above all" in finding.message


@pytest.mark.parametrize("call", ["fmi3GetFloat64", "fmi3GetDirectionalDerivative"])
def test_a_leak_below_the_quick_bound_is_nobodys_finding(call):
    # 16 bytes (32 with the allocator's header) in one call of a step of about nine: about
    # 4 bytes per FMI call, below bytes_per_call of both levels; no other rule may say anything
    report = _check("SimpleDAE", call, 16)
    assert report.findings == (), _detail(report)
    assert {"DAE760", "DAE761"} <= set(report.rules_run)
    assert thaw(report.info)["endurance"]["stopped"] == "budget"


@pytest.mark.parametrize("call", ["fmi3GetFloat64", "fmi3GetDirectionalDerivative"])
def test_a_leak_that_stops_the_path_run_is_the_growth_up_to_the_stop(call):
    # 64 KiB per call: memory grows by max_growth_mib within a few thousand calls and the run
    # stops there; the growth measured up to the stop is the finding, never "too few samples"
    report = _check("SimpleDAE", call, 64 * KIB)
    found = _found(report)
    assert set(found) == {"DAE761"}, _detail(report)
    ev = thaw(found["DAE761"][0].evidence)
    assert ev["stopped"] == "memory"
    assert ev["growth_kib"] >= OPTIONS["min_growth_kib"]
    assert ev["growth_kib"] * KIB >= default_catalogue()["DAE760"].option_values[
        "max_growth_mib"] * MIB
    # about 64 KiB in one call of a step of about nine
    assert 3 * KIB < ev["bytes_per_call"] < 20 * KIB
    assert not {"DAE760", "DAE761"} & {c for c, _ in report.rules_not_run}


@pytest.mark.parametrize("call", ["fmi3GetFloat64", "fmi3GetDirectionalDerivative"])
def test_a_leak_of_megabytes_per_call_is_the_binarys_memory(call):
    # 4 MiB per call exhausts the 2 GiB address space within the point probes (all of them
    # run here): binary-memory-limit naming the call that took the memory, whoever's
    # allocation found it gone; never an internal error or lsdae's own limit
    report = check_fmu(build_scene("SimpleDAE", defines=[
        f"DEFECT_LEAK_CALL={call}", f"DEFECT_LEAK_BYTES={4 * MIB}"]),
        options=EngineOptions(probes=True))
    found = _found(report)
    assert found and set(found) <= {"DAE703", "DAE761"}, _detail(report)
    for finding in found.get("DAE703", []):
        assert finding.subject == call
    assert not any("lsdae's own" in why for _, why in report.rules_not_run), _detail(report)
