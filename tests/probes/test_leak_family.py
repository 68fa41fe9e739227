"""Leaks, a family (issue 20, point 3): a leak in any FMI call an importer makes, of any size.

``-D DEFECT_LEAK_CALL=<function> -D DEFECT_LEAK_BYTES=<n>`` (scenes/common/fmi3_framework.c)
keeps n bytes, written, on every call of that function. The endurance path run makes every call
an importer makes (conformance/probes/endurance/calls.py), so a leak anywhere is
``memory-grows`` (DAE761, information): by its slope, or, when the run had to stop because
memory grew by ``max_growth_mib``, by the growth up to the stop; a leak so large that the
address space runs out before the path run is ``binary-memory-limit`` (DAE703), naming the call
that took the memory. The quick level judges a slope of ``bytes_per_call_quick`` bytes per FMI
call: a leak of L bytes (plus the allocator's 16) in a call made once in a step of about nine
calls is found from about 600 bytes on, in one made once per lap of the path (an instance
instantiated and freed) from about 40 KiB on. Below that it is nobody's finding, and nothing
else may be said about it either.
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

# (call, scene, a size the quick level must find): one step of the path makes each of the
# per-step calls once; instantiate and free are made once per lap
EVERY_CALL = [
    ("fmi3GetFloat64", "SimpleDAE", KIB),
    ("fmi3SetFloat64", "SimpleDAE", KIB),
    ("fmi3SetTime", "SimpleDAE", KIB),
    ("fmi3SetContinuousStates", "SimpleDAE", KIB),
    ("fmi3GetContinuousStateDerivatives", "SimpleDAE", KIB),
    ("fmi3GetContinuousStates", "SimpleDAE", KIB),
    ("fmi3GetNominalsOfContinuousStates", "SimpleDAE", KIB),
    ("fmi3GetDirectionalDerivative", "SimpleDAE", KIB),
    ("fmi3GetAdjointDerivative", "SimpleDAE", KIB),
    ("fmi3GetEventIndicators", "EventDAE", KIB),
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
    ev = thaw(found["DAE761"][0].evidence)
    assert ev["bytes_per_call"] >= OPTIONS["bytes_per_call_quick"]
    assert ev["growth_kib"] >= OPTIONS["min_growth_kib"]
    # the call is one the path run makes: in every step's base, or one of its optional calls
    # (instantiate and free: the instance cycle of each lap)
    made = thaw(report.info)["endurance"]["calls"]
    assert call in BASE_CALLS or any(call in name for name in made)


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
