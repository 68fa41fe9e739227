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
    """Gaps between two trajectories at their common output times (None: nothing in common).
    One pass over a (times x variables) array: thousands of variables cost no more than a
    few array operations."""
    common_t, i_dae, i_ode = np.intersect1d(np.asarray(dae.times, dtype=float),
                                            np.asarray(ode.times, dtype=float),
                                            return_indices=True)
    dae_at = _positions(dae.names)
    ode_at = _positions(ode.names)
    names = [n for n in dae.names if n in ode_at]
    left_out = [n for n in dae.names if n not in ode_at] + [
        n for n in ode.names if n not in dae_at]
    if common_t.size == 0 or not names:
        return None
    cd = np.array([dae_at[n] for n in names], dtype=np.intp)
    co = np.array([ode_at[n] for n in names], dtype=np.intp)
    a = dae.values[np.ix_(i_dae, cd)]
    b = ode.values[np.ix_(i_ode, co)]
    atol = np.asarray(dae.atol, dtype=float)[cd]
    ok = np.isfinite(a) & np.isfinite(b)
    tol = dae.rtol * np.maximum(np.abs(a), np.abs(b)) + atol[None, :]
    with np.errstate(invalid="ignore", over="ignore"):
        ratio = np.where(ok, np.abs(a - b) / np.where(tol > 0, tol, np.inf), 0.0)
    at = np.argmax(ratio, axis=0)             # the first time of each variable's largest gap
    largest = ratio[at, np.arange(len(names))]
    compared = ok.any(axis=0)
    gaps: dict[str, float] = {}
    for c in range(len(names)):
        if compared[c]:
            gaps[names[c]] = float(largest[c])
        else:
            left_out.append(names[c])
    worst: dict[str, Any] = {}
    if compared.any():
        c = int(np.flatnonzero(compared)[np.argmax(largest[compared])])  # the first largest
        k = int(at[c])
        worst = {"variable": names[c], "t": float(common_t[k]), "dae": float(a[k, c]),
                 "ode": float(b[k, c]), "difference": float(abs(a[k, c] - b[k, c])),
                 "tolerance_unit": float(tol[k, c]), "gap": float(ratio[k, c])}
    return Comparison(int(common_t.size), [n for n in names if n in gaps], gaps, worst,
                      left_out)


def _positions(names: list[str]) -> dict[str, int]:
    """Each name's first column (``list.index`` for every name at once)."""
    out: dict[str, int] = {}
    for k, name in enumerate(names):
        out.setdefault(name, k)
    return out
