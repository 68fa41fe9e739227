"""The importer-path probes (DAE730-DAE733) against fake instances, one fault at a time.

The real FMUs are covered by tests/probes/test_defects.py (one C switch per rule) and
tests/probes/test_clean_scenes.py; here each branch of the probes is driven on purpose,
including the ones no C switch reaches: a state that reads back but is not used, an indicator
vector that disagrees with fmi3GetFloat64, a failing or non-finite fmi3GetEventIndicators.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import pytest
from lxml import etree

from conformance.report.catalogue import default_catalogue
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description
from conformance.probes.events import indicators as event_indicators
from conformance.probes.readback import importer_paths
from conformance.probes.instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from conformance.runtime.layout import Layout
from tests.fixtures import SCENES_DIR

OPTIONS = {r.code: r.option_values for r in default_catalogue()}
FAMILY = {**importer_paths.PROBES, **event_indicators.PROBES}


@pytest.fixture(autouse=True)
def _count_on_a_fake(monkeypatch):
    """fmi3GetNumberOfEventIndicators is asked on a fresh instance in Instantiated, made from
    the loaded library: here a fake instance stands in for it."""
    monkeypatch.setattr(event_indicators, "_instantiated", lambda ctx: ctx.new_instance("dae"))


class Fake:
    """An instance of a linear model in DAE mode: every unknown is a weighted sum of the
    states, algebraic variables and inputs the equations see; indicators likewise."""

    def __init__(self, layout: Layout, fault: str = ""):
        self.layout, self.fault = layout, fault
        self.mode = "dae"
        self.values: dict[int, float] = dict(layout.start)
        self.used: dict[int, float] = dict(self.values)   # what the equations see
        self.previous: dict[int, float] = dict(self.values)
        self.t = 0.0

    # the calls the probes make
    def set_time(self, t: float) -> None:
        self.t = t

    def set_point(self, point: Point, *, algebraic: bool = True) -> None:
        self.previous = dict(self.used)
        self.t = point.t
        for vr, v in point.values.items():
            self.values[vr] = self.used[vr] = v

    def set_float64(self, vrs: Sequence[int], values: Sequence[float]) -> None:
        for vr, v in zip(vrs, values):
            if vr in self.layout.states and self.fault == "refuse":
                raise FmiError("fmi3SetFloat64", "fmi3Error", ["states: fmi3SetContinuousStates"])
            self.values[vr] = v
            if not (vr in self.layout.states and self.fault == "shadow"):
                self.used[vr] = v

    def _unknown(self, vr: int, seen: dict[int, float]) -> float:
        return sum((k % 7 + 1) * v for k, v in seen.items()) + vr + self.t

    def get_float64(self, vrs: Sequence[int]) -> np.ndarray:
        out = []
        for vr in vrs:
            if vr in self.values and vr not in self.layout.event_indicators:
                out.append(self.values[vr])
            elif vr in self.layout.event_indicators:
                out.append(self._indicator(vr) + (1.0 if self.fault == "vector-differs" else 0))
            else:
                out.append(self._unknown(vr, self.used))
        return np.array(out, dtype=float)

    def get_derivatives(self, n: int | None = None) -> np.ndarray:
        return self.get_float64(list(self.layout.derivatives))

    def get_states(self, n: int) -> np.ndarray:
        return np.array([self.values[vr] for vr in self.layout.states])

    def _indicator(self, vr: int) -> float:
        seen = self.previous if self.fault == "stale" else self.used
        return self._unknown(vr, seen)

    def number_of_event_indicators(self) -> int:
        return len(self.layout.event_indicators) + (1 if self.fault == "count" else 0)

    def get_event_indicators(self, n: int) -> np.ndarray:
        if self.fault == "indicators-fail":
            raise FmiError("fmi3GetEventIndicators", "fmi3Error", ["not in this mode"])
        z = np.array([self._indicator(vr) for vr in self.layout.event_indicators])
        if self.fault == "indicators-nan":
            z[:] = np.nan
        return z

    def free(self) -> None:
        pass


def make_ctx(scene: str, fault: str = "", *, seed: int = 0) -> ProbeContext:
    model = read_model_description(etree.parse(str(SCENES_DIR / scene / "modelDescription.xml")))
    manifest = read_manifest(etree.parse(str(SCENES_DIR / scene / "fmi-ls-manifest.xml")),
                             draft="alpha1")
    layout = Layout.build(model, manifest)
    rng = np.random.default_rng(seed)
    start = {vr: layout.start.get(vr, 0.0) for vr in (*layout.states, *layout.algebraic,
                                                      *layout.inputs)}
    points = [Point(0.0, start, "start")]
    for k in range(3):
        points.append(Point(0.01 * (k + 1), {vr: v + 0.1 * rng.standard_normal()
                                             for vr, v in start.items()}, f"near-{k + 1}"))
    return ProbeContext(model=model, manifest=manifest, draft="alpha1", seed=seed, rng=rng,
                        points=points, dae=Fake(layout, fault), ode=None,  # type: ignore[arg-type]
                        new_instance=lambda mode: Fake(layout, fault),  # type: ignore[arg-type]
                        facts={"layout": layout})


def found(ctx: ProbeContext) -> dict[str, list]:
    out = {}
    for code, probe in FAMILY.items():
        try:
            violations = list(probe(ctx, **OPTIONS[code]))
        except (ProbeSkipped, FmiError):  # the stage reports both as the reason it did not run
            continue
        if violations:
            out[code] = violations
    return out


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("scene", ["SimpleDAE", "EventDAE", "Robertson"])
def test_a_clean_fake_triggers_nothing(scene, seed):
    assert found(make_ctx(scene, seed=seed)) == {}


@pytest.mark.parametrize("fault, code", [
    ("shadow", "DAE730"),            # reads back, but the equations keep the old states
    ("refuse", "DAE731"),
    ("count", "DAE732"),
    ("indicators-fail", "DAE732"),
    ("indicators-nan", "DAE732"),
    ("stale", "DAE733"),
    ("vector-differs", "DAE733"),
])
def test_each_fault_triggers_exactly_its_rule(fault, code):
    result = found(make_ctx("EventDAE", fault))
    assert set(result) == {code}, result
    assert len(result[code]) == 1


@pytest.mark.parametrize("fault, code, part", [
    ("count", "DAE732", None),
    ("indicators-fail", "DAE732", None),
    ("indicators-nan", "DAE732", "not-finite"),
    ("stale", "DAE733", None),
    ("vector-differs", "DAE733", "vector-vs-variables"),
])
def test_each_fault_is_tagged_with_its_part(fault, code, part):
    (violation,) = found(make_ctx("EventDAE", fault))[code]
    assert violation.part == part


def test_a_state_that_reads_back_but_is_unused_names_the_values_that_differ():
    (violation,) = found(make_ctx("SimpleDAE", "shadow"))["DAE730"]
    differences = dict(violation.evidence)["differences"]
    assert differences, violation
    assert violation.subject is not None


def test_the_two_state_rules_share_one_measurement():
    ctx = make_ctx("SimpleDAE", "refuse")
    created = []
    make = ctx.new_instance
    ctx.new_instance = lambda mode: created.append(mode) or make(mode)  # type: ignore[misc]
    list(importer_paths.state_not_settable_by_value(ctx))
    list(importer_paths.state_set_ignored(ctx, **OPTIONS["DAE730"]))
    assert created == ["dae", "dae"]


def test_no_indicators_and_a_matching_count_of_zero_is_clean():
    ctx = make_ctx("SimpleDAE")
    assert list(event_indicators.event_indicators_failed(ctx)) == []
    assert list(event_indicators.event_indicators_inconsistent(ctx, **OPTIONS["DAE733"])) == []


def test_inconsistency_is_not_judged_when_the_count_is_wrong():
    with pytest.raises(ProbeSkipped):
        list(event_indicators.event_indicators_inconsistent(make_ctx("EventDAE", "count"),
                                                            **OPTIONS["DAE733"]))
