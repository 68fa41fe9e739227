"""The simulation of real FMUs (the scenes), in the probe worker: accuracy against reference
values, DAE against ODE mode, the hard cases returning with a finding, and the report's info."""
from __future__ import annotations

import time

import numpy as np
import pytest

from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import thaw
from conformance.run.simulate_fmu import simulate_fmu
from scenes.build import build_scene
from tests.numerics.systems import ROBERTSON_REFERENCE, VAN_DER_POL_IMPASSE
from tests.simkit import sim_settings


def _codes(result) -> set[str]:
    return {f.code for f in result.report.findings}


# Worst |error| / (rtol |ref| + atol) measured over the four reference times: 0.98 at rtol 1e-4,
# 0.51 at 1e-5, 1.01 at 1e-6, 1.44 at 1e-7, 1.88 at 1e-8. IDA controls the local error; the
# global error at tight tolerances accumulates to a small multiple of the tolerance.
@pytest.mark.parametrize(("rtol", "allowed"), [(1e-4, 1.0), (1e-5, 1.0), (1e-6, 1.5),
                                               (1e-8, 2.0)])
def test_robertson_in_dae_mode_to_4e10_matches_the_reference(rtol, allowed):
    settings = sim_settings(mode="dae", rtol=rtol, stop_time=4e10,
                        output_times=tuple(ROBERTSON_REFERENCE))
    result = simulate_fmu(build_scene("Robertson"), settings)
    assert _codes(result) == set()
    [traj] = result.trajectories
    assert traj.ok and traj.t_end == 4e10 and traj.names == ["y1", "y2", "y3"]
    assert traj.jacobian == "directional derivatives"
    for t, ref in ROBERTSON_REFERENCE.items():
        ref = np.array(ref)
        error = np.abs(traj.values[traj.times.index(t)] - ref)
        assert np.all(error <= allowed * (rtol * np.abs(ref) + np.array(traj.atol))), (t, error)


@pytest.mark.parametrize("scene", ["SimpleDAE", "HelloWorldDAE"])
def test_dae_and_ode_mode_agree_to_a_gap_that_shrinks_with_rtol(scene):
    differences = []
    for rtol in (1e-5, 1e-8):
        result = simulate_fmu(build_scene(scene), sim_settings(mode="both", rtol=rtol))
        assert _codes(result) == set()
        dae, ode = result.trajectories
        assert dae.ok and ode.ok and (dae.mode, ode.mode) == ("dae", "ode")
        assert max(result.comparison["gaps"].values()) <= 100.0
        states = [n for n, k in zip(dae.names, dae.kinds) if k == "state"]
        differences.append(max(np.max(np.abs(dae.series(n) - ode.series(n))) for n in states))
    assert differences[1] < differences[0] / 10


def test_van_der_pol_impasse_is_a_finding_with_the_time_and_returns():
    started = time.monotonic()
    result = simulate_fmu(build_scene("VanDerPolDAE"), sim_settings(mode="both"))
    assert time.monotonic() - started < 20
    assert _codes(result) == {"DAE802"}
    [finding] = result.report.findings
    event = dict(thaw(finding.evidence))["event"]
    assert abs(event["t"] - VAN_DER_POL_IMPASSE) < 1e-3 and event["involved"] == ["y2"]
    [dae] = result.trajectories  # ODE mode is not run after an incomplete DAE-mode run
    assert dae.times[-1] < VAN_DER_POL_IMPASSE


def test_akzo_discard_region_is_a_finding_not_a_hang():
    started = time.monotonic()
    result = simulate_fmu(build_scene("Akzo", defines=["AKZO_NO_CO2_FEED"]),
                          sim_settings(mode="both", stop_time=180.0))
    assert time.monotonic() - started < 20
    assert _codes(result) == {"DAE803"}
    event = dict(thaw(result.report.findings[0].evidence))["event"]
    assert event["status"] == "fmi3Discard" and 0.15 < event["t"] < 0.2


def test_akzo_with_its_feed_reaches_180():
    result = simulate_fmu(build_scene("Akzo"), sim_settings(mode="both", stop_time=180.0))
    assert _codes(result) == set() and all(t.ok for t in result.trajectories)


def test_four_bar_scaled_and_unscaled_give_the_same_verdict():
    verdicts = []
    for scene in ("FourBar", "FourBarScaled"):
        result = simulate_fmu(build_scene(scene), sim_settings(mode="both", stop_time=0.5))
        verdicts.append((_codes(result), [t.status for t in result.trajectories]))
    assert verdicts[0] == verdicts[1] == (set(), ["ok", "ok"])


def test_a_crash_during_the_simulation_is_a_finding():
    result = simulate_fmu(build_scene("HelloWorldDAE", defines=["DEFECT_SEGFAULT_GETFLOAT64"]),
                          sim_settings(mode="dae"))
    assert "DAE701" in _codes(result) and result.trajectories == []


def test_check_publishes_a_reproducible_trajectory_summary():
    fmu = build_scene("SimpleDAE")
    options = EngineOptions(select=("DAE8",))
    first, second = check_fmu(fmu, options=options), check_fmu(fmu, options=options)
    assert first == second  # no wall-clock time in the report by default
    info = thaw(first.info)["simulation"]
    assert info["mode"] == "dae" and info["rtol"] == 1e-6 and info["steps"] > 0
    assert "wall_s" not in info and info["ode"]["mode"] == "ode"
    assert len(info["times"]) == 101 and info["times"][-1] == 1.0
    assert set(info["series"]) == {"x1", "x2", "z1", "z2"}
    assert all(len(v) == 101 for v in info["series"].values())
    assert set(info["comparison"]["gaps"]) == {"x1", "x2", "z1", "z2"}
