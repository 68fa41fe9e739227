"""``lsdae simulate``: the CSV, the summary, exit codes and usage errors.

The subcommand is driven through its own ``add_parser``/``run`` (what conformance/commands/cli.py
wires), so these tests do not depend on the wiring.
"""
from __future__ import annotations

import argparse
import csv
import re
import shutil
import sys
import zipfile
from types import SimpleNamespace

import pytest

from conformance.commands import simulate
from conformance.commands.simulate import add_parser, run, summary
from tests.fixtures import build_scene, variant
from tests.numerics.systems import VAN_DER_POL_IMPASSE


def _main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="lsdae")
    add_parser(parser.add_subparsers(dest="command", required=True))
    return run(parser.parse_args(["simulate", *argv]))


def _rows(path) -> list[list[str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.reader(fh))


def test_robertson_trajectory_csv(tmp_path, capsys):
    out = tmp_path / "trajectory.csv"
    code = _main([str(build_scene("Robertson")), "--stop-time", "4e10",
                  "--output-times", "0.4,40,4e5,4e10", "-o", str(out)])
    assert code == 0
    rows = _rows(out)
    assert rows[0] == ["time", "y1", "y2", "y3"]
    assert [float(r[0]) for r in rows[1:]] == [0.0, 0.4, 40.0, 4e5, 4e10]
    assert float(rows[2][1]) == pytest.approx(9.851721139e-1, rel=1e-4)
    text = capsys.readouterr().out
    assert "DAE mode" in text and "reached the stop time" in text


def test_both_modes_write_both_trajectories_and_compare(tmp_path, capsys):
    dae, ode = tmp_path / "dae.csv", tmp_path / "ode.csv"
    code = _main([str(build_scene("HelloWorldDAE")), "--mode", "both", "--output-points", "11",
                  "-o", str(dae), "--ode-output", str(ode)])
    assert code == 0
    assert _rows(dae)[0] == _rows(ode)[0] == ["time", "x", "y", "z"]
    assert len(_rows(dae)) == len(_rows(ode)) == 12
    assert "DAE vs ODE: largest gap" in capsys.readouterr().out


def test_ode_mode_alone(tmp_path):
    out = tmp_path / "ode.csv"
    assert _main([str(build_scene("SimpleDAE")), "--mode", "ode", "-o", str(out)]) == 0
    assert _rows(out)[0] == ["time", "x1", "x2", "z1", "z2"]


def test_default_stop_time_comes_from_the_default_experiment(tmp_path):
    out = tmp_path / "r.csv"
    assert _main([str(build_scene("Robertson")), "-o", str(out)]) == 0
    assert float(_rows(out)[-1][0]) == 40.0


def test_impasse_is_a_finding_and_the_trajectory_up_to_it_is_written(tmp_path, capsys):
    out = tmp_path / "vdp.csv"
    assert _main([str(build_scene("VanDerPolDAE")), "-o", str(out), "--color", "never"]) == 1
    times = [float(r[0]) for r in _rows(out)[1:]]
    assert times and times[-1] < VAN_DER_POL_IMPASSE
    assert "algebraic-jacobian-singular-along-trajectory" in capsys.readouterr().out


def test_static_findings_are_one_line_and_fail_only_with_fail_on(tmp_path, capsys):
    """A resource compressed with bzip2 is a static warning (archive-compression-method): the
    simulation still succeeds (exit 0), the warning is summarised in one line, and only
    --fail-on warning turns it into exit 1."""
    fmu = tmp_path / "bzip2.fmu"
    shutil.copyfile(build_scene("HelloWorldDAE"), fmu)
    with zipfile.ZipFile(fmu, "a") as zf:
        zf.writestr("resources/notes.txt", "compressed the wrong way\n",
                    compress_type=zipfile.ZIP_BZIP2)
    out = tmp_path / "bzip2.csv"
    assert _main([str(fmu), "-o", str(out), "--color", "never"]) == 0
    printed = capsys.readouterr().out
    assert out.is_file()
    assert sum("static check:" in line for line in printed.splitlines()) == 1
    assert "archive-compression-method" in printed and "lsdae check" in printed
    assert _main([str(fmu), "--fail-on", "warning", "--color", "never"]) == 1


def test_start_stop_and_tolerance_come_from_the_default_experiment(tmp_path, capsys):
    fmu = variant("SimpleDAE", md_edits=[(
        '<DefaultExperiment startTime="0" stopTime="1"/>',
        '<DefaultExperiment startTime="2" stopTime="2.5" tolerance="1e-5"/>')])
    out = tmp_path / "shifted.csv"
    assert _main([str(fmu), "-o", str(out), "--color", "never"]) == 0
    times = [float(r[0]) for r in _rows(out)[1:]]
    assert times[0] == 2.0 and times[-1] == 2.5
    assert "rtol 1e-05" in capsys.readouterr().out
    assert _main([str(fmu), "-o", str(out), "--stop-time", "3", "--rtol", "1e-4"]) == 0
    assert float(_rows(out)[-1][0]) == 3.0


def test_nothing_simulated_is_a_failure_with_its_reason(tmp_path, capsys):
    broken = tmp_path / "broken.fmu"
    broken.write_bytes(b"not a zip archive")
    assert _main([str(broken), "--color", "never"]) == 1
    assert "nothing was simulated" in capsys.readouterr().err


def test_usage_errors(tmp_path, capsys):
    assert _main([str(tmp_path / "missing.fmu")]) == 2
    with pytest.raises(SystemExit) as bad:
        _main([str(tmp_path / "x.fmu"), "--output-times", "a,b"])
    assert bad.value.code == 2
    with pytest.raises(SystemExit):
        _main([str(tmp_path / "x.fmu"), "--rtol", "-1"])
    capsys.readouterr()


def test_start_values_of_inputs_change_the_run(tmp_path, capsys):
    fmu = str(build_scene("SimpleDAE"))
    base, moved = tmp_path / "base.csv", tmp_path / "moved.csv"
    assert _main([fmu, "-o", str(base), "--color", "never"]) == 0
    assert _main([fmu, "-o", str(moved), "--start-value", "u1=0.5", "--start-value", "u2=-0.25",
                  "--color", "never"]) == 0
    first, second = _rows(base), _rows(moved)
    assert first[0] == second[0] and first[1][:3] == second[1][:3]  # same time and states x1, x2
    assert first[-1] != second[-1], "the inputs' start values did not reach the run"


@pytest.mark.parametrize("item", ["nope=1", "u1", "u1=fast", "x1=2"])
def test_bad_start_values_are_usage_errors(item, capsys):
    assert _main([str(build_scene("SimpleDAE")), "--start-value", item]) == 2
    assert capsys.readouterr().err.startswith("lsdae: --start-value")


def test_the_summary_gives_the_largest_residual_along_the_dae_run(tmp_path, capsys):
    assert _main([str(build_scene("SimpleDAE")), "--color", "never"]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines()
                if "largest residual along the run" in line)
    value = float(line.split("largest residual along the run ")[1].split()[0])
    assert 0 <= value < 1e-5  # IDA kept 0 = g(x, w) to within its tolerance


@pytest.mark.parametrize("scene, define, code", [
    ("SimpleDAE", "DEFECT_ODE_DAE_INCONSISTENT", 1),     # a gap from t = 0 on
    ("HelloWorldDAE", "DEFECT_ODE_DAE_INCONSISTENT", 1),
    ("HelloWorldDAE", "DEFECT_LATE_ODE_DRIFT", 1),        # a gap from t = 0.5 on
    # the ODE run's instance starts where the DAE's ended: other states at t = 0, which
    # simulate alone cannot tell from an initialisation that alpha.1 leaves open (the
    # initial-gap part, information); `lsdae check` names the cause, instances-not-independent
    ("HelloWorldDAE", "DEFECT_STALE_STATES", 0),
])
def test_both_modes_decide_a_gap_themselves_at_any_time(scene, define, code, tmp_path, capsys):
    """simulate --mode both runs no point probe: a gap already there at t = 0 is its own
    verdict (ode-dae-trajectory-mismatch), printed, not left to a rule that does not run; an
    error (exit 1) where both runs start from the same states."""
    assert _main([str(variant(scene, defines=[define])), "--mode", "both",
                  "-o", str(tmp_path / "dae.csv")]) == code
    out = capsys.readouterr().out
    assert ("error[DAE805" if code else "info[DAE805") in out
    assert "DAE805" in out and "ode-dae-trajectory-mismatch" in out


def _traj(**kw):
    """A run's record as summary() reads it (conformance/simulate's Trajectory)."""
    base = dict(mode="dae", ok=True, terminated_at=None, message="done", status="ok",
                init=None, residual_along=None, t_start=0.0, t_end=2.5, stop_time=2.5,
                rtol=1e-6, steps=12, function_calls=30, jacobian_calls=4,
                jacobian="directional derivatives", fmi_calls=99, wall_s=0.0123,
                has_events=False, event_times=(), state_events=0, time_events=0, indicators=0)
    return SimpleNamespace(**{**base, **kw})


def test_summary_of_a_dae_run_that_reached_the_stop_time():
    assert summary(_traj()) == (
        "DAE mode: t = 0 .. 2.5 of 2.5, reached the stop time\n"
        "  rtol 1e-06, 12 steps, 30 residual and 4 Jacobian evaluations (directional "
        "derivatives), 99 FMI calls, 0.012 s\n")


def test_summary_of_an_ode_run_with_residuals_and_events():
    traj = _traj(mode="ode", terminated_at=1.25, message="terminated by the FMU at t = 1.25",
                 t_end=1.25, init={"residual_before": {"max_abs": 0.5},
                                   "residual_after": {"max_abs": 1e-12}},
                 residual_along={"max_abs": 3e-9, "residual": "g1", "t": 0.75},
                 has_events=True, event_times=(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), state_events=1,
                 time_events=5, indicators=2)
    assert summary(traj) == (
        "ODE mode: t = 0 .. 1.25 of 2.5, terminated by the FMU at t = 1.25\n"
        "  rtol 1e-06, 12 steps, 30 right-hand side and 4 Jacobian evaluations (directional "
        "derivatives), 99 FMI calls, 0.012 s; initial residual 0.5 -> 1e-12; largest residual "
        "along the run 3e-09 (g1 at t = 0.75)\n"
        "  1 state event, 5 time events (2 event indicators) at t = 0.1, 0.2, 0.3, 0.4, 0.5, "
        "...\n")


def test_summary_of_a_failed_run_with_one_of_each_event():
    traj = _traj(ok=False, status="failed", message="dg/dw became singular", t_end=0.8,
                 init={"residual_before": {"max_abs": 0.5}}, has_events=True,
                 event_times=(0.25,), state_events=2, time_events=1, indicators=1)
    assert summary(traj) == (
        "DAE mode: t = 0 .. 0.8 of 2.5, failed: dg/dw became singular\n"
        "  rtol 1e-06, 12 steps, 30 residual and 4 Jacobian evaluations (directional "
        "derivatives), 99 FMI calls, 0.012 s\n"
        "  2 state events, 1 time event (1 event indicator) at t = 0.25\n")
    assert summary(_traj(has_events=True, indicators=3)).endswith(
        "  0 state events, 0 time events (3 event indicators)\n")


def test_comparison_lines():
    assert simulate._comparison_line({}) == "DAE vs ODE: nothing to compare\n"
    assert simulate._comparison_line({"worst": None}) == "DAE vs ODE: nothing to compare\n"
    assert simulate._comparison_line(
        {"worst": {"gap": 0.01234, "variable": "x", "t": 0.5}, "compared_times": 11}) == (
        "DAE vs ODE: largest gap 0.0123 tolerance units (x at t = 0.5) over 11 output times\n")


def test_static_line_counts_and_names_the_first_three():
    from conformance.report.findings import Severity

    def finding(name, severity):
        return SimpleNamespace(name=name, severity=severity)

    findings = [finding("a", Severity.ERROR), finding("b", Severity.WARNING),
                finding("a", Severity.ERROR), finding("c", Severity.INFO),
                finding("d", Severity.INFO)]
    assert simulate._static_line(findings, "m.fmu") == (
        "static check: 2 errors, 1 warning, 2 infos (a, b, c, ...); `lsdae check m.fmu` "
        "shows them\n")
    assert simulate._static_line(findings[1:2], "m.fmu") == (
        "static check: 1 warning (b); `lsdae check m.fmu` shows them\n")


def test_usage_error_messages(tmp_path, capsys):
    missing = tmp_path / "missing.fmu"
    assert _main([str(missing)]) == 2
    assert capsys.readouterr() == ("", f"lsdae: {missing}: no such file or folder\n")
    assert _main([str(build_scene("HelloWorldDAE")), "--rtol", "1"]) == 2
    assert capsys.readouterr() == ("", "lsdae: --rtol must be below 1\n")


def test_ode_output_without_both_modes_is_said_on_stderr(tmp_path, capsys):
    ode = tmp_path / "o.csv"
    assert _main([str(build_scene("HelloWorldDAE")), "--ode-output", str(ode)]) == 0
    out, err = capsys.readouterr()
    assert err == "lsdae: --ode-output needs --mode both\n"
    assert out.startswith("DAE mode: ") and not ode.exists()


def test_a_run_stopped_by_its_budget_says_why_and_where(capsys):
    """A wall-clock budget of a nanosecond runs out before the first step: no finding of the
    simulation's own (the machine's speed is no verdict), so the reason is a note."""
    assert _main([str(build_scene("Robertson")), "--time-limit", "1e-9"]) == 1
    out, err = capsys.readouterr()
    why = ("lsdae's wall-clock safety net of 1e-09 s ran out (the machine's speed, not the "
           "FMU's: no verdict)")
    assert out.startswith(f"DAE mode: t = 0 .. 0 of 40, time-budget: {why}\n")
    assert out.endswith(
        "\nnote: time budget: the DAE-mode run was stopped at t = 0 of 40 after 0 steps by "
        "lsdae's wall-clock safety net (wall_seconds = 1e-09 s of simulation-failed): a faster "
        "machine could have finished it, so no verdict\n")
    assert err == f"lsdae: the DAE-mode integration stopped at t = 0 of 40: {why}\n"


def test_an_impasse_is_said_on_stderr_without_colour_under_no_color(tmp_path, capsys,
                                                                    monkeypatch):
    monkeypatch.setenv("NO_COLOR", "1")
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    assert _main([str(build_scene("VanDerPolDAE"))]) == 1
    out, err = capsys.readouterr()
    assert "\x1b[" not in out and "error[DAE" in out
    assert re.fullmatch(r"lsdae: the DAE-mode integration stopped at t = 0\.80\d+ of 1: dg/dw "
                        r"became singular\n", err), err
    monkeypatch.delenv("NO_COLOR")
    assert _main([str(build_scene("VanDerPolDAE")), "--color", "auto"]) == 1
    assert "\x1b[" in capsys.readouterr().out


def test_a_binary_that_dies_before_any_run_is_its_own_finding_and_no_simulation(capsys):
    """The binary exits inside fmi3SetTime: binary-crashed is printed (the runs' own finding)
    and nothing was simulated, for no reason a skipped rule or a static finding gives."""
    assert _main([str(variant("Robertson", defines=["DEFECT_EXIT_IN_CALL"])),
                  "--color", "never"]) == 1
    out, err = capsys.readouterr()
    assert out.startswith("\nerror[DAE701 binary-crashed]: ")
    assert err == "lsdae: nothing was simulated: no simulation ran\n"
