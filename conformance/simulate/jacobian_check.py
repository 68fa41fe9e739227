"""Which Jacobian the integrators use: the FMU's directional derivatives only when confirmed.

No run rests on derivatives the probes refuted. Inside ``lsdae check`` the derivative probes'
survey has judged them already (``directional-derivative-mismatch``), and
:class:`DerivativeCheck` carries that verdict. Without one (``lsdae simulate`` runs the
simulation probes only) :func:`choose_jacobian` compares, at the initial point and before the
run, the FMU's coloured directional derivatives with central differences of the same
evaluations (:func:`conformance.numerics.measure.measure`, no random directions), entry by entry
as the probe does (:func:`conformance.numerics.measure.disagreement`). Refuted derivatives are
not used: coloured finite differences stand in, and the trajectory's ``jacobian`` says why.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..numerics import measure, numdiff
from ..numerics.limits import EvaluationFailed
from ..runtime.errors import FmiError


@dataclass(frozen=True)
class DerivativeCheck:
    """How the FMU's directional derivatives are judged before a run.

    ``rtol``, ``margin``, ``ulps``: the options of directional-derivative-mismatch (what
    "confirmed" means). ``verdict``: the probes' verdict when they judged them ("" confirmed,
    else why they were not used), None to check at the initial point.
    """

    rtol: float
    margin: float
    ulps: float
    verdict: str | None = None


def choose_jacobian(system: Any, t0: float, check: DerivativeCheck | None) -> Any:
    """``system`` (an FmuDae or FmuOde), switched to finite differences when its directional
    derivatives are refuted: by the probes' verdict, or by :func:`refuted_at` at ``t0`` and
    the values the instance holds. ``check`` None: the FMU's, unchecked (benchmarks)."""
    if check is None or not system.jac.use_directional:
        return system
    note = check.verdict
    if note is None:
        y0 = np.asarray(system.inst.get_float64(system.jac.cols), dtype=float)
        note = refuted_at(system, t0, y0, rtol=check.rtol, margin=check.margin,
                          ulps=check.ulps)
    if note:
        system.jac.refuse(note)
        system.jacobian_source = system.jac.source
    return system


def refuted_at(system: Any, t: float, y: np.ndarray, *, rtol: float, margin: float,
               ulps: float) -> str:
    """Why the FMU's coloured directional derivatives at ``(t, y)`` may not be used ("" when
    finite differences confirm every entry the colouring gives): an entry whose difference
    exceeds ``margin`` times the finite-difference error estimate plus ``rtol`` times its
    row's scale, or a directional-derivative call that fails. A point where the FMU cannot
    be evaluated decides nothing (the run reports that)."""
    jac = system.jac

    def fun(delta: np.ndarray) -> np.ndarray:
        return np.asarray(system.evaluate(t, y + delta), dtype=float)

    def product(seed: np.ndarray) -> np.ndarray:
        system.evaluate(t, y)   # (t, y) set again after the differences (cached when set)
        return np.asarray(jac.product(seed), dtype=float)

    steps = numdiff.step_sizes(y, jac.nominal, method="central")
    try:
        e = measure.measure(measure.Sources(fun, product), jac.pattern, jac.colouring, steps, y,
                            np.random.default_rng(0), method="central", directions=0)
    except EvaluationFailed:
        return ""
    except FmiError as exc:
        return (f"the FMU's directional derivatives were not used: {exc.call} returned "
                f"{exc.status} at the initial point")
    m = len(jac.rows)
    row_nominal = np.array([system.layout.scale(vr) for vr in jac.rows], dtype=float)
    diff, tol, _, _ = measure.disagreement(e, e.dd, jac.nominal, m, rtol=rtol, margin=margin,
                                           ulps=ulps, row_nominal=row_nominal)
    bad = np.isfinite(e.dd) & np.isfinite(e.fd) & (diff > tol)
    if not bad.any():
        return ""
    k = int(np.argmax(np.where(bad, diff / np.maximum(tol, np.finfo(float).tiny), -np.inf)))
    name = system.layout.name
    worst = f"d({name(jac.rows[e.rows[k]])})/d({name(jac.cols[e.cols[k]])})"
    return (f"the FMU's directional derivatives were not used: finite differences refute "
            f"{int(bad.sum())} of their entries at the initial point, worst {worst} "
            f"({e.dd[k]:.6g} against {e.fd[k]:.6g})")
