"""``lsdae simulate``: the CSV, the summary, exit codes and usage errors.

The subcommand is driven through its own ``add_parser``/``run`` (what conformance/commands/cli.py
wires), so these tests do not depend on the wiring.
"""
from __future__ import annotations

import argparse
import csv
import shutil
import zipfile

import pytest

from conformance.commands.simulate import add_parser, run
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
