"""``lsdae simulate``: the CSV, the summary, exit codes and usage errors.

The subcommand is driven through its own ``add_parser``/``run`` (what conformance/cli.py
wires), so these tests do not depend on the wiring.
"""
from __future__ import annotations

import argparse
import csv

import pytest

from conformance.simulate_command import add_parser, run
from scenes.build import build_scene
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


def test_usage_errors(tmp_path, capsys):
    assert _main([str(tmp_path / "missing.fmu")]) == 2
    with pytest.raises(SystemExit) as bad:
        _main([str(tmp_path / "x.fmu"), "--output-times", "a,b"])
    assert bad.value.code == 2
    with pytest.raises(SystemExit):
        _main([str(tmp_path / "x.fmu"), "--rtol", "-1"])
    capsys.readouterr()
