"""The hard test scenes of issue 5: Akzo, VanDerPolDAE, FourBar/FourBarScaled, NearSingular.

Each scene is checked for what it is there to show (see its README.md):

* the regular ones pass every static rule and every probe with zero findings;
* Akzo returns fmi3Discard where sqrt(y2) is undefined, reaches the test set's reference at
  t = 180, and its no-CO2-feed variant ends in a finding near the NaN region, not a hang;
* VanDerPolDAE is reported singular near t* = 1.5 - ln 2, and the check returns;
* FourBar and FourBarScaled (kN, mm) are one model in two unit systems with identical verdicts;
* NearSingular warns about the condition of dg/dw below the catalogue's threshold and not above.

Their behaviour against independent numpy models (values, Jacobians, sparsity, state machine)
is in test_scenes.py, whose SCENES table lists them too.
"""
from __future__ import annotations

import ctypes
import math
import time
from pathlib import Path

import fmpy
import numpy as np
import pytest

from conformance.report.catalogue import default_catalogue
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import thaw
from scenes.build import SCENES_DIR, build_scene
from tests.checkkit import checked
from tests.scenes.test_scenes import SCENES, Instance
from tests.simkit import sim_settings

FMI_OK, FMI_DISCARD, FMI_ERROR = 0, 2, 3
CLEAN = ("Akzo", "NearSingular", "FourBar", "FourBarScaled")
T_STAR = 1.5 - math.log(2.0)
AKZO_180 = (0.1150794920661702, 0.1203831471567715e-2, 0.1611562887407974,
            0.3656156421249283e-3, 0.1708010885264404e-1, 0.4873531310307455e-2)
SIMULATION_BUDGET_S = 60.0   # a check that hangs would be stopped far later by the runner


def _check(name: str, *, seed: int = 0, defines: tuple[str, ...] = (), fresh: bool = False):
    """The full check; once per session for each question (FourBar's clean tests and its unit
    test ask the same ones), but ``fresh``: a run of its own (the tests that time it)."""
    fmu, options = build_scene(name, defines=defines), EngineOptions(probes=True, seed=seed)
    return check_fmu(fmu, options=options) if fresh else checked(fmu, options=options)


def _describe(report) -> str:
    return "\n".join(f"{f.severity} {f.code} {f.name}: {f.message} {thaw(f.evidence)}"
                     for f in report.findings)


def _rule(name: str):
    """The catalogue rule ``name``; an unknown name (a renamed rule) fails the test, loudly."""
    rule = default_catalogue().get(name)
    if rule is None:
        pytest.fail(f"the catalogue has no rule named {name!r} (renamed or removed?): "
                    f"update tests/scenes/test_hard_scenes.py", pytrace=False)
    return rule


def _code(name: str) -> str:
    return _rule(name).code


def _simulator():
    pytest.importorskip("sksundae")
    pytest.importorskip("conformance.numerics.dae")
    from bench.sim_bench import SceneFmu

    return SceneFmu


@pytest.fixture
def make(tmp_path):
    """name (and defines) -> a fresh fmpy instance of the scene, freed afterwards."""
    created = []

    def factory(name: str, defines: tuple[str, ...] = ()) -> Instance:
        fmu = build_scene(name, defines=defines)
        unzip = fmpy.extract(str(fmu), str(tmp_path / f"{name}-{len(created)}"))
        inst = Instance(SCENES[name], (fmu, Path(unzip), fmpy.read_model_description(str(fmu))))
        created.append(inst)
        return inst

    yield factory
    for inst in created:
        inst.free()


def _status_of_derivatives(inst: Instance) -> int:
    n = len(inst.scene.vr_x)
    return inst.raw("fmi3GetContinuousStateDerivatives", (ctypes.c_double * n)(), n)


def _status_of_get(inst: Instance, vrs: list[int]) -> int:
    n = len(vrs)
    return inst.raw("fmi3GetFloat64", (ctypes.c_uint32 * n)(*vrs), n, (ctypes.c_double * n)(), n)


# ----------------------------------------------------------------------- clean scenes

@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name", CLEAN)
def test_regular_hard_scene_is_clean(name, seed):
    report = _check(name, seed=seed)
    assert report.findings == (), _describe(report)
    assert report.rules_skipped == ()


# ------------------------------------------------------------------------------- Akzo

@pytest.mark.parametrize("dae", [False, True], ids=["ode", "dae"])
def test_akzo_discards_where_sqrt_y2_is_undefined(make, dae):
    sc = SCENES["Akzo"]
    inst = make("Akzo").to_continuous(dae=dae)
    x = np.array(sc.x_test)
    inst.set_states(x)
    assert _status_of_derivatives(inst) == FMI_OK
    inst.set_states(x * [1, -1, 1, 1, 1])                       # y2 < 0
    assert _status_of_derivatives(inst) == FMI_DISCARD
    assert _status_of_get(inst, sc.vr_der[:1]) == FMI_DISCARD
    if dae:
        assert _status_of_get(inst, sc.vr_res) == FMI_DISCARD
        one, out = (ctypes.c_double * 1)(1.0), (ctypes.c_double * 1)()
        u32 = ctypes.c_uint32 * 1
        assert inst.raw("fmi3GetDirectionalDerivative", u32(sc.vr_der[0]), 1,
                        u32(sc.vr_x[1]), 1, one, 1, out, 1) == FMI_DISCARD
    inst.set_states(x)                                            # still usable afterwards
    assert _status_of_derivatives(inst) == FMI_OK
    w = inst.get(sc.vr_w) if dae else sc.solve_w(x, [])     # DAE mode keeps the w it has
    np.testing.assert_allclose(inst.derivatives(), sc.f(x, w, []), rtol=1e-12)


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_akzo_reaches_the_test_set_reference_at_180(mode):
    fmu = _simulator()(build_scene("Akzo"))
    try:
        settings = sim_settings(rtol=1e-9, stop_time=180.0, output_times=(180.0,),
                            max_steps=100_000, wall_seconds=SIMULATION_BUDGET_S)
        traj, _ = fmu.simulate(mode, settings, 180.0)
    finally:
        fmu.close()
    assert traj.ok and traj.times[-1] == 180.0, traj.message
    final = traj.values[-1, [traj.names.index(f"y{i}") for i in range(1, 7)]]
    nominal = np.array([0.1, 1e-3, 0.1, 1e-3, 0.01, 0.01])
    error = np.abs(final - AKZO_180) / (np.abs(AKZO_180) + nominal)
    assert error.max() < 1e-7, error


def test_akzo_without_co2_feed_ends_near_the_nan_region_with_a_finding():
    start = time.monotonic()
    report = _check("Akzo", defines=("AKZO_NO_CO2_FEED",), fresh=True)
    assert time.monotonic() - start < SIMULATION_BUDGET_S
    # only the simulation probes (DAE80x) see it: the sampled points stay near the start
    assert report.findings, "no finding"
    assert all(f.code.startswith("DAE80") for f in report.findings), _describe(report)
    reached = [thaw(f.evidence).get("t_reached") for f in report.findings]
    assert any(t is not None and 0.15 < t < 0.2 for t in reached), _describe(report)  # t ~ 0.18


# ----------------------------------------------------------------------- Van der Pol

def test_van_der_pol_impasse_is_reported_near_t_star_and_the_check_returns():
    start = time.monotonic()
    report = _check("VanDerPolDAE", fresh=True)
    assert time.monotonic() - start < SIMULATION_BUDGET_S
    # one fault, one finding: static rules and point probes are clean (sampling stays near
    # y1 = 2); only the simulation meets the fold
    code = _code("algebraic-jacobian-singular-along-trajectory")
    assert [f.code for f in report.findings] == [code], _describe(report)
    t = thaw(report.findings[0].evidence)["t"]
    assert T_STAR - 2e-3 < t <= T_STAR + 1e-9


def test_van_der_pol_matches_the_closed_form_before_the_impasse():
    fmu = _simulator()(build_scene("VanDerPolDAE"))
    try:
        settings = sim_settings(rtol=1e-9, stop_time=0.6, output_times=(0.2, 0.4, 0.6),
                            wall_seconds=SIMULATION_BUDGET_S)
        traj, _ = fmu.simulate("dae", settings, 0.6)
    finally:
        fmu.close()
    assert traj.ok, traj.message
    np.testing.assert_allclose(traj.series("y1")[1:],
                               [1.858205663932365, 1.693209005105341, 1.484574864527525],
                               rtol=1e-7)
    y1 = traj.series("y1")
    np.testing.assert_allclose(traj.series("y2"), y1 / (1 - y1 ** 2), rtol=1e-7)


def test_van_der_pol_ode_mode_fails_on_the_fold_only(make):
    inst = make("VanDerPolDAE").to_continuous()
    inst.set_states([1.0 + 1e-6])
    assert _status_of_derivatives(inst) == FMI_OK
    assert inst.derivatives()[0] == pytest.approx((1 + 1e-6) / (1 - (1 + 1e-6) ** 2), rel=1e-6)
    inst.set_states([1.0])                                        # dg/dw = 0: Newton stops
    assert _status_of_derivatives(inst) == FMI_ERROR


# ------------------------------------------------------------------------ NearSingular

def _eps_around_threshold() -> tuple[float, float]:
    """(eps above, eps below) the DAE745 threshold: cond(dg/dw) = 10/eps (README.md)."""
    max_condition = _rule("algebraic-jacobian-ill-conditioned").option_values["max_condition"]
    crossing = 10.0 / max_condition
    return 10.0 * crossing, 0.1 * crossing


@pytest.mark.parametrize("side", ["above", "below"])
def test_near_singular_warns_below_the_threshold_and_not_above(side):
    above, below = _eps_around_threshold()
    eps = above if side == "above" else below
    report = _check("NearSingular", defines=(f"NEAR_SINGULAR_EPS={eps!r}",))
    code = _code("algebraic-jacobian-ill-conditioned")
    if side == "above":
        assert report.findings == (), _describe(report)
        return
    assert [f.code for f in report.findings] == [code], _describe(report)
    ev = thaw(report.findings[0].evidence)
    assert ev["condition_number"] == pytest.approx(10.0 / eps, rel=0.02)
    assert sorted(ev["involved"]) == ["z1", "z2"]


def test_near_singular_solution_does_not_depend_on_eps(make):
    _, below = _eps_around_threshold()
    for defines, tol in (((), 1e-12), ((f"NEAR_SINGULAR_EPS={below!r}",), 1e-6)):
        inst = make("NearSingular", defines).to_continuous()
        np.testing.assert_allclose(inst.get([4, 5]), [1 - 2 * math.sin(1), math.sin(1)],
                                   atol=tol)
        np.testing.assert_allclose(inst.derivatives(), [-math.sin(1)], rtol=1e-12)


def test_exactly_singular_family_member_gives_findings_not_an_exception():
    report = _check("NearSingular", defines=("NEAR_SINGULAR_EPS=0",))
    assert any(f.severity.name == "ERROR" for f in report.findings), _describe(report)


# --------------------------------------------------------------- FourBar, two unit systems

def test_fourbar_scenes_share_one_header():
    shared = SCENES_DIR / "FourBar" / "fourbar.h"
    assert (SCENES_DIR / "FourBarScaled" / "fourbar.h").resolve() == shared.resolve()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fourbar_verdicts_do_not_depend_on_the_units(seed):
    si, scaled = _check("FourBar", seed=seed), _check("FourBarScaled", seed=seed)
    def verdict(report):
        return (sorted((f.code, f.severity.name) for f in report.findings),
                sorted(report.rules_run), sorted(c for c, _ in report.rules_skipped))

    assert verdict(si) == verdict(scaled)
    assert si.findings == (), _describe(si)


def test_fourbar_scaled_is_the_same_model_in_kn_and_mm(make):
    x = np.array(SCENES["FourBar"].x_test)
    si = make("FourBar").to_continuous(x=x)
    kn = make("FourBarScaled").to_continuous(x=x)
    np.testing.assert_allclose(kn.derivatives(), si.derivatives(), rtol=1e-12, atol=1e-12)
    w_si, w_kn = si.get(range(14, 19)), kn.get(range(14, 19))
    np.testing.assert_allclose(w_kn * [1, 1, 1, 1e3, 1e3], w_si, rtol=1e-11, atol=1e-11)
    # DAE mode at the same inconsistent point: moment rows equal, loop rows in mm/s^2
    w = w_si + [0.5, 0.1, -0.3, 20.0, -10.0]
    res = []
    for inst, lam_unit in ((make("FourBar"), 1.0), (make("FourBarScaled"), 1e3)):
        inst.to_continuous(dae=True, x=x)
        inst.set(range(14, 19), w / [1, 1, 1, lam_unit, lam_unit])
        res.append(inst.get(range(19, 24)))
    np.testing.assert_allclose(res[1], res[0] * [1, 1, 1, 1e3, 1e3], rtol=1e-9, atol=1e-9)


FOURBAR_REFERENCE = {   # README.md: numpy twin, scipy DOP853 rtol 1e-13
    0.1: [0.071759049532, 0.100077573751, 0.067050639215, 0.068241027856, -0.000375061037,
          0.079626034873, -7983.462591638, -219.537650935],
    0.25: [0.078108535065, 0.100046604693, 0.074459219641, 0.084654442059, -0.000360536439,
           0.098772082272, -7955.056351191, -498.433227691],
    0.5: [0.077934911438, 0.100047347077, 0.074256641033, 0.001965959810, -0.000008439341,
          0.002293821894, -7956.61413414, -483.010633463],
}


@pytest.mark.parametrize("name, lam_unit", [("FourBar", 1.0), ("FourBarScaled", 1e3)])
def test_fourbar_reference_values_in_dae_mode(name, lam_unit):
    fmu = _simulator()(build_scene(name))
    try:
        settings = sim_settings(rtol=1e-10, stop_time=0.5, output_times=tuple(FOURBAR_REFERENCE),
                            wall_seconds=SIMULATION_BUDGET_S)
        traj, _ = fmu.simulate("dae", settings, 0.5)
    finally:
        fmu.close()
    assert traj.ok, traj.message
    columns = [traj.names.index(n) for n in ("theta1", "theta2", "theta3", "omega1", "omega2",
                                             "omega3", "lambdaX", "lambdaY")]
    got = traj.values[1:, columns].copy()
    got[:, 6:] *= lam_unit
    expected = np.array(list(FOURBAR_REFERENCE.values()))
    nominal = np.array([0.1] * 3 + [1.0] * 3 + [1e4] * 2)
    assert np.max(np.abs(got - expected) / (np.abs(expected) + nominal)) < 1e-7


# ------------------------------------------------------------------------ the benchmark

def test_sim_bench_smoke(tmp_path):
    _simulator()
    import json

    from bench import sim_bench

    assert sim_bench.main(["--out", str(tmp_path), "--quick", "--runs", "1"]) == 0
    data = json.loads((tmp_path / "simulation.json").read_text())
    rows = data["results"]
    assert {(r["scene"], r["mode"]) for r in rows} == {("SimpleDAE", "dae"), ("SimpleDAE", "ode")}
    assert all(r["ok"] and r["error_final"] < 100 * r["rtol"] and r["fmi_calls"] > 0
               for r in rows), rows
    assert data["machine"]["python"] and data["date"]
    assert "| 1e-06 | DAE | ok |" in (tmp_path / "simulation.md").read_text()
    assert (tmp_path / "simulation.png").stat().st_size > 10_000
