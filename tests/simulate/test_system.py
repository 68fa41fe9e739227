"""The FMU as a DAE residual and an ODE right-hand side (conformance/simulate/system.py), loaded
in this process (our own scene binaries only): coloured Jacobians from the declared sparsity,
directional derivatives against the finite-difference fallback."""
from __future__ import annotations


import numpy as np
import pytest

from conformance.model.description import Unknown
from conformance.numerics.dae import integrate_dae
from conformance.runtime.modes import start_instance
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
