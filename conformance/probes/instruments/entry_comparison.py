"""Comparing the FMU's derivative entries with finite differences, for the derivative probes.

Each entry ``J_ij`` is compared in units of the row's scale ``S_i = sum_j |J_ij| * nominal_j``;
a difference counts only when it exceeds ``margin`` times the finite-difference error estimate
plus ``rtol * S_i / nominal_j``, and never below the absolute floor of the entry
(:func:`conformance.numerics.measure.floor`: ``TINY / h_j``, and where the row's finite
differences are all zero or underflow ``ulps * eps * nominal_i / h_j``, since nothing was
resolved below that). The tolerances are the calling rule's catalogue options.

:func:`directional_verdict` says whether the FMU's directional derivatives may be used by
other verdicts (dg/dw) and by the simulation: only when the survey confirmed them, judged with
the options of ``directional-derivative-mismatch``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Mapping

import numpy as np

from ...report.catalogue import default_catalogue
from ...report import causes
from ...report.findings import Violation, evidence
from ...numerics import measure
from ...numerics.intsets import isin_ints
from .api import PLANNED_OPTIONS, ProbeContext
from .jacobian import PointSurvey, Survey, point_evidence, row_scale
from .jacobian_layout import JacobianLayout


@dataclass
class Worst:
    """The worst point of one entry: the excess ratio and what to show as evidence."""

    ratio: float
    ps: PointSurvey
    items: dict



def keep_worst(worst: dict, key, ratio: float, ps: PointSurvey, items: dict) -> None:
    if key not in worst or ratio > worst[key].ratio:
        worst[key] = Worst(ratio, ps, items)


def compared_entries(layout: JacobianLayout, e, which: str, *, rtol: float, margin: float,
                     ulps: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The FMU's values, |FMU - FD|, the tolerance, the FD error estimate and the scale of
    every measured entry at one point (each of shape (nnz,))."""
    fmu = e.dd if which == "dd" else e.adj
    diff, tol, err, scale = measure.disagreement(e, fmu, layout.nominal, len(layout.rows),
                                                 rtol=rtol, margin=margin, ulps=ulps,
                                                 row_nominal=layout.row_nominal)
    return fmu, diff, tol, err, scale


def entry_floor(layout: JacobianLayout, e, *, ulps: float) -> np.ndarray:
    """The absolute floor of every entry at one point (units of ``fd``), shape (k,)."""
    return measure.floor(e, len(layout.rows), ulps=ulps, row_nominal=layout.row_nominal)


def closest_entries(s: Survey, which: str, *, rtol: float, margin: float, ulps: float,
                    limit: int = 20) -> list[tuple[str, float, float]]:
    """The entries that came closest to their tolerance (the report plots error against
    tolerance for passing checks too): (entry, |FMU - FD|, tolerance), worst first."""
    layout = s.layout
    assert layout is not None
    n = len(layout.cols)
    parts: list[tuple[np.ndarray, ...]] = []
    for ps in s.points:
        e = ps.entries
        if (e.dd if which == "dd" else e.adj) is None:
            continue
        _, diff, tol, _, _ = compared_entries(layout, e, which, rtol=rtol, margin=margin,
                                              ulps=ulps)
        ok = np.isfinite(diff) & (tol > 0)
        parts.append((e.rows[ok].astype(np.int64) * n + e.cols[ok], diff[ok] / tol[ok],
                      diff[ok], tol[ok]))
    if not parts:
        return []
    key, ratio, diff, tol = (np.concatenate(column) for column in zip(*parts))
    if not key.size:
        return []
    order = np.arange(key.size)   # points in turn, entries in order: first seen first
    # each entry at its worst point (the first of equal ratios), ranked worst first, entries
    # of equal ratio in the order they were first seen
    by_key = np.lexsort((order, -ratio, key))
    first = by_key[np.r_[True, key[by_key][1:] != key[by_key][:-1]]]
    _, seen = np.unique(key, return_index=True)   # sorted by key, as ``first`` is
    ranked = first[np.lexsort((seen, -ratio[first]))][:limit]
    return [(layout.entry(int(key[k] // n), int(key[k] % n)), float(diff[k]), float(tol[k]))
            for k in ranked]


def mismatched_entries(s: Survey, which: str, *, rtol: float, margin: float, ulps: float) -> dict:
    """Entries where the FMU's value (``dd`` or ``adj``) and the finite difference disagree."""
    layout = s.layout
    assert layout is not None
    worst: dict[tuple[int, int], Worst] = {}
    for ps in s.points:
        e = ps.entries
        fmu, diff, tol, err, scale = compared_entries(layout, e, which, rtol=rtol, margin=margin,
                                               ulps=ulps)
        # non-finite: nan-or-inf. An adjoint as wrong as the directional derivative is a finding
        # of its own: an importer may call only one of the two functions.
        bad = np.isfinite(fmu) & np.isfinite(e.fd) & (diff > tol)
        floor = entry_floor(layout, e, ulps=ulps) if bad.any() else None
        for k in np.flatnonzero(bad):
            items = {"fmu": float(fmu[k]), "finite_difference": float(e.fd[k]),
                     "error_estimate": float(err[k]), "tolerance": float(tol[k]),
                     "row_scale": float(scale[k] * layout.nominal[e.cols[k]]),
                     "declared": bool(e.declared[k])}
            _note_floor(items, floor[k], margin * err[k] + rtol * scale[k])  # type: ignore
            keep_worst(worst, (int(e.rows[k]), int(e.cols[k])),
                       float(diff[k] / tol[k]) if tol[k] > 0 else np.inf, ps, items)
    return worst


def _note_floor(items: dict, floor: float, scaled: float) -> None:
    """Say in the evidence when the absolute floor, not the scaled tolerance, decided."""
    if floor > scaled:
        items["tolerance_floor"] = float(floor)


def undeclared_entries(s: Survey, *, rtol: float, margin: float, ulps: float) -> dict:
    """Entries the dependencies leave out that are clearly non-zero at some point, in rows that
    make a claim (an explicit dependencies list): ``|fd| * nominal_j`` above ``margin`` times
    its error estimate (times ``nominal_j``) plus ``rtol`` times the row scale of the declared
    entries. The worst point of each, with its evidence items."""
    layout = s.layout
    assert layout is not None
    worst: dict[tuple[int, int], Worst] = {}
    for ps in s.points:
        e = ps.entries
        scale = row_scale(layout, e, declared_only=True)[e.rows]
        nominal = layout.nominal[e.cols]
        err = e.error(ulps)
        size = np.abs(e.fd) * nominal
        scaled = margin * err * nominal + rtol * scale
        floor = entry_floor(layout, e, ulps=ulps) * nominal
        tol = np.maximum(scaled, floor)
        clear = ~e.declared & ~e.zero & np.isfinite(size) & (size > tol)
        for k in np.flatnonzero(clear):
            if not layout.rows[e.rows[k]].explicit:
                continue
            items = {"finite_difference": float(e.fd[k]), "error_estimate": float(err[k]),
                     "tolerance": float(tol[k] / nominal[k]), "row_scale": float(scale[k])}
            _note_floor(items, floor[k] / nominal[k], scaled[k] / nominal[k])
            keep_worst(worst, (int(e.rows[k]), int(e.cols[k])),
                       float(size[k] / tol[k]) if tol[k] > 0 else np.inf, ps, items)
    return worst


@dataclass
class KindChange:
    """A declared entry that is not 'dependent' but changed between points: the smallest and
    largest finite difference (value, error estimate, point) and the tolerance."""

    kind: str
    lo: tuple[float, float, PointSurvey]
    hi: tuple[float, float, PointSurvey]
    tolerance: float
    scale: float        # the largest row scale S_i / nominal_j over the points (rtol's unit)


def kind_changes(s: Survey, kinds: Mapping[tuple[int, int], str], *, rtol: float,
                 margin: float, ulps: float) -> dict[tuple[int, int], KindChange]:
    """The entries of ``kinds`` (declared, not 'dependent') whose finite differences differ
    between the points by more than ``margin`` times their two error estimates plus ``rtol``
    times the largest row scale over ``nominal_j`` (never less than the larger of the two
    entries' absolute floors): the unknown is not affine in the known."""
    layout = s.layout
    assert layout is not None
    n = len(layout.cols)
    wanted = np.array(sorted(i * n + j for i, j in kinds), dtype=np.int64)
    parts: list[tuple[np.ndarray, ...]] = []
    for p, ps in enumerate(s.points):
        e = ps.entries
        key = e.rows.astype(np.int64) * n + e.cols
        use = isin_ints(key, wanted) & e.declared & np.isfinite(e.fd)
        scale = row_scale(layout, e)[e.rows[use]] / layout.nominal[e.cols[use]]
        parts.append((key[use], e.fd[use], e.error(ulps)[use], scale,
                      np.full(int(use.sum()), p), entry_floor(layout, e, ulps=ulps)[use]))
    out: dict[tuple[int, int], KindChange] = {}
    if not parts:
        return out
    key, fd, err, scale, point, floor = (np.concatenate(column) for column in zip(*parts))
    if not key.size:
        return out
    order = np.arange(key.size)     # the points in turn: the first of equal values wins
    hi = _first_per_key(key, -fd, order)
    lo = _first_per_key(key, fd, order)
    keys = key[hi]
    largest = np.maximum.reduceat(scale[np.argsort(key, kind="stable")],
                                  np.r_[0, np.flatnonzero(np.diff(np.sort(key))) + 1])
    tol = np.maximum(margin * (err[hi] + err[lo]) + rtol * largest,
                     np.maximum(floor[hi], floor[lo]))
    for a in np.flatnonzero(fd[hi] - fd[lo] > tol):
        i, j = divmod(int(keys[a]), n)
        h, lw = hi[a], lo[a]
        out[(i, j)] = KindChange(
            kinds[(i, j)], (float(fd[lw]), float(err[lw]), s.points[point[lw]]),
            (float(fd[h]), float(err[h]), s.points[point[h]]), float(tol[a]),
            float(largest[a]))
    return out


def _first_per_key(key: np.ndarray, value: np.ndarray, order: np.ndarray) -> np.ndarray:
    """For each distinct ``key`` (ascending), the index of its smallest ``value``, the first
    in ``order`` among equal ones."""
    by = np.lexsort((order, value, key))
    return by[np.r_[True, key[by][1:] != key[by][:-1]]]


def entry_violations(s: Survey, worst: dict, message: str, *, place: str
                     ) -> Iterator[Violation]:
    """One violation per entry the finite differences do not confirm. ``place`` says where it
    was seen (the function, and the mode or state); the cause is the entry's unknown and its
    known: a wrong partial derivative that the directional and the adjoint derivative, both
    modes or Initialization Mode all give, and the entries a wrong formula spoils (of one
    unknown, or through one known), are one defect, one finding (``conformance.run.causes``)."""
    layout = s.layout
    assert layout is not None
    for (i, j), w in sorted(worst.items()):
        entry = layout.entry(i, j)
        yield Violation(message, layout.rows[i].location, evidence(
            entry=entry, unknown=layout.rows[i].name, known=layout.cols[j].name,
            **w.items, scale="row scale S_i = sum_j |J_ij| * nominal_j; tolerance = margin * "
            "error_estimate + rtol * S_i / nominal_j", point=point_evidence(layout, w.ps),
            place=place),
            subject=entry, cause=causes.entry(layout.rows[i].name, layout.cols[j].name))


def entry_errors(worst: dict, layout: JacobianLayout) -> list[tuple[str, float, float]]:
    return [(layout.entry(i, j), abs(w.items.get("fmu", 0.0) - w.items["finite_difference"]),
             w.items["tolerance"]) for (i, j), w in worst.items()]


def call_failures(s: Survey, call: str) -> Iterator[Violation]:
    """The first refusal of the FMU's derivative function, if any (one finding, not one per
    point)."""
    for flag, point, exc in s.failures:
        if flag != call or exc.after is not None:  # after an earlier failure: a consequence
            continue
        fn = "fmi3GetDirectionalDerivative" if call == "directional" else "fmi3GetAdjointDerivative"
        yield Violation(
            f"{fn} fails in DAE mode with residuals, derivatives and outputs as unknowns and "
            "states, algebraic variables and inputs as knowns (fmi-ls-dae allows both)",
            evidence=evidence(call=exc.call, status=exc.status, log=list(exc.log)[:10],
                              point=point.label))
        return


# ------------------------------------------------------ may the FMU's derivatives be used?

DIRECTIONAL_RULE = "directional-derivative-mismatch"
OPTIONS_FACT = "derivatives.directional_options"


def directional_options(ctx: ProbeContext) -> dict:
    """The options of directional-derivative-mismatch (``rtol``, ``margin``, ``ulps``): as it ran
    in this worker (it records them), else as the check plans it (in the other worker), else its
    catalogue defaults. What "confirmed" means for every use of the FMU's directional
    derivatives."""
    options = ctx.facts.get(OPTIONS_FACT)
    if not isinstance(options, dict):
        planned = (ctx.facts.get(PLANNED_OPTIONS) or {}).get(DIRECTIONAL_RULE)
        if planned is None:
            rule = default_catalogue().get(DIRECTIONAL_RULE)
            planned = rule.option_values if rule else {}
        options = {k: v for k, v in planned.items() if k in ("rtol", "margin", "ulps")}
        ctx.facts[OPTIONS_FACT] = options
    return options


def directional_verdict(ctx: ProbeContext, s: Survey) -> tuple[bool, str]:
    """(use, note): whether the FMU's directional derivatives are confirmed by the survey and
    may be used, and, when the FMU provides them but they may not, why (a note for the
    evidence: finite differences stand in). No note when the FMU provides none."""
    failed = next((exc for flag, _, exc in s.failures if flag == "directional"), None)
    if failed is not None:
        return False, (f"the FMU's directional derivatives were not used: {failed.call} "
                       f"returned {failed.status} (directional-derivative-mismatch)")
    if not s.directional or s.layout is None:
        return False, ""
    worst = mismatched_entries(s, "dd", **directional_options(ctx))
    if not worst:
        return True, ""
    (i, j), _ = max(worst.items(), key=lambda kv: kv[1].ratio)
    return False, (f"the FMU's directional derivatives were not used: finite differences "
                   f"refute {len(worst)} of their entries, worst {s.layout.entry(i, j)} "
                   "(directional-derivative-mismatch)")
