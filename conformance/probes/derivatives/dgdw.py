"""Probes of dg/dw and of ODE against DAE mode (DAE745-DAE747), on the Jacobian survey.

* ``algebraic-jacobian-ill-conditioned`` / ``-singular``: the condition number of dg/dw at the
  sampling points, scaled by nominals, from the FMU's directional derivatives when the survey
  confirmed them (else finite differences, whose error bound then also counts as singular);
* ``ode-dae-inconsistent``: at the same (t, x, u), solve g = 0 for w by Newton with the FMU's
  dg/dw (if confirmed, else central differences) from the w that ODE mode gives, and compare
  the derivatives and outputs of both modes.

No verdict rests on derivatives the probes refuted (directional-derivative-mismatch): see
:func:`conformance.probes.instruments.entry_comparison.directional_verdict`. The Newton solve and
the comparison of both modes at one point are in :mod:`.ode_dae`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from ...report import causes
from ...report.findings import Violation, evidence
from ...numerics import numdiff
from ...numerics.conditioning import conditioning
from ..instruments.api import ODE_DAE_FAULT, ProbeContext, ProbeSkipped, noted
from ..instruments.entry_comparison import directional_options, directional_verdict, entry_floor
from ..instruments.jacobian import PointSurvey, Survey, point_evidence, surveyed
from .ode_dae import compare_modes, sparse_dgdw


@dataclass
class _Block:
    """dg/dw at one point, scaled (an ndarray up to ``dense_up_to`` rows, else a sparse CSC
    matrix); ``error`` the bound of its measurement error, scaled the same way, in the norm
    the block is judged in (Frobenius for 2-norm, max column sum for the 1-norm; 0 for the
    FMU's own, confirmed derivatives)."""

    ps: PointSurvey
    g: Any
    error: float
    source: str
    note: str


def _algebraic_blocks(ctx: ProbeContext, s: Survey, dense_up_to: int) -> Iterator[_Block]:
    """dg/dw at every point, scaled: columns by the algebraic variables' nominals, rows by the
    residuals' nominals when declared, else equilibrated (a residual's scale is arbitrary).
    From the FMU's directional derivatives only when the survey confirmed them, else from
    finite differences, with their error estimates (``margin`` times, as
    directional-derivative-mismatch counts them, and never below the entries' absolute floors)
    and a note why the FMU's were not used. Dense up to ``dense_up_to`` rows, else sparse: the
    measured entries only, nothing of size n x n."""
    layout = s.layout
    assert layout is not None
    res = layout.indices("residual", of="rows")
    alg = layout.indices("algebraic")
    if res.size == 0 or res.size != alg.size:
        return  # residual-count-mismatch (static) explains a non-square dg/dw
    n = res.size
    rpos = np.full(len(layout.rows), -1, dtype=np.intp)
    rpos[res] = np.arange(n)
    cpos = np.full(len(layout.cols), -1, dtype=np.intp)
    cpos[alg] = np.arange(n)
    use, note = directional_verdict(ctx, s)
    options = directional_options(ctx)
    source = "fmi3GetDirectionalDerivative" if use else "finite differences"
    col_nominal = layout.nominal[alg]
    row_nominal = np.array([layout.rows[i].nominal or 0.0 for i in res])
    for ps in s.points:
        e = ps.entries
        inside = (rpos[e.rows] >= 0) & (cpos[e.cols] >= 0)
        direct = use & ~np.isnan(e.dd)
        value = np.where(direct, e.dd, e.fd)[inside]
        if not np.all(np.isfinite(value)):
            continue  # nan-or-inf reports it
        bound = np.where(direct, 0.0, np.maximum(
            e.error(options["ulps"]) * options["margin"],
            entry_floor(layout, e, ulps=options["ulps"])))[inside]
        r, c = rpos[e.rows[inside]], cpos[e.cols[inside]]
        value, bound = value * col_nominal[c], bound * col_nominal[c]
        biggest = np.zeros(n)
        np.maximum.at(biggest, r, np.abs(value))
        divisor = np.where(row_nominal > 0, row_nominal, np.where(biggest > 0, biggest, 1.0))
        value, bound = value / divisor[r], bound / divisor[r]
        if n <= dense_up_to:
            g = np.zeros((n, n))
            g[r, c] = value
            error_matrix = np.zeros((n, n))
            error_matrix[r, c] = bound
            error = float(np.linalg.norm(np.nan_to_num(error_matrix, posinf=np.inf)))
        else:
            import scipy.sparse as sp  # scipy: only for a dg/dw too large for a dense SVD

            g = sp.csc_array((value, (r, c)), shape=(n, n))
            column_error = np.bincount(c, weights=np.nan_to_num(bound, posinf=np.inf),
                                       minlength=n)
            error = float(column_error.max(initial=0.0))
        yield _Block(ps, g, error, source, note)


def _algebraic_survey(ctx: ProbeContext) -> Survey:
    s = surveyed(ctx)
    assert s.layout is not None
    residuals = s.layout.indices("residual", of="rows").size
    algebraic = s.layout.indices("algebraic").size
    if residuals == 0 or residuals != algebraic:
        raise ProbeSkipped(f"dg/dw is {residuals} x {algebraic}: no square matrix to assess "
                           "(residual-count-mismatch reports a difference)")
    return s


@dataclass
class _Judged:
    """The condition of one block: the number, whether singular, the direction, the block."""

    block: _Block
    condition: float
    singular: bool
    direction: np.ndarray
    details: dict[str, Any]


def _condition(b: _Block, *, dense_up_to: int, seed: int) -> _Judged:
    """The condition number of the block, whether it is numerically singular, and the
    direction of near-singularity (which algebraic variables it involves). Singular: the
    smallest singular value is at most max(shape) * eps * largest (numpy's matrix_rank
    criterion), or at most ``error``, the bound of the measurement error of ``g`` (Weyl: a
    matrix that close to g may be singular). Above ``dense_up_to`` rows the same criterion in
    the 1-norm, from the sparse LU and the Hager-Higham estimate of the inverse's norm
    (numerics.conditioning), after the structural rank of the nonzeros (maximum matching): a
    pattern that cannot have full rank is singular whatever its values."""
    g, n = b.g, b.g.shape[0]
    if n > dense_up_to:
        import scipy.sparse as sp  # scipy: only for a dg/dw too large for a dense SVD

        from ...numerics.graphs.matching import maximum_matching  # scipy's csgraph: as above

        nonzero = sp.csr_array(g)
        nonzero.eliminate_zeros()   # stored: an edge (an entry measured as exactly 0 is none)
        matched = maximum_matching(nonzero)
        if matched.size < n:
            direction = np.zeros(n)
            direction[matched.col_to_row < 0] = 1.0
            return _Judged(b, np.inf, True, direction / np.linalg.norm(direction), {
                "method": "structural rank (maximum matching of the nonzeros)",
                "structural_rank": matched.size})
    found = conditioning(g, dense_up_to=dense_up_to, seed=seed)
    if found.largest == 0:
        return _Judged(b, np.inf, True, found.direction, _sparse_details(found))
    singular = found.smallest <= max(found.largest * n * numdiff.EPS, b.error)
    return _Judged(b, found.condition, bool(singular), found.direction, _sparse_details(found))


def _sparse_details(found: Any) -> dict[str, Any]:
    """What the evidence says about a sparse estimate (nothing for the dense SVD, whose
    evidence is as it always was)."""
    if found.norm == 2:
        return {}
    return {"method": found.method, "norm": "1-norm", "lu_nonzeros": found.factor_nonzeros}


def _worst_condition(ctx: ProbeContext, s: Survey, singular: bool, dense_up_to: int
                     ) -> _Judged | None:
    worst = None
    for b in _algebraic_blocks(ctx, s, dense_up_to):
        judged = _condition(b, dense_up_to=dense_up_to, seed=ctx.seed)
        if judged.singular == singular and (worst is None or
                                            judged.condition > worst.condition):
            worst = judged
    return worst


def _condition_violation(s: Survey, found: _Judged, message: str, **extra) -> Violation:
    layout = s.layout
    assert layout is not None
    b = found.block
    alg = layout.indices("algebraic")
    direction = found.direction
    order = np.argsort(-np.abs(direction))[:5]
    involved = [layout.cols[alg[k]].name for k in order if abs(direction[k]) > 1e-3]
    res = layout.indices("residual", of="rows")
    if b.source == "finite differences":
        extra["measurement_error"] = b.error
    if b.note:
        extra["note"] = b.note
    cond = found.condition
    return Violation(message, layout.rows[res[0]].location, evidence(
        condition_number=cond if np.isfinite(cond) else "inf", size=b.g.shape[0],
        source=b.source, scale="columns by the algebraic variables' nominal values, rows by "
        "the residuals' nominal values or else equilibrated", involved=involved,
        **found.details, **extra, point=point_evidence(layout, b.ps)),
        cause=tuple(causes.through(name) for name in involved) or None)


def algebraic_jacobian_ill_conditioned(ctx: ProbeContext, *, max_condition: float,
                                       dense_up_to: int) -> Iterator[Violation]:
    """The scaled dg/dw has a condition number above ``max_condition`` (but is not singular);
    a dense SVD up to ``dense_up_to`` algebraic variables, a sparse estimate above."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(ctx, s, False, dense_up_to)
    if found is not None and found.condition > max_condition:
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is ill-conditioned: an importer's Newton iteration loses accuracy",
            threshold=max_condition)


def algebraic_jacobian_singular(ctx: ProbeContext, *, dense_up_to: int
                                ) -> Iterator[Violation]:
    """The scaled dg/dw is numerically singular at a sampling point (DAE-51); a dense SVD up
    to ``dense_up_to`` algebraic variables, a sparse LU above."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(ctx, s, True, dense_up_to)
    if found is not None:
        n = found.block.g.shape[0]
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is singular: the DAE does not have index 1 here",
            threshold=f"smallest singular value <= {n} * eps * largest"
            + (" or <= the measurement error" if found.block.source == "finite differences"
               else ""))


# ------------------------------------------------------------------------- ODE against DAE

def ode_dae_inconsistent(ctx: ProbeContext, *, rtol: float, margin: float,
                         ulps: float, max_iterations: int, dense_up_to: int
                         ) -> Iterator[Violation]:
    """At the same (t, x, u), the derivatives and outputs of ODE mode equal those of DAE mode
    at the algebraic variables that solve the residuals (DAE-42). Newton's dg/dw is dense up
    to ``dense_up_to`` algebraic variables, coloured and sparse above."""
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
    sparse = sparse_dgdw(layout, res_i, alg_j) if alg_j.size > dense_up_to else None
    worst = None
    for ps in s.points:
        found = compare_modes(ctx, s, ps, res_i, cmp_i, alg_j, res, cmp, alg, rtol=rtol,
                              margin=margin, ulps=ulps, max_iterations=max_iterations,
                              sparse=sparse)
        if found is not None and (worst is None or found[0] > worst[0]):
            worst = found
    if worst is not None:
        yield Violation(
            "ODE mode and DAE mode disagree: at the same time, states and inputs, the "
            "derivatives or outputs of ODE mode differ from those of DAE mode at the algebraic "
            "variables that solve the residuals", layout.rows[res_i[0]].location,
            evidence(worst[1]), cause=_differing(worst[1]))


def _differing(found: dict) -> tuple[str, ...]:
    """The cause of a disagreement of the modes: each derivative or output that differs
    beyond its tolerance (the worst first); their partial derivatives and trajectories show
    the same formula."""
    ode, dae, tol = found["ode"], found["dae"], found["tolerance"]
    names = [found["worst"], *(n for n in ode if n != found["worst"] and n in dae and n in tol
                               and abs(dae[n] - ode[n]) > tol[n])]
    return tuple(causes.through(n) for n in names)


PROBES = {
    "DAE745": algebraic_jacobian_ill_conditioned,
    "DAE746": algebraic_jacobian_singular,
    "DAE747": noted(ODE_DAE_FAULT, "DAE747", ode_dae_inconsistent),
}
