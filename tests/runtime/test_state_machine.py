"""lsdae calls the FMU only where the FMI 3.0.2 state machine allows it, also on the paths where
something went wrong: an instance an fmi3Error put in Terminated is freed without fmi3Terminate
(§2.3.8), one left in Configuration or Reconfiguration Mode leaves it first (§2.3.6, §2.3.7),
an event iteration that does not settle never ends in fmi3EnterContinuousTimeMode (§2.3.5), and
a switch that is no fixed or tunable structural parameter is never set (§2.3.6).

Real :class:`~conformance.runtime.instance.Instance` objects over a fake binary that keeps the
state machine (:class:`StrictFmu`): it records each call the current state does not allow, as
the tests' verdict, and answers what the test scripts (a refused or discarded call, an event
iteration that keeps asking for another update).
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pytest

from conformance.checks.context import CheckContext
from conformance.checks.enable import enable_parameter_not_structural, \
    enable_parameter_variability
from conformance.model.description import read_model_description
from conformance.model.manifest import read_manifest
from conformance.probes.evaluation import handshake
from conformance.probes.evaluation.readable import sweep
from conformance.probes.instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from conformance.probes.readback import rare_calls
from conformance.runtime.arrays import vr_array
from conformance.runtime.instance import Instance
from conformance.runtime.layout import Layout
from conformance.runtime.modes import reconfigure, start_instance
from conformance.runtime.records import GETTERS
from tests.fakelibrary import FakeLibrary, simple_dae_xml

X1 = 1   # SimpleDAE's state x1, a Float64

INST, CONF, INIT, EM, RECONF, CT, TERM = (
    "Instantiated", "Configuration Mode", "Initialization Mode", "Event Mode",
    "Reconfiguration Mode", "Continuous-Time Mode", "Terminated")

#: The calls that change the state, by state (FMI 3.0.2 §2.3.2-§2.3.8, §3.2.1); None: stays.
TRANSITIONS: dict[str, dict[str, str | None]] = {
    INST: {"fmi3EnterConfigurationMode": CONF, "fmi3EnterInitializationMode": INIT},
    CONF: {"fmi3ExitConfigurationMode": INST},
    INIT: {"fmi3ExitInitializationMode": EM},
    EM: {"fmi3UpdateDiscreteStates": None, "fmi3EnterContinuousTimeMode": CT,
         "fmi3EnterConfigurationMode": RECONF, "fmi3Terminate": TERM},
    RECONF: {"fmi3ExitConfigurationMode": EM},
    CT: {"fmi3EnterEventMode": EM, "fmi3CompletedIntegratorStep": None, "fmi3Terminate": TERM},
    TERM: {},
}
CT_SETTERS = ("fmi3SetTime", "fmi3SetContinuousStates")


def allowed(state: str, fname: str) -> bool:
    """Whether FMI 3.0.2 lists ``fname`` in ``state`` (the state tables; not the arguments)."""
    if state in (CONF, RECONF):   # §2.3.6, §2.3.7: fmi3Set* and the exit, nothing else
        return fname == "fmi3ExitConfigurationMode" or (
            fname.startswith("fmi3Set") and fname not in CT_SETTERS)
    if fname in ("fmi3FreeInstance", "fmi3Reset") or fname.startswith("fmi3Get"):
        return True   # §2.3.1 (FMU State Settable) and every state's getters
    if state == TERM:
        return False  # §2.3.8: getters, fmi3Reset and fmi3FreeInstance only
    if fname.startswith("fmi3Set"):
        return state in (INST, INIT, CT) or fname not in CT_SETTERS
    return fname in TRANSITIONS[state]


VARIABLE_GETTERS = {fname for fname, _ in GETTERS.values()}


@dataclass
class _Component:
    state: str = INST
    needs_update: bool = False   # what the last fmi3UpdateDiscreteStates said
    updates: int = 0
    booleans: dict[int, bool] = field(default_factory=dict)


@dataclass
class StrictFmu:
    """The FMI functions as fmpy's recording class exposes them (FmiError for a status above
    fmi3Warning). ``status(component, fname, args)`` gives a call's status ("fmi3OK",
    "fmi3Discard", "fmi3Error"); ``unsettled`` is how many fmi3UpdateDiscreteStates calls in a
    row say discreteStatesNeedUpdate. ``illegal`` lists (state, call) of every call made where
    the state does not allow it."""

    status: Callable[[_Component, str, tuple], str] = lambda c, fname, args: "fmi3OK"
    unsettled: int = 0
    components: list[_Component] = field(default_factory=list)
    calls: list[tuple[str, str]] = field(default_factory=list)
    illegal: list[tuple[str, str]] = field(default_factory=list)

    def fmi3InstantiateModelExchange(self, name: bytes, *args: Any) -> int:
        self.components.append(_Component())
        return len(self.components)

    def __getattr__(self, fname: str) -> Callable[..., None]:
        if not fname.startswith("fmi3"):
            raise AttributeError(fname)

        def call(handle: int, *args: Any) -> None:
            c = self.components[handle - 1]
            self.calls.append((c.state, fname))
            if not allowed(c.state, fname) or (
                    fname == "fmi3EnterContinuousTimeMode" and c.needs_update):  # §2.3.5
                self.illegal.append((c.state, fname))   # recorded; the fake goes along
            status = self.status(c, fname, args)
            if status == "fmi3Error":
                c.state = TERM   # §2.3.1: fmi3Error puts the instance in Terminated
                raise FmiError(fname, "fmi3Error", [f"[Error] {fname} refused"])
            if status == "fmi3Discard":   # §2.2.4: the state is the same as before the call
                raise FmiError(fname, "fmi3Discard", [f"[Warning] {fname} discarded"])
            _answer(c, fname, args)
            if fname == "fmi3Reset":
                c.state = INST
            elif fname == "fmi3FreeInstance":
                c.state = "freed"
            elif fname == "fmi3UpdateDiscreteStates":
                c.updates += 1
                c.needs_update = c.updates <= self.unsettled
                args[0]._obj.value = c.needs_update
            elif TRANSITIONS.get(c.state, {}).get(fname) is not None:
                c.state = TRANSITIONS[c.state][fname]  # type: ignore[assignment]
        return call


def _answer(c: _Component, fname: str, args: tuple) -> None:
    """Keep the Booleans set; every variable read writes its buffer (0, or the Boolean)."""
    if fname == "fmi3SetBoolean":
        c.booleans.update((int(args[0][k]), bool(args[2][k])) for k in range(args[1]))
    elif fname in VARIABLE_GETTERS:
        for k in range(int(args[3])):
            args[2][k] = (c.booleans.get(int(args[0][k]), False) if fname == "fmi3GetBoolean"
                          else None if fname == "fmi3GetString" else 0)


def make_ctx(fmu: StrictFmu, md_edits: tuple[tuple[str, str], ...] = ()) -> ProbeContext:
    model = read_model_description(simple_dae_xml("modelDescription.xml", md_edits))
    manifest = read_manifest(simple_dae_xml("fmi-ls-manifest.xml"), draft="alpha1")
    library = FakeLibrary(Layout.build(model, manifest), fmu)
    start = Point(0.0, {1: 0.5, 3: 0.5, 5: 0.1, 6: 0.2, 7: 0.0, 8: 0.0}, "start")
    return ProbeContext(model=model, manifest=manifest, draft="alpha1", seed=0,
                        rng=np.random.default_rng(0), points=[start], dae=None, ode=None,
                        new_instance=lambda mode: start_instance(library, mode),  # type: ignore
                        facts={"layout": library.layout, "library": library})


def _library(ctx: ProbeContext) -> FakeLibrary:
    return ctx.facts["library"]  # type: ignore[return-value]


# ------------------------------------------------------------------ F1: no fmi3Terminate after

def test_an_instance_an_error_terminated_is_freed_without_fmi3Terminate():
    fmu = StrictFmu(status=lambda c, fname, args: "fmi3Error" if fname == "fmi3SetTime"
                    else "fmi3OK")
    ctx = make_ctx(fmu)
    inst = start_instance(_library(ctx), "dae")  # type: ignore[arg-type]
    with pytest.raises(FmiError):
        inst.set_time(0.5)
    assert inst.failure is not None and fmu.components[0].state == TERM
    before = len(fmu.calls)
    inst.free()
    assert fmu.calls[before:] == [(TERM, "fmi3FreeInstance")]
    assert fmu.illegal == []


def test_a_healthy_instance_is_terminated_then_freed():
    fmu = StrictFmu()
    inst = start_instance(_library(make_ctx(fmu)), "ode")  # type: ignore[arg-type]
    before = len(fmu.calls)
    inst.free()
    assert fmu.calls[before:] == [(CT, "fmi3Terminate"), (TERM, "fmi3FreeInstance")]
    assert fmu.illegal == []


# ------------------------------------------------------- F7: leave (Re)Configuration Mode first

@pytest.mark.parametrize("answer", ["fmi3OK", "fmi3Discard"])
def test_an_instance_left_in_configuration_mode_exits_it_before_it_is_freed(answer):
    # rare_calls' illegal fmi3SetBoolean on a Float64 state, accepted or discarded
    fmu = StrictFmu(status=lambda c, fname, args: answer if fname == "fmi3SetBoolean"
                    else "fmi3OK")
    inst = Instance(_library(make_ctx(fmu)), name="fake-ode-1")  # type: ignore[arg-type]
    inst.enter_configuration_mode()
    try:
        inst.call("fmi3SetBoolean", vr_array([X1]), 1, (ctypes.c_bool * 1)(True), 1)
    except FmiError:
        pass
    inst.free()
    assert [f for _, f in fmu.calls[-2:]] == ["fmi3ExitConfigurationMode", "fmi3FreeInstance"]
    assert fmu.illegal == []


def test_an_instance_refused_in_configuration_mode_is_only_freed():
    fmu = StrictFmu(status=lambda c, fname, args: "fmi3Error" if fname == "fmi3SetBoolean"
                    else "fmi3OK")
    inst = Instance(_library(make_ctx(fmu)), name="fake-ode-1")  # type: ignore[arg-type]
    inst.enter_configuration_mode()
    with pytest.raises(FmiError):
        inst.set_boolean(X1, True)
    inst.free()
    assert fmu.calls[-1] == (TERM, "fmi3FreeInstance") and fmu.illegal == []


def test_a_discard_in_reconfiguration_mode_exits_then_terminates_in_event_mode():
    fmu = StrictFmu(status=lambda c, fname, args: "fmi3Discard"
                    if fname == "fmi3SetBoolean" and c.state == RECONF else "fmi3OK")
    inst = Instance(_library(make_ctx(fmu)), name="fake-dae-1")  # type: ignore[arg-type]
    inst.enter_initialization_mode(0.0)
    inst.exit_initialization_mode()
    with pytest.raises(FmiError):
        reconfigure(inst, True)
    assert fmu.components[0].state == RECONF
    inst.free()
    assert fmu.calls[-3:] == [(RECONF, "fmi3ExitConfigurationMode"), (EM, "fmi3Terminate"),
                              (TERM, "fmi3FreeInstance")]
    assert fmu.illegal == []


def test_the_illegal_call_probe_leaves_every_instance_legally():
    # the FMU accepts every illegal call: each is found, and no instance is left in
    # Configuration Mode or terminated from there
    fmu = StrictFmu()
    ctx = make_ctx(fmu)
    ctx.dae = start_instance(_library(ctx), "dae")  # type: ignore[arg-type]
    ctx.ode = start_instance(_library(ctx), "ode")  # type: ignore[arg-type]
    found = list(rare_calls.illegal_call_accepted(ctx))
    assert "fmi3SetBoolean on the Float64 variable 'x1' in Configuration Mode is accepted" in \
        " ".join(v.text for v in found)
    assert fmu.illegal == []
    assert all(c.state in ("freed", CT) for c in fmu.components)


# ------------------------------------------- F4: no Continuous-Time Mode before the iteration

def test_an_iteration_that_settles_late_enough_reaches_continuous_time_mode():
    fmu = StrictFmu(unsettled=3)
    inst = start_instance(_library(make_ctx(fmu)), "ode")  # type: ignore[arg-type]
    assert inst.discrete is not None and inst.discrete.calls == 4
    assert fmu.components[0].state == CT and fmu.illegal == []


def test_an_unsettled_iteration_is_unavailable_not_continuous_time_mode():
    fmu = StrictFmu(unsettled=1000)
    with pytest.raises(ProbeSkipped, match="discreteStatesNeedUpdate after 10 calls"):
        start_instance(_library(make_ctx(fmu)), "dae")  # type: ignore[arg-type]
    assert "fmi3EnterContinuousTimeMode" not in [f for _, f in fmu.calls]
    assert fmu.calls[-2:] == [(EM, "fmi3Terminate"), (TERM, "fmi3FreeInstance")]
    assert fmu.illegal == []


def test_the_handshake_reports_an_iteration_that_does_not_settle():
    """Continuous-Time Mode is not entered (no illegal call), and the FMU an importer would
    loop on in Event Mode is the handshake's finding, in DAE and in ODE mode, one cause."""
    fmu = StrictFmu(unsettled=1000)
    ctx = make_ctx(fmu)
    found = list(handshake.enable_handshake(ctx))
    assert [dict(v.evidence)["mode"] for v in found] == ["dae", "ode"]
    assert all("the event iteration after initialisation does not settle" in v.text
               and v.cause == handshake.UNSETTLED for v in found)
    assert [v.part for v in found] == [None, "ode-run-fails"]
    assert fmu.illegal == [] and all(c.state == "freed" for c in fmu.components)


def test_the_read_sweep_stops_before_continuous_time_mode_when_the_iteration_does_not_settle():
    fmu = StrictFmu(unsettled=1000)
    ctx = make_ctx(fmu)
    library = _library(ctx)
    result = sweep(lambda label: Instance(library, name=library.next_name(label)),  # type: ignore
                   ctx.model, "dae")
    assert "does not settle" in result.unreached[CT]
    assert set(result.unreached) == {CT} and result.faults == []
    assert fmu.illegal == [] and all(c.state == "freed" for c in fmu.components)


# --------------------------------------------- F6: a switch that is no structural parameter

@pytest.mark.parametrize("edit,check", [
    (('causality="structuralParameter" variability="tunable"',
      'causality="parameter" variability="tunable"'), enable_parameter_not_structural),
    (('causality="structuralParameter" variability="tunable"',
      'causality="structuralParameter" variability="discrete"'), enable_parameter_variability),
])
def test_a_switch_that_cannot_be_set_in_configuration_mode_is_never_set(edit, check):
    fmu = StrictFmu()
    ctx = make_ctx(fmu, md_edits=(edit,))
    layout: Layout = ctx.facts["layout"]  # type: ignore[assignment]
    assert (layout.enable, layout.enable_status, layout.modes) == (None, "unusable", ())
    for mode in ("dae", "ode"):
        with pytest.raises(ProbeSkipped):
            start_instance(_library(ctx), mode)  # type: ignore[arg-type]
    with pytest.raises(ProbeSkipped, match="see the static findings"):
        list(handshake.enable_handshake(ctx))
    assert fmu.calls == []   # fmi3EnterConfigurationMode and fmi3SetBoolean never made
    # ... and the static findings the skip points at are there
    static = CheckContext(model=ctx.model, manifest=ctx.manifest, draft="alpha1")
    assert [v.subject for v in check(static)] == ["ODE_DAE_Switch"]
