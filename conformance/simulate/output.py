"""The trajectory as CSV: a ``time`` column, then one column per state and algebraic variable,
named as in modelDescription.xml (quoted by the csv module when a name needs it).

Values are written with 17 significant digits (a float64 round-trips); a value that could not
be read (an algebraic variable ODE mode does not expose) is an empty field.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from ..numerics.settings import Trajectory


def to_csv(traj: Trajectory) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["time", *traj.names])
    for t, row in zip(traj.times, traj.values):
        writer.writerow([_number(t), *(_number(v) for v in row)])
    return out.getvalue()


def write_csv(traj: Trajectory, path: Path | str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(to_csv(traj), encoding="utf-8")


def _number(value: float) -> str:
    value = float(value)
    return repr(float(value)) if math.isfinite(value) else ""  # shortest exact round trip
