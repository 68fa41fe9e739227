"""No run rests on derivatives the probes refuted (conformance/simulate/jacobian_check.py): the
FMU's directional derivatives are used only when confirmed, by the probes' verdict or by finite
differences at the initial point; otherwise coloured finite differences, with a note why.

Scene binaries loaded in this process; DEFECT_ZERO_DIRECTIONAL and DEFECT_WRONG_JACOBIAN give
correct equations with wrong derivatives.
"""
from __future__ import annotations


import pytest

from conformance.report.catalogue import default_catalogue
from conformance.runtime.modes import start_instance
from conformance.simulate.integrate import simulate_instance
from conformance.simulate.jacobian_check import DerivativeCheck, choose_jacobian
from conformance.simulate.system import DIRECTIONAL, FINITE_DIFFERENCES, FmuDae, FmuOde
from tests.fixtures import build_scene
from tests.simkit import sim_settings

OPTIONS = default_catalogue()["directional-derivative-mismatch"].option_values


def _check(verdict: str | None = None) -> DerivativeCheck:
    return DerivativeCheck(rtol=OPTIONS["rtol"], margin=OPTIONS["margin"], ulps=OPTIONS["ulps"],
                           verdict=verdict)


def _system(loaded, mode: str, scene: str, *defines: str):
    library, layout, model, manifest = loaded(scene, *defines)
    inst = start_instance(library, mode)
    dense = sim_settings().dense_up_to
    system = (FmuDae(inst, layout, manifest, dense_up_to=dense) if mode == "dae"
              else FmuOde(inst, layout, model, dense_up_to=dense))
    return system, layout, model, manifest


@pytest.mark.parametrize("mode", ["dae", "ode"])
@pytest.mark.parametrize("scene", ["SimpleDAE", "Robertson", "HelloWorldDAE", "Chain"])
def test_correct_derivatives_are_confirmed_at_the_initial_point(loaded, scene, mode):
    system, layout, _, _ = _system(loaded, mode, scene)
    choose_jacobian(system, layout.start_time, _check())
    assert system.jacobian_source == DIRECTIONAL and system.jac.use_directional


@pytest.mark.parametrize("mode", ["dae", "ode"])
@pytest.mark.parametrize("defect", ["DEFECT_ZERO_DIRECTIONAL", "DEFECT_WRONG_JACOBIAN"])
def test_refuted_derivatives_are_replaced_by_finite_differences(loaded, defect, mode):
    system, layout, _, _ = _system(loaded, mode, "SimpleDAE", defect)
    choose_jacobian(system, layout.start_time, _check())
    assert not system.jac.use_directional
    assert system.jacobian_source.startswith(f"{FINITE_DIFFERENCES} (the FMU's directional "
                                             "derivatives were not used")
    assert "d(der(x1))/d(x1)" in system.jacobian_source or defect == "DEFECT_ZERO_DIRECTIONAL"


def test_the_probes_verdict_is_taken_as_it_is(loaded):
    system, layout, _, _ = _system(loaded, "dae", "SimpleDAE", "DEFECT_ZERO_DIRECTIONAL")
    calls = system.inst.calls
    choose_jacobian(system, layout.start_time, _check(""))   # confirmed by the probes
    assert system.jac.use_directional and system.inst.calls == calls   # no check, no call
    choose_jacobian(system, layout.start_time, _check("refuted by the probes"))
    assert system.jacobian_source == f"{FINITE_DIFFERENCES} (refuted by the probes)"
    clean, layout, _, _ = _system(loaded, "dae", "SimpleDAE")
    choose_jacobian(clean, layout.start_time, None)          # no check asked for
    assert clean.jac.use_directional


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_correct_equations_with_zero_derivatives_simulate(loaded, mode):
    library, layout, model, manifest = loaded("SimpleDAE", "DEFECT_ZERO_DIRECTIONAL")
    settings = sim_settings(rtol=1e-6)
    runs = {}
    for name, check in (("unchecked", None), ("checked", _check())):
        inst = start_instance(library, mode)
        runs[name] = simulate_instance(inst, layout, settings, start=0.0, stop=1.0, model=model,
                                       manifest=manifest, derivatives=check)
        inst.free()
    assert runs["checked"].ok, runs["checked"].message
    assert runs["checked"].jacobian.startswith(FINITE_DIFFERENCES)
    if mode == "dae":   # with the zeros, dg/dw looks singular at the initial point
        assert not runs["unchecked"].ok


def test_check_uses_the_probes_verdict_and_the_model_simulates():
    from conformance.run.engine import EngineOptions, check_fmu
    from conformance.reporters.json_report import fmu_dict

    fmu = build_scene("SimpleDAE", defines=["DEFECT_ZERO_DIRECTIONAL"])
    report = check_fmu(fmu, options=EngineOptions(probes=True, select=("DAE74", "DAE80")))
    assert {f.code for f in report.findings} == {"DAE740"}
    simulation = fmu_dict(report)["info"]["simulation"]
    assert simulation["status"] == "ok" and simulation["ode"]["status"] == "ok"
    for run in (simulation, simulation["ode"]):
        assert run["jacobian"].startswith(f"{FINITE_DIFFERENCES} (the FMU's directional "
                                          "derivatives were not used: finite differences "
                                          "refute")
        assert "directional-derivative-mismatch" in run["jacobian"]   # the probes' verdict


def test_lsdae_simulate_checks_at_the_initial_point(tmp_path, capsys):
    import argparse

    from conformance.commands.simulate import add_parser, run

    parser = argparse.ArgumentParser(prog="lsdae")
    add_parser(parser.add_subparsers(dest="command", required=True))
    fmu = build_scene("SimpleDAE", defines=["DEFECT_ZERO_DIRECTIONAL"])
    code = run(parser.parse_args(["simulate", str(fmu), "-o", str(tmp_path / "out.csv")]))
    assert code == 0
    assert "at the initial point" in capsys.readouterr().out
