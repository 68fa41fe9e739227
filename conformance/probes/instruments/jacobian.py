"""The Jacobian survey shared by the derivative probes (derivatives/partials.py,
derivatives/dgdw.py).

The rows, columns and declared sparsity come from :mod:`.jacobian_layout`, in DAE mode (the
manifest's promises) or in ODE mode (modelDescription's). At every sampling point the Jacobian
of a mode is measured once (:func:`survey`, memoised in ``ctx.facts`` per mode): finite
differences of the function coloured by the declared sparsity, the FMU's directional and adjoint
derivatives coloured the same way, the declared zeros verified with a few random directions,
and every row under suspicion measured again column by column
(:func:`conformance.numerics.measure.measure`).

Also the helpers the probes share: the row scale ``S_i = sum_j |J_ij| * nominal_j``, a point as
evidence, and the per-FMU ``probe_errors`` the HTML report plots.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from typing import Callable, Iterable, Iterator, TypeVar

import numpy as np

from ...numerics import colouring as col
from ...report.findings import Violation, evidence
from ...numerics import measure, numdiff
from ...numerics.intsets import unique_ints
from .api import Evaluator, FmiError, Point, ProbeContext, ProbeSkipped
from .common import renew
from .jacobian_layout import MODE_NAMES, JacobianLayout, build_layout

log = logging.getLogger(__name__)

S = TypeVar("S")
FACT = "derivatives.survey"              # DAE mode; ODE mode under FACT + ".ode"
MAX_PROBE_ERRORS = 200
MAX_PLOTTED_ENTRIES = 50_000   # declared and observed entries of the published sparsity


def fact_key(mode: str) -> str:
    return FACT if mode == "dae" else f"{FACT}.{mode}"


@dataclass(frozen=True)
class Settings:
    """How the Jacobian is measured (not what counts as wrong: that is in the catalogue)."""

    method: str = "central"     # finite differences, see numdiff.METHODS
    directions: int = 2         # random directions verifying the declared zeros, per point
    suspicion: float = 3.0      # re-measure a row column by column above this error multiple
    ulps: float = numdiff.DEFAULT_ULPS
    coloured: bool = True       # False: one column per group (the benchmark's reference)
    use_derivatives: bool = True  # False: finite differences only (the benchmark)


@dataclass
class PointSurvey:
    point: Point
    x: np.ndarray
    entries: measure.Entries


@dataclass
class Survey:
    layout: JacobianLayout | None
    reason: str = ""
    mode: str = "dae"           # the mode measured: "dae" or "ode"
    points: list[PointSurvey] = field(default_factory=list)
    failures: list[tuple[str, Point, FmiError]] = field(default_factory=list)
    directional: bool = False
    adjoint: bool = False
    probed: bool = False        # the FMU's derivative functions were tried once


# ------------------------------------------------------------------- the evaluator at a point

class _At:
    """The evaluator at one point, the knowns as a vector (time included)."""

    def __init__(self, ev: Evaluator, layout: JacobianLayout, point: Point):
        self.ev, self.layout, self.point = ev, layout, point
        self.row_vrs = tuple(r.vr for r in layout.rows)   # tuples: converted once per call
        self.dd_row_idx = np.flatnonzero(layout.dd_rows)
        self.dd_row_vrs = tuple(layout.rows[i].vr for i in self.dd_row_idx)
        self.dd_idx = np.flatnonzero(layout.dd_columns)
        self.dd_vrs = tuple(layout.cols[j].vr for j in self.dd_idx)
        self.time = [j for j, c in enumerate(layout.cols) if c.role == "time"]
        missing = [c.vr for c in layout.cols if c.role != "time" and c.vr not in point.values]
        known = dict(point.values)
        if missing:  # the sampler did not set them: read the instance's own values
            known.update(zip(missing, ev.evaluate(point, missing).tolist()))
        self.x = np.array([point.t if c.role == "time" else float(known[c.vr])
                           for c in layout.cols])
        self.value_cols = np.array([c.role != "time" for c in layout.cols], dtype=bool)
        self.value_vrs = [c.vr for c in layout.cols if c.role != "time"]
        self.base = self.at(np.zeros(len(layout.cols)))

    def at(self, delta: np.ndarray) -> Point:
        x = self.x + delta
        t = float(x[self.time[0]]) if self.time else self.point.t
        values = dict(zip(self.value_vrs, x[self.value_cols].tolist()))
        return Point(t, values, self.point.label)

    def fun(self, delta: np.ndarray) -> np.ndarray:
        return np.asarray(self.ev.evaluate(self.at(delta), self.row_vrs), dtype=float)

    def directional(self, seed: np.ndarray) -> np.ndarray:
        """J @ seed from the FMU for the rows it may be asked for, NaN for the others."""
        out = np.full(len(self.row_vrs), np.nan)
        out[self.dd_row_idx] = self.ev.directional(
            self.base, self.dd_row_vrs, self.dd_vrs,
            np.asarray(seed, dtype=float)[self.dd_idx])
        return out

    def adjoint(self, v: np.ndarray) -> np.ndarray:
        out = np.full(len(self.layout.cols), np.nan)
        out[self.dd_idx] = self.ev.adjoint(self.base, self.dd_row_vrs, self.dd_vrs,
                                           np.asarray(v, dtype=float)[self.dd_row_idx])
        return out


# ------------------------------------------------------------------------------- the survey

def survey(ctx: ProbeContext, settings: Settings = Settings(), mode: str = "dae") -> Survey:
    """The Jacobian of ``mode`` measured at every sampling point, once per FMU (memoised in
    ctx.facts)."""
    memo = ctx.facts.get(fact_key(mode))
    if isinstance(memo, Survey):
        return memo
    result = run_survey(ctx, settings, mode)
    ctx.facts[fact_key(mode)] = result
    _publish_jacobian(ctx, result)
    return result


def run_survey(ctx: ProbeContext, settings: Settings, mode: str = "dae") -> Survey:
    """The survey itself, without the memo (the benchmark runs it with other settings)."""
    layout, reason = build_layout(ctx, mode)
    if getattr(ctx.facts.get("library"), "fatal", False):  # no call after fmi3Fatal (SM-04)
        return Survey(layout=None, mode=mode, reason="an FMI call returned fmi3Fatal: no "
                      "instance may be called (SM-04)")
    if layout is None or getattr(ctx, mode) is None:
        failure = ctx.facts.get(f"{mode}_error")
        return Survey(layout=None, mode=mode, reason=reason or (
            f"{MODE_NAMES[mode]} could not be started" + (f" ({failure})" if failure else "")))
    me = ctx.model.model_exchange if ctx.model is not None else None
    use = settings.use_derivatives and me is not None and bool(layout.dd_rows.any())
    result = Survey(layout, directional=bool(use and me.flag("providesDirectionalDerivatives")),
                    adjoint=bool(use and me.flag("providesAdjointDerivatives")), mode=mode)
    colouring = (col.colour_columns(layout.pattern) if settings.coloured
                 else col.one_per_group(layout.pattern))
    row_colouring = (col.colour_rows(layout.pattern) if settings.coloured
                     else col.one_per_group(layout.pattern, rows=True))
    rng = np.random.default_rng((ctx.seed, 740) if mode == "dae" else (ctx.seed, 740, 1))
    start_time = min((p.t for p in ctx.points), default=0.0)
    for point in ctx.points:
        failed = getattr(getattr(ctx, mode), "failure", None) is not None  # Terminated (SM-04)
        if failed and renew(ctx, mode) is None:
            break
        measured = _measure_point(getattr(ctx, mode), layout, point, result, colouring,
                                  row_colouring, rng, settings, start_time)
        if measured is not None:
            result.points.append(measured)
    return result


def _measure_point(ev, layout, point, result, colouring, row_colouring, rng, settings,
                   start_time):
    try:
        at = _At(ev, layout, point)
        # fmi3SetTime never goes below the start time (SM-06): it bounds the time column
        lower = np.array([start_time if c.role == "time" else c.lower for c in layout.cols])
        steps = numdiff.step_sizes(at.x, layout.nominal, method=settings.method, lower=lower,
                                   upper=np.array([c.upper for c in layout.cols]))
    except FmiError as exc:
        result.failures.append(("evaluate", point, exc))
        return None
    for flag in ("directional", "adjoint"):
        if result.probed or not getattr(result, flag):
            continue
        try:  # one probing call, so a refusal is reported once and not mid-measurement
            (at.directional if flag == "directional" else at.adjoint)(
                np.zeros(len(layout.cols) if flag == "directional" else len(layout.rows)))
        except FmiError as exc:
            result.failures.append((flag, point, exc))
            setattr(result, flag, False)
    result.probed = True
    sources = measure.Sources(at.fun, at.directional if result.directional else None,
                              at.adjoint if result.adjoint else None, layout.dd_columns,
                              layout.dd_rows)
    try:
        entries = measure.measure(sources, layout.pattern, colouring, steps, at.x, rng,
                              row_colouring=row_colouring, method=settings.method,
                              directions=settings.directions, suspicion=settings.suspicion,
                              ulps=settings.ulps)
    except FmiError as exc:  # e.g. a value out of range refused: nothing to compare here
        result.failures.append(("evaluate", point, exc))
        return None
    return PointSurvey(point, at.x, entries)


def _publish_jacobian(ctx: ProbeContext, s: Survey) -> None:
    """info["jacobian"] for the HTML report's sparsity plot (DAE mode's, or ODE mode's for an
    FMU without DAE mode): the declared entries of the rows that claim them and the entries
    observed to move. A Jacobian of more than ``MAX_PLOTTED_ENTRIES`` of them (a plot of which
    would show nothing) is summarised in info["jacobian_left_out"] instead: its size and
    counts."""
    if s.layout is None or (s.mode != "dae" and ctx.dae is not None):
        return
    layout = s.layout
    n = len(layout.cols)
    moved = [(e.rows.astype(np.int64) * n + e.cols)[~e.zero & (e.fd != 0)]
             for e in (ps.entries for ps in s.points)]
    observed = unique_ints(np.concatenate(moved)) if moved else np.zeros(0, dtype=np.int64)
    p = layout.pattern
    explicit = np.array([r.explicit for r in layout.rows], dtype=bool)
    declared = explicit[p.rows] if p.nnz else np.zeros(0, dtype=bool)
    info = ctx.facts.setdefault("info", {})
    if int(declared.sum()) + observed.size > MAX_PLOTTED_ENTRIES:
        info["jacobian_left_out"] = {
            "rows": len(layout.rows), "cols": n, "declared": int(declared.sum()),
            "observed": int(observed.size), "limit": MAX_PLOTTED_ENTRIES}
        return
    info["jacobian"] = {
        "rows": [r.name for r in layout.rows], "cols": [c.name for c in layout.cols],
        "declared": np.column_stack([p.rows[declared], p.cols[declared]]).tolist(),
        "observed": np.column_stack([observed // n, observed % n]).tolist(), "mode": s.mode}


def surveyed(ctx: ProbeContext, *, min_points: int = 1, mode: str = "dae") -> Survey:
    """The survey of ``mode``, or ProbeSkipped with the reason it has nothing to compare."""
    s = survey(ctx, mode=mode)
    if s.layout is None:
        raise ProbeSkipped(s.reason)
    if len(s.points) < min_points:
        raise ProbeSkipped(f"{len(s.points)} sampling point(s) could be measured, "
                           f"{min_points} needed")
    return s


def per_mode(ctx: ProbeContext, surveyed_in: Callable[[str], S]) -> list[S]:
    """``surveyed_in(mode)`` for every mode the FMU has (DAE mode first; the runtime layout's
    ``modes``), or ProbeSkipped naming, per mode, why none has anything to compare. A probe of
    both modes runs on what it gets: one rule, one promise, whatever the mode."""
    modes = getattr(ctx.facts.get("layout"), "modes", ("dae",)) or ("dae",)
    found, reasons = [], []
    for mode in modes:
        try:
            found.append(surveyed_in(mode))
        except ProbeSkipped as exc:
            reasons.append(f"{MODE_NAMES[mode]}: {exc}" if len(modes) > 1 else str(exc))
    if not found:
        raise ProbeSkipped("; ".join(reasons))
    return found


def mode_evidence(s: Survey) -> dict:
    """The mode of a survey and the file whose promises it verifies, for the evidence."""
    file = s.layout.rows[0].location.file if s.layout is not None and s.layout.rows else None
    return {"mode": MODE_NAMES[s.mode], "declared_in": file}


def in_mode(violations: Iterable[Violation], s: Survey) -> Iterator[Violation]:
    """The violations of a survey with its mode added to message and evidence."""
    for v in violations:
        yield replace(v, message=f"{v.message} ({MODE_NAMES[s.mode]})",
                      evidence=evidence(mode_evidence(s), **dict(v.evidence)))


def record_errors(ctx: ProbeContext, code: str, items: list[tuple[str, float, float]]) -> None:
    info = ctx.facts.setdefault("info", {})
    errors = info.setdefault("probe_errors", [])
    items = sorted(items, key=lambda it: -(it[1] / it[2]) if it[2] > 0 else -np.inf)
    room = max(0, MAX_PROBE_ERRORS - len(errors))
    errors.extend({"rule": code, "entry": entry, "error": float(err), "tolerance": float(tol)}
                  for entry, err, tol in items[:room])



# ------------------------------------------------------------------------------ shared helpers

def row_scale(layout: JacobianLayout, e: measure.Entries, *,
              declared_only: bool = False) -> np.ndarray:
    """S_i = sum_j |J_ij| * nominal_j over the measured entries of each row, shape (m,)."""
    return measure.row_scale(e, layout.nominal, len(layout.rows), declared_only=declared_only)


def base_point(layout: JacobianLayout, ps: PointSurvey) -> Point:
    """The point a survey point was measured at, every known set (time from its column)."""
    t = next((float(v) for c, v in zip(layout.cols, ps.x) if c.role == "time"), ps.point.t)
    values = {c.vr: float(v) for c, v in zip(layout.cols, ps.x) if c.role != "time"}
    return Point(t, values, ps.point.label)


def point_evidence(layout: JacobianLayout, ps: PointSurvey, limit: int = 20) -> dict:
    values = {c.name: float(v) for c, v in zip(layout.cols, ps.x) if c.role != "time"}
    shown = dict(list(values.items())[:limit])
    return {"label": ps.point.label, "t": float(ps.point.t), "values": shown}

