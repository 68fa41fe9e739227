"""Derivative probes (DAE740-DAE744): the FMU's partial derivatives and its dependencies.

They compare, each with the tolerances of its catalogue entry, the Jacobian measured once per
FMU and mode by :func:`conformance.probes.instruments.jacobian.survey`, in every mode the FMU has:
DAE mode against the manifest's ``<ModelStructure>``, ODE mode (the switch off, or an ordinary Model
Exchange FMU) against modelDescription's. One rule is one promise, whatever the mode: each
finding names its mode in the message and the evidence.

* ``directional-derivative-mismatch`` / ``adjoint-derivative-mismatch``: the FMU's entries
  against finite differences, and the dot-product test v(Js) = (vJ)s;
* ``dependency-undeclared`` / ``dependency-never-observed``: observed against declared
  sparsity (and fmi3GetVariableDependencies against the manifest, when the FMU provides it);
  ``dependencies-kind-violated``: a non-``dependent`` entry that changes.

dg/dw and ODE against DAE (DAE745-DAE747) are in :mod:`conformance.probes.derivatives.dgdw`, a
family of its own that reads the same survey.

Every comparison is scaled: an entry ``J_ij`` is compared in units of the row's scale
``S_i = sum_j |J_ij| * nominal_j`` (how much the unknown moves when each known moves by its
nominal), and a difference counts only when it exceeds ``margin`` times the finite-difference
error estimate (:mod:`conformance.numerics.numdiff`) plus ``rtol * S_i / nominal_j``.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any, Iterator

import numpy as np

from ...numerics.intsets import isin_ints, unique_ints
from ...report import causes
from ...report.findings import Violation, evidence
from ..instruments.api import FmiError, ProbeContext, ProbeSkipped
from ..instruments.entry_comparison import (OPTIONS_FACT, call_failures, closest_entries,
                                            entry_errors, entry_violations, kind_changes,
                                            mismatched_entries, undeclared_entries)
from ..instruments.jacobian import (FACT, MODE_NAMES, JacobianLayout, Settings, Survey, base_point,
                                    build_layout, in_mode, per_mode, point_evidence, record_errors,
                                    run_survey, survey, surveyed)

__all__ = ["FACT", "PROBES", "JacobianLayout", "Settings", "Survey", "build_layout",
           "run_survey", "survey"]

log = logging.getLogger(__name__)


# -------------------------------------------------------------------------------- the modes

def _surveys(ctx: ProbeContext, *, min_points: int = 1) -> list[Survey]:
    return per_mode(ctx, lambda mode: surveyed(ctx, min_points=min_points, mode=mode))


# ------------------------------------------------------------------------------- the probes

def _against_fd(ctx: ProbeContext, s: Survey, which: str, code: str, *, rtol: float,
                margin: float, ulps: float,
                part: str | None = None) -> tuple[list[Violation], dict]:
    """The steps both derivative probes share: the FMU's refusals, the entries finite
    differences do not confirm (recorded for the report's error plot), and their findings.
    ``part``: the catalogue part of the unconfirmed entries (the caller's, by mode); a refusal
    (only ever reported in DAE mode: ODE mode skips) is the part ``refused-in-dae-mode``."""
    call, fmi = _CALLS[which]
    refused = next(((point, exc) for flag, point, exc in s.failures
                    if flag == call and exc.after is None), None)
    if refused is not None and s.mode == "ode":
        # ODE mode gives total derivatives through the FMU's own solve of its algebraic
        # equations: where that solve is singular they do not exist, and the FMU may rightly
        # refuse them (as in Initialization Mode, initial-directional-derivative-mismatch)
        point, exc = refused
        first = f": {exc.log[0]}" if exc.log else ""
        raise ProbeSkipped(f"{fmi} returns {exc.status} in ODE mode at point {point.label}"
                           f"{first}; a total derivative may not exist where the FMU solves its "
                           "own algebraic equations, so nothing is compared")
    failures = [replace(v, part="refused-in-dae-mode") for v in call_failures(s, call)]
    if not getattr(s, call) and not failures:
        raise ProbeSkipped(f"the FMU does not provide {call} derivatives")
    worst = mismatched_entries(s, which, rtol=rtol, margin=margin, ulps=ulps)
    if which == "adj":
        worst = _single_entry_adjoint(ctx, s, worst)
    errors = (entry_errors(worst, s.layout)
              or closest_entries(s, which, rtol=rtol, margin=margin, ulps=ulps))
    record_errors(ctx, code, errors if s.mode == "dae" else
                  [(f"{entry} [{MODE_NAMES[s.mode]}]", err, tol) for entry, err, tol in errors])
    found = [replace(v, part=part) for v in entry_violations(
        s, worst, f"{fmi} gives {{subject}} that finite differences of the function do not "
        "confirm", place=f"{fmi}, {MODE_NAMES[s.mode]}")]
    return failures + found, worst


_CALLS = {"dd": ("directional", "fmi3GetDirectionalDerivative"),
          "adj": ("adjoint", "fmi3GetAdjointDerivative")}


def _single_entry_adjoint(ctx: ProbeContext, s: Survey, worst: dict) -> dict:
    """Each adjoint mismatch confirmed on its row and column alone, at its worst point:
    fmi3GetAdjointDerivative with the row's unknown seeded and the column's known the only
    known. The survey's adjoint calls seed groups of rows that share no *declared* column, so a
    dependency the manifest leaves out leaks into another row's entry of the same column
    (dependency-undeclared's finding): only what the single-entry call confirms is reported.
    An entry the call cannot check (refused, point not settable) is kept as measured."""
    layout = s.layout
    assert layout is not None
    kept = {}
    ev = getattr(ctx, s.mode)
    for (i, j), w in worst.items():
        try:
            value = float(ev.adjoint(  # type: ignore[union-attr]
                base_point(layout, w.ps), [layout.rows[i].vr], [layout.cols[j].vr],
                np.ones(1))[0])
        except (FmiError, ProbeSkipped):
            kept[(i, j)] = w
            continue
        if not np.isfinite(value) or abs(value - w.items["finite_difference"]) > \
                w.items["tolerance"]:
            w.items.update(fmu=value, confirmed="single-entry adjoint call (row seeded, "
                                                "column read)")
            kept[(i, j)] = w
    return kept


def directional_derivative_mismatch(ctx: ProbeContext, *, rtol: float,
                                    margin: float, ulps: float) -> Iterator[Violation]:
    """fmi3GetDirectionalDerivative against finite differences of the function (DAE-50)."""
    ctx.facts[OPTIONS_FACT] = {"rtol": rtol, "margin": margin, "ulps": ulps}  # "confirmed"
    surveys, reasons = [], []
    for s in _surveys(ctx):
        try:
            found, _ = _against_fd(ctx, s, "dd", "DAE740", rtol=rtol, margin=margin, ulps=ulps,
                                   part="dae-mode" if s.mode == "dae" else None)
        except ProbeSkipped as exc:
            reasons.append(str(exc))
            continue
        surveys.append(s)
        yield from in_mode(found, s)
    if not surveys:
        raise ProbeSkipped(reasons[0])


def adjoint_derivative_mismatch(ctx: ProbeContext, *, rtol: float, margin: float,
                                ulps: float, dot_rtol: float) -> Iterator[Violation]:
    """fmi3GetAdjointDerivative against finite differences, and the dot-product test
    v(Js) = (vJ)s against the directional derivative (PD-06, DAE-50)."""
    ran, reasons = 0, []
    for s in _surveys(ctx):
        try:
            found = list(_adjoint(ctx, s, rtol=rtol, margin=margin, ulps=ulps,
                                  dot_rtol=dot_rtol))
        except ProbeSkipped as exc:
            reasons.append(str(exc))
            continue
        ran += 1
        yield from in_mode(found, s)
    if not ran:
        raise ProbeSkipped(reasons[0])


def _adjoint(ctx: ProbeContext, s: Survey, *, rtol: float, margin: float, ulps: float,
             dot_rtol: float) -> Iterator[Violation]:
    found, worst = _against_fd(ctx, s, "adj", "DAE741", rtol=rtol, margin=margin, ulps=ulps)
    yield from found
    if worst:
        return
    # judged with this rule's tolerances: a probe sees only its own options
    directional_ok = not mismatched_entries(s, "dd", rtol=rtol, margin=margin, ulps=ulps)
    for ps in s.points:
        if ps.entries.dot is None or not directional_ok:
            continue
        a, b, size = ps.entries.dot
        if np.isfinite(size) and abs(a - b) > dot_rtol * size:
            yield Violation(
                "the adjoint derivative is not the transpose of the directional derivative: "
                "v·(J s) differs from (vᵀJ)·s", s.layout.rows[0].location,
                evidence(directional=a, adjoint=b, difference=abs(a - b),
                         tolerance=dot_rtol * size, scale="|v|·|J|·|s|",
                         point=point_evidence(s.layout, ps)))
            return


def dependency_undeclared(ctx: ProbeContext, *, rtol: float, margin: float,
                          ulps: float) -> Iterator[Violation]:
    """A partial derivative clearly non-zero for a known the dependencies leave out (MS-20)."""
    for s in _surveys(ctx):
        yield from in_mode(_undeclared(ctx, s, rtol=rtol, margin=margin, ulps=ulps), s)


def _undeclared(ctx: ProbeContext, s: Survey, *, rtol: float, margin: float,
                ulps: float) -> Iterator[Violation]:
    layout = s.layout
    assert layout is not None
    worst = undeclared_entries(s, rtol=rtol, margin=margin, ulps=ulps)
    suffix = "" if s.mode == "dae" else f" [{MODE_NAMES[s.mode]}]"
    record_errors(ctx, "DAE742", [(layout.entry(i, j) + suffix,
                                   abs(w.items["finite_difference"]), w.items["tolerance"])
                                  for (i, j), w in worst.items()])
    for (i, j), w in sorted(worst.items()):
        residual = s.mode == "dae" and layout.rows[i].role == "residual"
        yield Violation(
            "{subject} is clearly non-zero but the dependencies of the unknown do not list the "
            "known: an importer that colours its Jacobian from them gets it wrong",
            layout.rows[i].location, evidence(
                entry=layout.entry(i, j), unknown=layout.rows[i].name,
                known=layout.cols[j].name, known_value_reference=layout.cols[j].vr, **w.items,
                point=point_evidence(layout, w.ps)), subject=layout.entry(i, j),
            part="residual-dependencies" if residual else None,
            cause=causes.entry(layout.rows[i].name, layout.cols[j].name))
    if s.mode == "dae":
        yield from _reported_dependencies(ctx, layout, s.mode,
                                          part="reported-dependencies-dae-mode")
    else:
        yield from _reported_dependencies(ctx, layout, s.mode, part="reported-dependencies")


def _reported_dependencies(ctx: ProbeContext, layout: JacobianLayout, mode: str, *,
                           part: str) -> Iterator[Violation]:
    """fmi3GetVariableDependencies against the XML of the mode, when the FMU offers it
    (``part``: the catalogue part, which depends on the mode)."""
    me = ctx.model.model_exchange if ctx.model is not None else None
    reader = getattr(getattr(ctx, mode), "variable_dependencies", None)
    xml = "manifest" if mode == "dae" else "modelDescription.xml"
    if not (me and me.flag("providesPerElementDependencies") and callable(reader)):
        return
    knowns = {c.vr: c for c in layout.cols}
    for i, r in enumerate(layout.rows):
        if not r.explicit:
            continue
        try:
            reported = {int(vr) for vr, *_ in reader(r.vr)}
        except FmiError:
            return
        listed = {layout.cols[j].vr for j in layout.pattern.row(i).tolist()}
        for vr in sorted({vr for vr in reported if vr in knowns} - listed):
            entry = f"d({layout.rows[i].name})/d({knowns[vr].name})"
            yield Violation(
                f"fmi3GetVariableDependencies reports {{subject}} but the {xml} dependencies "
                "leave it out", layout.rows[i].location,
                evidence(entry=entry, known_value_reference=vr,
                         source="fmi3GetVariableDependencies"),
                subject=entry, part=part)


def dependency_never_observed(ctx: ProbeContext, *, min_points: int) -> Iterator[Violation]:
    """A declared dependency whose function never moved at any sampling point.

    In ODE mode an unknown that DAE mode says depends on a known only through the algebraic
    variables is a total derivative through the FMU's own solve of its algebraic equations:
    it shrinks along each link of a chain of them and may be too small to resolve at all (the
    Chain scene's d(der(x))/d(u) at N = 300 is below the smallest double), so not seeing it
    move says nothing and is not reported."""
    surveys = _surveys(ctx, min_points=min_points)
    direct = next((_pair_keys(s.layout) for s in surveys if s.mode == "dae"), None)
    for s in surveys:
        yield from in_mode(_never_observed(s, direct if s.mode == "ode" else None), s)


def _pair_keys(layout: Any) -> np.ndarray:
    """The key of each declared entry of ``layout``, (unknown's value reference, known's value
    reference) as one int64: the unknown's times 2**32 plus the known's (value references are
    32-bit)."""
    p = layout.pattern
    row_vrs = np.array([r.vr for r in layout.rows], dtype=np.int64)
    col_vrs = np.array([c.vr for c in layout.cols], dtype=np.int64)
    return (row_vrs[p.rows] << 32) | col_vrs[p.cols]


def _never_observed(s: Survey, direct: np.ndarray | None) -> Iterator[Violation]:
    """``direct``: in ODE mode, DAE mode's declared entries (:func:`_pair_keys`); an
    ODE-mode entry that is not one of them goes through the algebraic variables and is not
    judged."""
    layout = s.layout
    assert layout is not None
    n = len(layout.cols)
    explicit = np.array([r.explicit for r in layout.rows], dtype=bool)
    through_w = np.empty(0, dtype=np.int64)    # entries i * n + j, sorted
    if direct is not None:
        p = layout.pattern
        through = ~isin_ints(_pair_keys(layout), direct)
        through_w = unique_ints(p.rows[through].astype(np.int64) * n + p.cols[through])
    keys, moved = [], []
    for ps in s.points:
        e = ps.entries
        claim = e.declared & explicit[e.rows]
        entry = e.rows.astype(np.int64) * n + e.cols
        if through_w.size:
            claim &= ~isin_ints(entry, through_w)
        keys.append(entry[claim])
        moved.append(~e.zero[claim])
    if not keys:
        return
    unique, at = np.unique(np.concatenate(keys), return_inverse=True)   # sorted by (i, j)
    ever = np.zeros(unique.size, dtype=bool)
    np.logical_or.at(ever, at, np.concatenate(moved))   # moved at some point
    for k in unique[~ever].tolist():
        i, j = divmod(k, n)
        yield Violation(
            "the dependencies list {subject} but the unknown did not change at all when the "
            "known was perturbed, at any sampling point", layout.rows[i].location,
            evidence(entry=layout.entry(i, j), points=len(s.points)),
            subject=layout.entry(i, j),
            part="time-listed" if layout.cols[j].role == "time" else None)


def dependencies_kind_violated(ctx: ProbeContext, *, rtol: float, margin: float,
                               ulps: float) -> Iterator[Violation]:
    """A ``constant``/``fixed``/``tunable``/``discrete`` entry whose partial derivative changes
    between sampling points (MS-31: such an unknown is affine in that known)."""
    for s in _surveys(ctx, min_points=2):
        yield from in_mode(_kind_violated(s, rtol=rtol, margin=margin, ulps=ulps), s)


def _kind_violated(s: Survey, *, rtol: float, margin: float,
                   ulps: float) -> Iterator[Violation]:
    layout = s.layout
    assert layout is not None
    explicit = [r.explicit for r in layout.rows]
    kind_of = {(i, j): kind for i, j, kind in zip(layout.pattern.rows.tolist(),
                                                  layout.pattern.cols.tolist(), layout.kinds)
               if kind != "dependent" and explicit[i]}
    for (i, j), c in kind_changes(s, kind_of, rtol=rtol, margin=margin, ulps=ulps).items():
        yield Violation(
            f"{{subject}}: declared '{c.kind}', but the partial derivative changes between "
            "sampling points (the unknown is not affine in the known)", layout.rows[i].location,
            evidence(entry=layout.entry(i, j), kind=c.kind, known_value_reference=layout.cols[j].vr,
                     smallest=c.lo[0],
                     largest=c.hi[0], tolerance=c.tolerance,
                     points=[point_evidence(layout, c.lo[2]), point_evidence(layout, c.hi[2])]),
            subject=layout.entry(i, j),
            cause=causes.entry(layout.rows[i].name, layout.cols[j].name))


PROBES = {
    "DAE740": directional_derivative_mismatch,
    "DAE741": adjoint_derivative_mismatch,
    "DAE742": dependency_undeclared,
    "DAE743": dependency_never_observed,
    "DAE744": dependencies_kind_violated,
}
