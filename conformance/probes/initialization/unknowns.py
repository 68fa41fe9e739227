"""InitialUnknown probes (DAE750-DAE752): the dependencies of ``<InitialUnknown>`` in
Initialization Mode, measured on the binary.

They compare, each with the tolerances of its catalogue entry, the Jacobian of the initial
unknowns with respect to the knowns of Initialization Mode, measured once per FMU by
:func:`conformance.probes.initialization.survey.initial_survey` (fresh instances, the knowns set as
start values before fmi3EnterInitializationMode):

* ``initial-dependency-undeclared``: an entry the ``dependencies`` leave out that is clearly
  non-zero (MS-20, MS-11);
* ``initial-dependencies-kind-violated``: an entry declared ``constant`` whose finite difference
  changes between points (MS-31: the unknown is affine in that known);
* ``initial-directional-derivative-mismatch``: fmi3GetDirectionalDerivative in Initialization
  Mode against finite differences (PD-02, PD-03, PD-05, PD-06).

Each mode the FMU has is verified: DAE mode against the manifest's list, ODE mode against
modelDescription's (:mod:`.layout`); a finding names its mode. The comparisons are
those of the Continuous-Time Mode probes (``entry_comparison``): scaled by
the row scale ``S_i = sum_j |J_ij| * nominal_j``, a difference counts only above ``margin``
times the finite-difference error estimate plus ``rtol`` times the scale. A finding names the
InitialUnknown element (manifest or modelDescription, the list the instance follows) and its
line.
"""
from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace

import numpy as np

from ...report import causes
from ...report.findings import Violation, evidence
from ..instruments.api import ProbeContext, ProbeSkipped
from ..instruments.entry_comparison import (entry_violations, kind_changes, mismatched_entries,
                                            undeclared_entries)
from .survey import SETTINGS_FACT, InitialSurvey, SurveySettings, confirm, surveyed
from ..instruments.jacobian import PointSurvey, per_mode, point_evidence

__all__ = ["PROBES"]

MODES = {"dae": "DAE mode", "ode": "ODE mode"}


def _surveys(ctx: ProbeContext, *, min_points: int = 1) -> list[InitialSurvey]:
    return per_mode(ctx, lambda mode: surveyed(ctx, min_points=min_points, mode=mode))


def _where(s: InitialSurvey) -> dict:
    used = s.counter.used if s.counter is not None else s.instances   # confirmations too
    return {"element": "InitialUnknown", "file": s.file, "mode": MODES.get(s.mode, s.mode),
            "instances": used}


def _confirmed(s: InitialSurvey, ps: PointSurvey, i: int, j: int, *, factor: float,
               ulps: float) -> tuple[float, float] | None:
    """Entry (i, j) at ``ps`` measured again at ``factor`` times the step: (value, error)."""
    c = confirm(s, ps, j, factor=factor, ulps=ulps)
    if c is None or not (np.isfinite(c[0][i]) and np.isfinite(c[1][i])):
        return None
    return float(c[0][i]), float(c[1][i])


def _holds(before: float, after: float, tolerance: float, factor: float) -> bool:
    """A discrepancy found at the survey's step (``before``) still counts at ``factor`` times
    the step (``after``): above its tolerance there, and not shrunk as an error of the FMU's
    solver shrinks with a larger step (by ``factor``), only as truncation or chance do (by
    less than ``sqrt(factor)``). A real fault does not depend on the step."""
    return abs(after) > tolerance and abs(after) * math.sqrt(factor) >= abs(before)


def initial_dependency_undeclared(ctx: ProbeContext, *, rtol: float, margin: float,
                                  ulps: float, confirm_factor: float, points: int,
                                  max_instances: int, max_seconds: float
                                  ) -> Iterator[Violation]:
    """An initial unknown clearly depends on a known of Initialization Mode that its
    dependencies leave out (MS-11, MS-20), at the survey's step and at ``confirm_factor``
    times it. ``points``, ``max_instances`` and ``max_seconds`` set the survey the other
    InitialUnknown probes read too."""
    ctx.facts.setdefault(SETTINGS_FACT, SurveySettings(points, max_instances, max_seconds))
    for s in _surveys(ctx):
        yield from _undeclared(s, rtol=rtol, margin=margin, ulps=ulps,
                               confirm_factor=confirm_factor)


def _undeclared(s: InitialSurvey, *, rtol: float, margin: float, ulps: float,
                confirm_factor: float) -> Iterator[Violation]:
    layout = s.layout
    assert layout is not None
    worst = undeclared_entries(s, rtol=rtol, margin=margin, ulps=ulps)
    found = []   # all confirmed first: a time budget that ends a confirmation leaves no verdict
    for (i, j), w in sorted(worst.items()):
        row, col = layout.rows[i], layout.cols[j]
        again = _confirmed(s, w.ps, i, j, factor=confirm_factor, ulps=ulps)
        if again is None or not _holds(
                w.items["finite_difference"], again[0],
                margin * again[1] + rtol * w.items["row_scale"] / col.nominal, confirm_factor):
            continue
        w.items.update(confirmed_finite_difference=again[0], confirmed_error_estimate=again[1],
                       confirm_factor=confirm_factor)
        found.append(Violation(
            f"{{subject}} is clearly non-zero in Initialization Mode ({MODES.get(s.mode)}) but "
            f"the dependencies of <InitialUnknown> '{row.name}' do not list '{col.name}' "
            f"({_known_text(col.role)}): an importer that solves the initialisation from "
            "them gets it wrong", row.location,
            evidence(_where(s), entry=layout.entry(i, j), unknown=row.name, known=col.name,
                     known_value_reference=col.vr, known_role=col.role, **w.items,
                     point=point_evidence(layout, w.ps)),
            subject=layout.entry(i, j), part="dae-mode" if s.mode == "dae" else None,
            cause=causes.entry(layout.rows[i].name, layout.cols[j].name)))
    yield from found


def _known_text(role: str) -> str:
    return {"time": "the start time", "input": "an input", "parameter": "a parameter",
            "state": "a state's exact start value"}.get(role, "an exact start value")


def initial_dependencies_kind_violated(ctx: ProbeContext, *, rtol: float, margin: float,
                                       ulps: float, confirm_factor: float
                                       ) -> Iterator[Violation]:
    """An InitialUnknown entry declared ``constant`` whose partial derivative changes between
    points (MS-31), at the survey's step and at ``confirm_factor`` times it. Only ``constant``
    is a claim here: the other kinds are not allowed on an InitialUnknown, which the static
    rules report."""
    modes = []
    for s in _surveys(ctx):
        if any(k == "constant" and s.layout.rows[i].explicit
               for i, k in zip(s.layout.pattern.rows.tolist(), s.layout.kinds)):
            modes.append(s.mode)
    if not modes:
        return  # nothing declared constant: nothing to verify
    found, reasons = False, []
    for mode in modes:
        try:
            s = surveyed(ctx, min_points=2, mode=mode)
        except ProbeSkipped as exc:
            reasons.append(f"{MODES[mode]}: {exc}" if len(modes) > 1 else str(exc))
            continue
        found = True
        yield from _kind_violated(s, rtol=rtol, margin=margin, ulps=ulps,
                                  confirm_factor=confirm_factor)
    if not found:
        raise ProbeSkipped("; ".join(reasons))


def _kind_violated(s: InitialSurvey, *, rtol: float, margin: float, ulps: float,
                   confirm_factor: float) -> Iterator[Violation]:
    layout = s.layout
    assert layout is not None
    constant = {(i, j): k for i, j, k in zip(layout.pattern.rows.tolist(),
                                             layout.pattern.cols.tolist(), layout.kinds)
                if k == "constant" and layout.rows[i].explicit}
    if not constant:
        return  # nothing declared constant in this mode: nothing to verify
    found = []   # all confirmed first, as above
    for (i, j), c in kind_changes(s, constant, rtol=rtol, margin=margin, ulps=ulps).items():
        lo = _confirmed(s, c.lo[2], i, j, factor=confirm_factor, ulps=ulps)
        hi = _confirmed(s, c.hi[2], i, j, factor=confirm_factor, ulps=ulps)
        if lo is None or hi is None or not _holds(
                c.hi[0] - c.lo[0], hi[0] - lo[0], margin * (hi[1] + lo[1]) + rtol * c.scale,
                confirm_factor):
            continue
        found.append(Violation(
            f"{{subject}} is declared 'constant' by <InitialUnknown> '{layout.rows[i].name}' "
            f"but changes between points of Initialization Mode ({MODES.get(s.mode)}): the "
            "initial unknown is not affine in the known", layout.rows[i].location,
            evidence(_where(s), entry=layout.entry(i, j), kind=c.kind,
                     known_value_reference=layout.cols[j].vr, smallest=c.lo[0],
                     largest=c.hi[0], tolerance=c.tolerance,
                     confirmed=[lo[0], hi[0]], confirm_factor=confirm_factor,
                     points=[point_evidence(layout, c.lo[2]), point_evidence(layout, c.hi[2])]),
            subject=layout.entry(i, j),
            cause=causes.entry(layout.rows[i].name, layout.cols[j].name)))
    yield from found


def initial_directional_derivative_mismatch(ctx: ProbeContext, *, rtol: float, margin: float,
                                            ulps: float, confirm_factor: float
                                            ) -> Iterator[Violation]:
    """fmi3GetDirectionalDerivative in Initialization Mode, the initial unknowns as unknowns and
    the knowns of MS-11 as knowns, against finite differences at the survey's step and at
    ``confirm_factor`` times it (PD-02, PD-03, PD-06)."""
    me = ctx.model.model_exchange if ctx.model is not None else None
    if not (me and me.flag("providesDirectionalDerivatives")):
        raise ProbeSkipped("the FMU does not provide directional derivatives")
    ran, reasons = False, []
    for s in _surveys(ctx):
        try:
            found = list(_directional(s, rtol=rtol, margin=margin, ulps=ulps,
                                      confirm_factor=confirm_factor))
        except ProbeSkipped as exc:
            reasons.append(f"{MODES[s.mode]}: {exc}")
            continue
        ran = True
        yield from found
    if not ran:
        raise ProbeSkipped("; ".join(reasons))


def _directional(s: InitialSurvey, *, rtol: float, margin: float, ulps: float,
                 confirm_factor: float) -> Iterator[Violation]:
    if s.interference:
        raise ProbeSkipped(s.interference)
    for what, point, exc in s.failures:
        # Not a finding: where the initial problem is singular the derivative does not exist,
        # and the FMU may rightly refuse it (its residuals and dg/dw have rules of their own).
        if what == "directional":
            first = f": {exc.log[0]}" if exc.log else ""
            raise ProbeSkipped(f"fmi3GetDirectionalDerivative fails in Initialization Mode "
                               f"({exc.status} at point {point.label}{first}); nothing to "
                               "compare")
    layout = s.layout
    assert layout is not None
    worst = mismatched_entries(s, "dd", rtol=rtol, margin=margin, ulps=ulps)
    for (i, j), w in list(worst.items()):
        again = _confirmed(s, w.ps, i, j, factor=confirm_factor, ulps=ulps)
        if again is None or not _holds(
                w.items["fmu"] - w.items["finite_difference"], w.items["fmu"] - again[0],
                margin * again[1] + rtol * w.items["row_scale"] / layout.cols[j].nominal,
                confirm_factor):
            del worst[(i, j)]
            continue
        w.items.update(confirmed_finite_difference=again[0], confirmed_error_estimate=again[1],
                       confirm_factor=confirm_factor)
    for v in entry_violations(
            s, worst, "fmi3GetDirectionalDerivative in Initialization Mode "
            f"({MODES.get(s.mode)}) gives {{subject}} that finite differences of the initial "
            "unknowns do not confirm",
            place=f"fmi3GetDirectionalDerivative, Initialization Mode, {MODES.get(s.mode)}"):
        yield replace(v, evidence=evidence(_where(s), **dict(v.evidence)))


PROBES = {
    "DAE750": initial_dependency_undeclared,
    "DAE751": initial_dependencies_kind_violated,
    "DAE752": initial_directional_derivative_mismatch,
}
