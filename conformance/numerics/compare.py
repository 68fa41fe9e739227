"""DAE mode against ODE mode: the same model integrated twice, compared at common output times.

Both runs are only accurate to their tolerance, so they agree only to a gap that shrinks with
rtol. Each difference is measured in units of the tolerance both runs were given,

    gap_i(t) = |dae_i(t) - ode_i(t)| / (rtol * max(|dae_i(t)|, |ode_i(t)|) + atol_i)

(``atol_i = atol_factor * rtol * nominal_i``, as the integrators use), and the rule compares the
largest gap with a factor from the catalogue: a few tolerance units of global error are normal
for a BDF method, a gap of hundreds means the two modes describe different trajectories.
Variables present in one mode only (a state of one mode only, an algebraic variable ODE mode
does not expose) and times one run did not reach are left out, and said so in the evidence.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .settings import Trajectory


@dataclass
class Comparison:
    """The largest gap per variable (in tolerance units) and where the worst one was."""

    compared_times: int
    variables: list[str]
    gaps: dict[str, float]
    worst: dict[str, Any] = field(default_factory=dict)
    left_out: list[str] = field(default_factory=list)

    @property
    def largest(self) -> float:
        return max(self.gaps.values(), default=0.0)


def compare(dae: Trajectory, ode: Trajectory) -> Comparison | None:
    """Gaps between two trajectories at their common output times (None: nothing in common)."""
    common_t, i_dae, i_ode = np.intersect1d(np.asarray(dae.times, dtype=float),
                                            np.asarray(ode.times, dtype=float),
                                            return_indices=True)
    names = [n for n in dae.names if n in ode.names]
    left_out = [n for n in dae.names if n not in ode.names] + [
        n for n in ode.names if n not in dae.names]
    if common_t.size == 0 or not names:
        return None
    gaps: dict[str, float] = {}
    worst: dict[str, Any] = {}
    worst_ratio = -1.0
    for name in names:
        a = dae.values[i_dae, dae.names.index(name)]
        b = ode.values[i_ode, ode.names.index(name)]
        atol = dae.atol[dae.names.index(name)]
        ok = np.isfinite(a) & np.isfinite(b)
        if not np.any(ok):
            left_out.append(name)
            continue
        tol = dae.rtol * np.maximum(np.abs(a), np.abs(b)) + atol
        ratio = np.where(ok, np.abs(a - b) / np.where(tol > 0, tol, np.inf), 0.0)
        k = int(np.argmax(ratio))
        gaps[name] = float(ratio[k])
        if ratio[k] > worst_ratio:
            worst_ratio = float(ratio[k])
            worst = {"variable": name, "t": float(common_t[k]), "dae": float(a[k]),
                     "ode": float(b[k]), "difference": float(abs(a[k] - b[k])),
                     "tolerance_unit": float(tol[k]), "gap": float(ratio[k])}
    return Comparison(int(common_t.size), [n for n in names if n in gaps], gaps, worst,
                      left_out)
