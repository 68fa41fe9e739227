"""lsdae's own limits are never the binary's fault (issue 22, point 3).

A time or memory limit reached while no FMI call is in progress is lsdae's own computation:
the probe is listed as not run with the limit and the reason, never as a ``binary-*`` finding,
and the worker that had to be replaced says so. The same limit reached inside an FMI call stays
the binary's finding. The worker here is a stand-in (tests/probes/fake_worker.py) that reaches
the limit on purpose, so the verdicts do not depend on how fast anything is; the last tests
reach our own memory limit with the real probes, through a rule option.
"""
from __future__ import annotations

import dataclasses

import pytest

from conformance.report.catalogue import Catalogue, default_catalogue
from conformance.run.engine import EngineOptions, check_fmu
from conformance.probes.machinery import driver
from tests.probes.fake_worker import BEHAVIOUR
from tests.fixtures import build_scene, chain

CATALOGUE = default_catalogue()
BINARY = {"binary-crashed", "binary-timed-out", "binary-memory-limit"}
PROBES = ("DAE720", "DAE721", "DAE722")
SELECT = ("DAE701", "DAE702", "DAE703", *PROBES)


def _catalogue(options: dict[str, dict]) -> Catalogue:
    """The default catalogue with the options of some rules (by code) changed."""
    rules = []
    for rule in CATALOGUE:
        if rule.code in options:
            unknown = set(options[rule.code]) - set(rule.option_values)
            assert not unknown, f"{rule.code} has no options {sorted(unknown)}"
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, **options[rule.code]}.items())))
        rules.append(rule)
    return Catalogue(rules)


@pytest.fixture
def fake(monkeypatch):
    """Run the stand-in worker, doing ``behaviour`` in the first probe."""
    monkeypatch.setattr(driver, "ENTRY", "tests.probes.fake_worker:run_job")

    def use(behaviour: str) -> None:
        monkeypatch.setenv(BEHAVIOUR, f"{behaviour}:{PROBES[0]}")
    return use


def _check(catalogue: Catalogue):
    return check_fmu(build_scene("HelloWorldDAE"), catalogue=catalogue,
                     options=EngineOptions(probes=True, select=SELECT))


@pytest.mark.parametrize("behaviour, limits", [
    ("sleep-outside", {"DAE702": {"probe_seconds": 1.0}}),
    ("memory-outside", {"DAE703": {"address_space_mib": 512}}),
    # the time goes into calls, but each returns: our budget ran out, nothing hung
    ("short-calls", {"DAE702": {"probe_seconds": 3.0}}),
])
def test_a_limit_reached_outside_any_fmi_call_is_not_run_and_never_the_binarys(
        fake, behaviour, limits):
    fake(behaviour)
    report = _check(_catalogue(limits))
    assert not {f.name for f in report.findings} & BINARY
    not_run = dict(report.rules_not_run)
    first = PROBES[0]
    assert first in not_run and "lsdae's own" in not_run[first]
    limit = "memory limit" if behaviour.startswith("memory") else "time limit"
    assert not_run[first].startswith(limit)
    assert ("no FMI call was in progress" in not_run[first]) != (behaviour == "short-calls")
    # the stopped worker was replaced: the probes after it ran, and the reason says so
    assert "a new one runs the probes after it" in not_run[first]
    assert set(PROBES[1:]) <= set(report.rules_run) and not set(PROBES[1:]) & set(not_run)


@pytest.mark.parametrize("behaviour, limits, name", [
    ("sleep-inside", {"DAE702": {"probe_seconds": 1.0}}, "binary-timed-out"),
    ("memory-inside", {"DAE703": {"address_space_mib": 512}}, "binary-memory-limit"),
])
def test_the_same_limit_inside_an_fmi_call_is_the_binarys(fake, behaviour, limits, name):
    fake(behaviour)
    report = _check(_catalogue(limits))
    found = [f for f in report.findings if f.name == name]
    assert len(found) == 1
    evidence = found[0].evidence_dict()
    assert evidence["call"] == "fmi3DoStep" and evidence["call_in_progress"] is True
    assert PROBES[0] not in dict(report.rules_not_run)


def test_a_per_fmu_limit_outside_any_fmi_call_is_ours_too(fake):
    fake("sleep-outside")
    report = _check(_catalogue({"DAE702": {"probe_seconds": 30.0, "fmu_seconds": 1.0}}))
    assert not {f.name for f in report.findings} & BINARY
    not_run = dict(report.rules_not_run)
    assert set(PROBES) <= set(not_run)
    assert all("per FMU" in not_run[c] and "lsdae's own" in not_run[c] for c in PROBES)


@pytest.mark.parametrize("code", ["DAE745", "DAE746"])
def test_dense_work_past_our_memory_limit_is_not_run_on_a_correct_fmu(code):
    # dg/dw forced dense (dense_up_to above N) at N = 8000: two 8000 x 8000 arrays (1 GiB) do
    # not fit in the address space given to the worker. Only our numerics run out, outside any
    # FMI call, at once (an allocation, not a computation that a slow machine would time out).
    fmu = chain.build_chain(8000)
    catalogue = _catalogue({code: {"dense_up_to": 100_000},
                            "DAE703": {"address_space_mib": 900}})
    report = check_fmu(fmu, catalogue=catalogue,
                       options=EngineOptions(probes=True, select=("DAE70", "DAE740", code)))
    assert not {f.name for f in report.findings} & BINARY
    reason = dict(report.rules_not_run).get(code, "")
    assert reason.startswith("memory limit") and "lsdae's own computation" in reason
    # with the defaults the same FMU is judged, and is clean
    clean = check_fmu(fmu, options=EngineOptions(probes=True,
                                                 select=("DAE70", "DAE740", code)))
    assert code in clean.rules_run and not clean.findings and not clean.rules_not_run
