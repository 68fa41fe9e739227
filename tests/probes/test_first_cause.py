"""A refused call ends the story there: the first failing call is the finding, of the rule that
owns it, and what fails on the instance afterwards (SM-04: it is in Terminated) is nobody's.

Real :class:`~conformance.runtime.instance.Instance` objects over a fake library whose FMU keeps
the FMI 3.0 state machine: a call that returns fmi3Error puts the instance in Terminated, where
every later set fails ("not allowed in Terminated"), as DEFECT_INPUT_NOT_SETTABLE does in the
C framework (its defect variant is in tests/fixtures/defects/basic.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pytest

from conformance.report.catalogue import default_catalogue
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description
from conformance.probes.evaluation import basic, failures
from conformance.probes.instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from conformance.probes.instruments.common import renew_failed
from conformance.runtime.instance import Instance, KnownNotSet, PointNotSet
from conformance.runtime.layout import Layout
from tests.fakelibrary import FakeLibrary, simple_dae_xml

OPTIONS = {r.code: r.option_values for r in default_catalogue()}
U1, U2, Z1, Z2 = 7, 8, 5, 6   # SimpleDAE's inputs and algebraic variables


@dataclass
class _Component:
    mode: str
    terminated: bool = False
    t: float = 0.0
    values: dict[int, float] = field(default_factory=dict)

    def computed(self) -> float:
        """Every unknown (derivatives, residuals, outputs): the sum of the knowns set."""
        return self.t + sum(self.values.values())


@dataclass
class FakeFmu:
    """The FMI functions the probes call, as fmpy's recording class exposes them: each raises
    FmiError for a status above fmi3Warning. ``refuse(mode, call, component, args)`` says
    whether a call is refused (fmi3Error, and the instance goes to Terminated)."""

    refuse: Callable[[str, str, _Component, tuple], bool]
    components: list[_Component] = field(default_factory=list)
    log: list[str] = field(default_factory=list)

    def fmi3InstantiateModelExchange(self, name: bytes, *args: Any) -> int:
        self.components.append(_Component("dae" if b"-dae-" in name else "ode"))
        return len(self.components)

    def __getattr__(self, fname: str) -> Callable[..., int]:
        if not fname.startswith("fmi3"):
            raise AttributeError(fname)

        def call(handle: int, *args: Any) -> int:
            c = self.components[handle - 1]
            if fname in ("fmi3FreeInstance", "fmi3Terminate", "fmi3Reset"):
                c.terminated = c.terminated and fname == "fmi3Terminate"
                return 0
            if fname.startswith("fmi3Set") and c.terminated:
                raise FmiError(fname, "fmi3Error", [f"[Error] {fname}: not allowed in "
                                                    "Terminated"])
            if self.refuse(c.mode, fname, c, args):
                c.terminated = True
                raise FmiError(fname, "fmi3Error", [f"[Error] {fname}: refused"])
            if fname == "fmi3SetTime":
                c.t = float(args[0])
            elif fname == "fmi3SetFloat64":
                c.values.update(zip(_vrs(args), (float(args[2][k]) for k in range(args[1]))))
            elif fname == "fmi3GetFloat64":
                for k, vr in enumerate(_vrs(args)):
                    args[2][k] = c.values.get(vr, c.computed())
            elif fname == "fmi3GetContinuousStateDerivatives":
                for k in range(int(args[1])):
                    args[0][k] = c.computed()
            return 0
        return call


def _vrs(args: tuple) -> list[int]:
    return [int(args[0][k]) for k in range(int(args[1]))]


def make_ctx(refuse: Callable[[str, str, _Component, tuple], bool]) -> ProbeContext:
    model = read_model_description(simple_dae_xml("modelDescription.xml"))
    manifest = read_manifest(simple_dae_xml("fmi-ls-manifest.xml"), draft="alpha1")
    library = FakeLibrary(Layout.build(model, manifest), FakeFmu(refuse))

    def new_instance(mode: str) -> Instance:
        inst = Instance(library, name=library.next_name(mode))  # type: ignore[arg-type]
        inst.mode = mode
        return inst

    start = Point(0.0, {1: 0.5, 3: 0.5, Z1: 0.1, Z2: 0.2, U1: 0.0, U2: 0.0}, "start")
    points = [start] + [Point(0.1 * k, {**start.values, 1: 0.5 + 0.01 * k}, f"near-{k}")
                        for k in (1, 2, 3)]
    return ProbeContext(model=model, manifest=manifest, draft="alpha1", seed=0,
                        rng=np.random.default_rng(0), points=points,
                        dae=new_instance("dae"), ode=new_instance("ode"),
                        new_instance=new_instance,
                        facts={"layout": library.layout, "library": library})


def run_basic(ctx: ProbeContext) -> tuple[dict[str, list], dict[str, str]]:
    """The basic probes in catalogue order, an instance another probe terminated renewed
    before each, as the probe stage does."""
    found: dict[str, list] = {}
    skipped: dict[str, str] = {}
    for code in ("DAE720", "DAE722", "DAE723", "DAE724", "DAE725"):
        renew_failed(ctx)
        violations: list = []
        try:
            for v in {**basic.PROBES, **failures.PROBES}[code](ctx, **OPTIONS[code]):
                violations.append(v)
        except ProbeSkipped as exc:
            skipped[code] = str(exc)
        except FmiError as exc:
            skipped[code] = exc.cause()
        if violations:
            found[code] = violations
    return found, skipped


def _inputs_in_dae(mode: str, fname: str, c: _Component, args: tuple) -> bool:
    return mode == "dae" and fname == "fmi3SetFloat64" and bool({U1, U2} & set(_vrs(args)))


# ------------------------------------------------------------------------------- the probes

def test_a_refused_input_is_input_not_settable_and_nothing_else():
    ctx = make_ctx(_inputs_in_dae)
    found, skipped = run_basic(ctx)
    assert set(found) == {"DAE725"}
    assert [v.subject for v in found["DAE725"]] == ["u1", "u2"]   # each on a fresh instance
    ev = dict(found["DAE725"][0].evidence)
    assert (ev["call"], ev["status"], ev["value_reference"], ev["mode"]) == (
        "fmi3SetFloat64", "fmi3Error", U1, "DAE mode")
    assert ev["log"] and ev["state"] == "Continuous-Time Mode"
    # the probes that cannot set their points say why, naming the inputs, never fmi3SetTime
    assert {"DAE720", "DAE722", "DAE724"} <= set(skipped)
    assert all("inputs" in skipped[c] and "fmi3SetTime" not in skipped[c]
               for c in ("DAE720", "DAE724"))


def test_an_input_refused_in_ode_mode_names_ode_mode():
    ctx = make_ctx(lambda mode, fname, c, args: mode == "ode" and fname == "fmi3SetFloat64"
                   and U2 in _vrs(args))
    (v,) = list(failures.input_not_settable(ctx))
    assert v.subject == "u2" and dict(v.evidence)["mode"] == "ODE mode"


def test_settable_inputs_are_clean():
    found, skipped = run_basic(make_ctx(lambda *a: False))
    assert found == {} and skipped == {}


def test_a_refused_time_is_evaluation_failed_once_per_point():
    # fmi3SetTime refused once time has advanced: each point on a fresh instance, so each
    # failure is the first call that failed on its instance, and fmi3SetFloat64 (inputs)
    # afterwards is never blamed
    ctx = make_ctx(lambda mode, fname, c, args: fname == "fmi3SetTime" and args[0] > 0)
    found, _ = run_basic(ctx)
    assert set(found) == {"DAE724"}
    assert [dict(v.evidence)["point"] for v in found["DAE724"]] == ["near-1", "near-2", "near-3"]
    assert {v.subject for v in found["DAE724"]} == {"fmi3SetTime"}
    assert {dict(v.evidence)["setting"] for v in found["DAE724"]} == {"time"}


def test_evaluation_failed_never_blames_a_call_on_a_terminated_instance():
    ctx = make_ctx(lambda mode, fname, c, args: fname == "fmi3SetContinuousStates")
    with pytest.raises(KnownNotSet):
        ctx.dae.set_point(ctx.points[0])     # refused: Terminated since
    # handed the terminated instance, the probe takes a fresh one for every point after a
    # failure: the states' refusal at each point, never fmi3SetTime failing in Terminated
    found = list(failures.evaluation_failed(ctx))
    assert [v.subject for v in found] == ["fmi3SetContinuousStates"] * 4
    assert {dict(v.evidence)["setting"] for v in found} == {"states"}


def test_each_refused_algebraic_variable_is_tried_on_a_fresh_instance():
    ctx = make_ctx(lambda mode, fname, c, args: mode == "dae" and fname == "fmi3SetFloat64"
                   and set(_vrs(args)) & {Z1, Z2} and not set(_vrs(args)) & {U1, U2})
    found = list(basic.algebraic_not_settable(ctx, **OPTIONS["DAE720"]))
    assert [v.subject for v in found] == ["z1", "z2"]
    assert all(dict(v.evidence)["status"] == "fmi3Error" for v in found)


# ------------------------------------------------------------------------------ the runtime

@pytest.mark.parametrize("call, kind", [
    ("fmi3SetTime", "time"), ("fmi3SetContinuousStates", "states")])
def test_a_refused_set_says_which_kind_of_known(call, kind):
    ctx = make_ctx(lambda mode, fname, c, args: fname == call)
    with pytest.raises(KnownNotSet) as info:
        ctx.dae.set_point(ctx.points[0])
    assert (info.value.kind, info.value.call, info.value.mode) == (kind, call, "dae")
    assert ctx.dae.failure is info.value


def test_algebraic_variables_and_inputs_are_told_apart_when_set_alone():
    ctx = make_ctx(lambda mode, fname, c, args: fname == "fmi3SetFloat64")
    inst = ctx.dae
    with pytest.raises(KnownNotSet) as info:
        inst.set_point(ctx.points[0], algebraic=False)
    assert info.value.kind == "inputs" and info.value.names == ("u1", "u2")
    inst.reset()
    assert inst.failure is None                       # fmi3Reset: Instantiated again
    with pytest.raises(KnownNotSet) as info:
        ctx.new_instance("dae").set_algebraic(ctx.points[0])
    assert info.value.kind == "algebraic variables" and info.value.vrs == (Z1, Z2)
    with pytest.raises(KnownNotSet) as info:          # both in one fmi3SetFloat64
        ctx.new_instance("dae").set_point(ctx.points[0])
    assert info.value.kind == "algebraic variables and inputs"


def test_a_later_failure_carries_the_first_and_the_point_not_set_names_it():
    ctx = make_ctx(_inputs_in_dae)
    inst = ctx.dae
    with pytest.raises(PointNotSet) as first:
        inst.evaluate(ctx.points[0], [11])
    assert first.value.error.kind == "algebraic variables and inputs"
    with pytest.raises(PointNotSet) as later:
        inst.evaluate(ctx.points[1], [11])
    error = later.value.error
    assert error.call == "fmi3SetTime" and error.after is inst.failure
    assert "fmi3SetFloat64" in str(later.value) and "Terminated" in str(later.value)


def test_discard_does_not_terminate():
    ctx = make_ctx(lambda *a: False)
    inst = ctx.dae

    def discard(handle: int, *args: Any) -> int:
        raise FmiError("fmi3GetFloat64", "fmi3Discard", [])

    ctx.facts["library"].fmu.fmi3GetFloat64 = discard
    with pytest.raises(FmiError):
        inst.get_float64([11])
    assert inst.failure is None
