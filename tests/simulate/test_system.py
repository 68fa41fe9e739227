"""The FMU as a DAE residual and an ODE right-hand side (conformance/simulate/system.py), loaded
in this process (our own scene binaries only): coloured Jacobians from the declared sparsity,
directional derivatives against the finite-difference fallback, and only the calls the FMI 3.0.2
state machine allows once a run has stopped (on an fmi3Error, or the FMU's terminateSimulation)."""
from __future__ import annotations


import numpy as np
import pytest

from conformance.model.description import Unknown
from conformance.numerics.dae import integrate_dae
from conformance.numerics.settings import FMU_FAILED
from conformance.runtime.errors import FmiError
from conformance.runtime.modes import start_instance
from conformance.simulate.integrate import simulate_instance
from conformance.simulate.system import FINITE_DIFFERENCES, FmuDae, FmuOde, pattern_from
from tests.simkit import sim_settings

DENSE = sim_settings().dense_up_to


def test_pattern_from_dependencies_and_dense_rows_without_them():
    rows = [Unknown("Residual", 7, (2, 6), None, None, "m", "p"),
            Unknown("Residual", 8, None, None, None, "m", "p"), None]
    dense = pattern_from(rows, [2, 4, 6]).to_dense()
    assert dense.tolist() == [[True, False, True], [True, True, True], [True, True, True]]


def test_directional_jacobian_matches_the_finite_difference_fallback(loaded):
    library, layout, _, manifest = loaded("Robertson")
    inst = start_instance(library, "dae")
    exact = FmuDae(inst, layout, manifest, dense_up_to=DENSE)
    fallback = FmuDae(inst, layout, manifest, dense_up_to=DENSE, use_directional=False)
    assert fallback.jacobian_source == FINITE_DIFFERENCES
    y = np.array([0.9, 2e-5, 0.1 - 2e-5])
    # forward differences: d(massBalance)/d(y2) with a step of 3e-13 loses ~1e-4 to rounding
    assert fallback.partials(0.5, y) == pytest.approx(exact.partials(0.5, y), rel=1e-3,
                                                      abs=1e-6)
    f = exact.evaluate(0.5, y)
    assert f[2] == pytest.approx(0.0, abs=1e-15)
    assert f[0] == pytest.approx(-0.04 * 0.9 + 1e4 * 2e-5 * (0.1 - 2e-5))


def test_columns_that_share_no_row_share_a_directional_derivative(loaded):
    library, layout, _, manifest = loaded("Chain")
    inst = start_instance(library, "dae")
    system = FmuDae(inst, layout, manifest, dense_up_to=DENSE)
    n = system.nx + system.nw
    assert system.jac.colouring.count < n
    y = inst.get_float64([*system.states, *system.algebraic])
    fallback = FmuDae(inst, layout, manifest, dense_up_to=DENSE, use_directional=False)
    assert system.partials(0.0, y) == pytest.approx(fallback.partials(0.0, y), rel=1e-4,
                                                    abs=1e-6)


def test_fallback_jacobian_integrates_robertson_too(loaded):
    library, layout, _, manifest = loaded("Robertson")
    runs = []
    for directional in (True, False):
        inst = start_instance(library, "dae")
        system = FmuDae(inst, layout, manifest, dense_up_to=DENSE,
                        use_directional=directional)
        y0 = inst.get_float64([*system.states, *system.algebraic])
        runs.append(integrate_dae(system, sim_settings(rtol=1e-6), t0=0.0, y0=y0, stop=40.0))
        inst.free()
    assert all(r.ok for r in runs)
    assert runs[0].values[-1] == pytest.approx(runs[1].values[-1], rel=1e-4, abs=1e-10)
    assert runs[0].fmi_calls > 0


def test_ode_mode_system_reads_the_algebraic_variables(loaded):
    library, layout, model, _ = loaded("HelloWorldDAE")
    inst = start_instance(library, "ode")
    system = FmuOde(inst, layout, model, dense_up_to=DENSE)
    x = np.array([2.0])
    assert system.evaluate(0.1, x) == pytest.approx([2.8])
    assert system.partials(0.1, x)[0, 0] == pytest.approx(1.4)
    assert system.algebraic_values(0.1, x) == pytest.approx([2.8, -0.4])


# ---------------------------------------------- only the calls the state machine allows

class _Refusing:
    """The loaded binary of one instance, except that fmi3SetTime past ``after`` returns
    fmi3Error (the instance is in Terminated from then on, FMI 3.0.2 §2.3.1); ``later`` lists
    the calls made after that."""

    def __init__(self, fmu, after: float):
        self.fmu, self.after, self.failed, self.later = fmu, after, False, []

    def __getattr__(self, fname: str):
        function = getattr(self.fmu, fname)

        def call(*args):
            if self.failed:
                self.later.append(fname)
            elif fname == "fmi3SetTime" and args[1] > self.after:
                self.failed = True
                raise FmiError(fname, "fmi3Error", ["[Error] refused"])
            return function(*args)
        return call


def test_a_dae_run_an_error_stopped_sets_nothing_afterwards(loaded):
    # SimpleDAE has no events, so a run that ends is evaluated again along its output times
    # (residual_along): not when an fmi3Error put the instance in Terminated (§2.3.8)
    library, layout, model, manifest = loaded("SimpleDAE")
    inst = start_instance(library, "dae")
    binary = inst._fmu = _Refusing(inst._fmu, after=0.3)
    traj = simulate_instance(inst, layout, sim_settings(), start=0.0, stop=1.0, model=model,
                             manifest=manifest)
    assert traj.status == FMU_FAILED and inst.failure is not None
    assert binary.failed and not [f for f in binary.later if f.startswith("fmi3Set")]
    assert traj.residual_along == {}


def _in_event_mode(inst) -> list[str]:
    """Record the calls ``inst`` makes while in Event Mode."""
    calls: list[str] = []
    real = inst._fmi
    state = ["Continuous-Time Mode"]

    def fmi(fname, *args, **kwargs):
        if state[0] == "Event Mode":
            calls.append(fname)
        result = real(fname, *args, **kwargs)
        state[0] = {"fmi3EnterEventMode": "Event Mode",
                    "fmi3EnterContinuousTimeMode": "Continuous-Time Mode"}.get(fname, state[0])
        return result
    inst._fmi = fmi
    return calls


def test_an_ode_run_the_fmu_ends_reads_its_last_values_without_setting_them(loaded):
    # EventDAE ends the run at its time event (terminateSimulation): the instance stays in
    # Event Mode, where the output at the event reads w without fmi3SetTime or
    # fmi3SetContinuousStates (FMI 3.0.2 §2.3.5 lists neither)
    library, layout, model, manifest = loaded("EventDAE", "EVENTDAE_TERMINATE")
    inst = start_instance(library, "ode")
    in_event_mode = _in_event_mode(inst)
    traj = simulate_instance(inst, layout, sim_settings(rtol=1e-8), start=0.0, stop=1.0,
                             model=model, manifest=manifest)
    assert traj.ok and traj.terminated_at == pytest.approx(0.75) and traj.times[-1] == 0.75
    assert not {"fmi3SetTime", "fmi3SetContinuousStates"} & set(in_event_mode)
    x, w = traj.values[-1]
    # what the FMU computed at the event's (t, x) before the event (b = 0 until then,
    # scenes/EventDAE), as the DAE-mode run records it
    assert w == pytest.approx(3.0 * x)
