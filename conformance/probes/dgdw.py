"""Probes of dg/dw and of ODE against DAE mode (DAE745-DAE747), on the Jacobian survey.

* ``algebraic-jacobian-ill-conditioned`` / ``-singular``: the condition number of dg/dw at the
  sampling points, scaled by nominals, from the FMU's directional derivatives when the survey
  confirmed them (else finite differences, whose error bound then also counts as singular);
* ``ode-dae-inconsistent``: at the same (t, x, u), solve g = 0 for w by Newton with the FMU's
  dg/dw (if confirmed, else central differences) from the w that ODE mode gives, and compare
  the derivatives and outputs of both modes.

No verdict rests on derivatives the probes refuted (directional-derivative-mismatch): see
:func:`conformance.probes.entry_comparison.directional_verdict`. The Newton solve and the
comparison of both modes at one point are in :mod:`.ode_dae_comparison`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np

from ..report.findings import Violation, evidence
from ..numerics import numdiff
from .api import ODE_DAE_FAULT, ProbeContext, ProbeSkipped, noted
from .entry_comparison import directional_options, directional_verdict
from .jacobian import PointSurvey, Survey, point_evidence, surveyed
from .ode_dae_comparison import compare_modes


@dataclass
class _Block:
    """dg/dw at one point, scaled; ``error`` the 2-norm bound (Frobenius) of its measurement
    error, scaled the same way (0 for the FMU's own, confirmed derivatives)."""

    ps: PointSurvey
    g: np.ndarray
    error: float
    source: str
    note: str


def _algebraic_blocks(ctx: ProbeContext, s: Survey) -> Iterator[_Block]:
    """dg/dw at every point, scaled: columns by the algebraic variables' nominals, rows by the
    residuals' nominals when declared, else equilibrated (a residual's scale is arbitrary).
    From the FMU's directional derivatives only when the survey confirmed them, else from
    finite differences, with their error estimates (``margin`` times, as
    directional-derivative-mismatch counts them) and a note why the FMU's were not used."""
    layout = s.layout
    assert layout is not None
    res = layout.indices("residual", of="rows")
    alg = layout.indices("algebraic")
    if res.size == 0 or res.size != alg.size:
        return  # residual-count-mismatch (static) explains a non-square dg/dw
    rpos = {int(i): a for a, i in enumerate(res)}
    cpos = {int(j): a for a, j in enumerate(alg)}
    use, note = directional_verdict(ctx, s)
    options = directional_options(ctx)
    source = "fmi3GetDirectionalDerivative" if use else "finite differences"
    for ps in s.points:
        e = ps.entries
        err = e.error(options["ulps"]) * options["margin"]
        g = np.zeros((res.size, alg.size))
        bound = np.zeros((res.size, alg.size))
        for k, (i, j) in enumerate(zip(e.rows.tolist(), e.cols.tolist())):
            if i in rpos and j in cpos:
                direct = use and not np.isnan(e.dd[k])
                g[rpos[i], cpos[j]] = e.dd[k] if direct else e.fd[k]
                bound[rpos[i], cpos[j]] = 0.0 if direct else err[k]
        if not np.all(np.isfinite(g)):
            continue  # nan-or-inf reports it
        g = g * layout.nominal[alg][None, :]
        bound = bound * layout.nominal[alg][None, :]
        for a, i in enumerate(res):
            nominal = layout.rows[i].nominal
            biggest = np.abs(g[a]).max(initial=0.0)
            divisor = nominal if nominal else (biggest if biggest > 0 else 1.0)
            g[a], bound[a] = g[a] / divisor, bound[a] / divisor
        yield _Block(ps, g, float(np.linalg.norm(np.nan_to_num(bound, posinf=np.inf))),
                     source, note)


def _algebraic_survey(ctx: ProbeContext) -> Survey:
    s = surveyed(ctx)
    assert s.layout is not None
    residuals = s.layout.indices("residual", of="rows").size
    algebraic = s.layout.indices("algebraic").size
    if residuals == 0 or residuals != algebraic:
        raise ProbeSkipped(f"dg/dw is {residuals} x {algebraic}: no square matrix to assess "
                           "(residual-count-mismatch reports a difference)")
    return s


def _condition(g: np.ndarray, error: float = 0.0) -> tuple[float, bool, np.ndarray]:
    """2-norm condition number, whether numerically singular, and the direction of the
    smallest singular value (which algebraic variables the near-singularity involves).
    Singular: the smallest singular value is at most max(shape) * eps * largest (numpy's
    matrix_rank criterion), or at most ``error``, the 2-norm bound of the measurement error
    of ``g`` (Weyl: a matrix that close to g may be singular)."""
    if not np.all(np.isfinite(g)):
        return np.inf, True, np.zeros(g.shape[1])
    _, sv, vt = np.linalg.svd(g)
    if sv[0] == 0:
        return np.inf, True, vt[-1]
    singular = sv[-1] <= max(sv[0] * max(g.shape) * numdiff.EPS, error)
    return (float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf), bool(singular), vt[-1]


def _worst_condition(ctx: ProbeContext, s: Survey, singular: bool) -> tuple | None:
    worst = None
    for b in _algebraic_blocks(ctx, s):
        cond, is_singular, direction = _condition(b.g, b.error)
        if is_singular == singular and (worst is None or cond > worst[1]):
            worst = (b.ps, cond, direction, b.source, b.g.shape[0], b.note, b.error)
    return worst


def _condition_violation(s: Survey, found: tuple, message: str, **extra) -> Violation:
    layout = s.layout
    assert layout is not None
    ps, cond, direction, source, n, note, error = found
    alg = layout.indices("algebraic")
    order = np.argsort(-np.abs(direction))[:5]
    involved = [layout.cols[alg[k]].name for k in order if abs(direction[k]) > 1e-3]
    res = layout.indices("residual", of="rows")
    if source == "finite differences":
        extra["measurement_error"] = error
    if note:
        extra["note"] = note
    return Violation(message, layout.rows[res[0]].location, evidence(
        condition_number=cond if np.isfinite(cond) else "inf", size=n, source=source,
        scale="columns by the algebraic variables' nominal values, rows by the residuals' "
        "nominal values or else equilibrated", involved=involved, **extra,
        point=point_evidence(layout, ps)))


def algebraic_jacobian_ill_conditioned(ctx: ProbeContext, *, max_condition: float
                                       ) -> Iterator[Violation]:
    """The scaled dg/dw has a condition number above ``max_condition`` (but is not singular)."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(ctx, s, singular=False)
    if found is not None and found[1] > max_condition:
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is ill-conditioned: an importer's Newton iteration loses accuracy",
            threshold=max_condition)


def algebraic_jacobian_singular(ctx: ProbeContext) -> Iterator[Violation]:
    """The scaled dg/dw is numerically singular at a sampling point (DAE-51)."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(ctx, s, singular=True)
    if found is not None:
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is singular: the DAE does not have index 1 here",
            threshold=f"smallest singular value <= {found[4]} * eps * largest"
            + (" or <= the measurement error" if found[3] == "finite differences" else ""))


# ------------------------------------------------------------------------- ODE against DAE

def ode_dae_inconsistent(ctx: ProbeContext, *, rtol: float, margin: float,
                         ulps: float, max_iterations: int) -> Iterator[Violation]:
    """At the same (t, x, u), the derivatives and outputs of ODE mode equal those of DAE mode
    at the algebraic variables that solve the residuals (DAE-42)."""
    s = surveyed(ctx)
    if ctx.ode is None:
        failure = ctx.facts.get("ode_error")
        raise ProbeSkipped("ODE mode is not available" + (f": {failure}" if failure else ""))
    layout = s.layout
    assert layout is not None
    res_i = layout.indices("residual", of="rows")
    cmp_i = np.array([i for i, r in enumerate(layout.rows) if r.role != "residual"], dtype=np.intp)
    alg_j = layout.indices("algebraic")
    if res_i.size == 0 or alg_j.size == 0 or cmp_i.size == 0:
        raise ProbeSkipped("no residuals, algebraic variables, derivatives or outputs to compare")
    res = [layout.rows[i].vr for i in res_i]
    cmp = [layout.rows[i].vr for i in cmp_i]
    alg = [layout.cols[j].vr for j in alg_j]
    worst = None
    for ps in s.points:
        found = compare_modes(ctx, s, ps, res_i, cmp_i, alg_j, res, cmp, alg, rtol=rtol,
                              margin=margin, ulps=ulps, max_iterations=max_iterations)
        if found is not None and (worst is None or found[0] > worst[0]):
            worst = found
    if worst is not None:
        yield Violation(
            "ODE mode and DAE mode disagree: at the same time, states and inputs, the "
            "derivatives or outputs of ODE mode differ from those of DAE mode at the algebraic "
            "variables that solve the residuals", layout.rows[res_i[0]].location,
            evidence(worst[1]))


PROBES = {
    "DAE745": algebraic_jacobian_ill_conditioned,
    "DAE746": algebraic_jacobian_singular,
    "DAE747": noted(ODE_DAE_FAULT, "DAE747", ode_dae_inconsistent),
}
