"""Derivative probes (DAE740-DAE779): partial derivatives, dependencies, dg/dw, ODE against DAE.

In DAE mode the unknowns are the residuals, the state derivatives and the outputs; the knowns
the states, the algebraic variables, the inputs and time. At every sampling point the Jacobian
is measured once (:func:`survey`, shared by all the probes through ``ctx.facts``): finite
differences of the function coloured by the *declared* sparsity (the manifest ``dependencies``,
what an importer colours its own Jacobian with), the FMU's directional and adjoint derivatives
coloured the same way, the declared zeros verified with a few random directions, and every row
under suspicion measured again column by column (:func:`conformance.probes.colouring.measure`).
The probes then compare, each with the tolerances of its catalogue entry:

* ``directional-derivative-mismatch`` / ``adjoint-derivative-mismatch``: the FMU's entries
  against finite differences, and the dot-product test v(Js) = (vJ)s;
* ``dependency-undeclared`` / ``dependency-never-observed``: observed against declared
  sparsity; ``dependencies-kind-violated``: a non-``dependent`` entry that changes;
* ``algebraic-jacobian-ill-conditioned`` / ``-singular``: dg/dw, scaled by nominals;
* ``ode-dae-inconsistent``: ODE mode against DAE mode at the same (t, x, u).

Every comparison is scaled: an entry ``J_ij`` is compared in units of the row's scale
``S_i = sum_j |J_ij| * nominal_j`` (how much the unknown moves when each known moves by its
nominal), and a difference counts only when it exceeds ``margin`` times the finite-difference
error estimate (:mod:`conformance.probes.numdiff`) plus ``rtol * S_i / nominal_j``.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np

from ..findings import Location, Violation, evidence
from ..model import ModelDescription, Unknown, Variable
from . import colouring as col
from . import numdiff
from .api import Evaluator, FmiError, Point, ProbeContext, ProbeSkipped

log = logging.getLogger(__name__)

FACT = "derivatives.survey"
MAX_PROBE_ERRORS = 200


@dataclass(frozen=True)
class Settings:
    """How the Jacobian is measured (not what counts as wrong: that is in the catalogue)."""

    method: str = "central"     # finite differences, see numdiff.METHODS
    directions: int = 2         # random directions verifying the declared zeros, per point
    suspicion: float = 3.0      # re-measure a row column by column above this error multiple
    ulps: float = numdiff.DEFAULT_ULPS
    coloured: bool = True       # False: one column per group (the benchmark's reference)
    use_derivatives: bool = True  # False: finite differences only (the benchmark)


@dataclass(frozen=True)
class Row:
    vr: int
    name: str
    role: str                   # residual | derivative | output
    explicit: bool              # the dependencies attribute is present (a claim)
    location: Location
    nominal: float | None = None  # declared nominal (residuals are scaled by it when given)


@dataclass(frozen=True)
class Column:
    vr: int
    name: str
    role: str                   # state | algebraic | input | time
    nominal: float
    lower: float
    upper: float


@dataclass(frozen=True)
class JacobianLayout:
    """Rows, columns and the declared sparsity of the DAE-mode Jacobian."""

    rows: tuple[Row, ...]
    cols: tuple[Column, ...]
    pattern: col.Pattern
    kinds: tuple[str, ...]              # dependenciesKind of each declared entry
    dd_columns: np.ndarray              # bool (n,): knowns passed to the FMU's derivatives

    @property
    def nominal(self) -> np.ndarray:
        return np.array([c.nominal for c in self.cols])

    def entry(self, i: int, j: int) -> str:
        return f"d({self.rows[i].name})/d({self.cols[j].name})"

    def indices(self, role: str, of: str = "cols") -> np.ndarray:
        items = self.cols if of == "cols" else self.rows
        return np.array([k for k, it in enumerate(items) if it.role == role], dtype=np.intp)


@dataclass
class PointSurvey:
    point: Point
    x: np.ndarray
    entries: col.Entries


@dataclass
class Survey:
    layout: JacobianLayout | None
    reason: str = ""
    points: list[PointSurvey] = field(default_factory=list)
    failures: list[tuple[str, Point, FmiError]] = field(default_factory=list)
    directional: bool = False
    adjoint: bool = False
    probed: bool = False        # the FMU's derivative functions were tried once


# ---------------------------------------------------------------------------------- the layout

def _float(text: str | None, default: float) -> float:
    try:
        return float(text) if text is not None else default
    except ValueError:
        return default


def _scalar_float(model: ModelDescription, vr: int | None) -> Variable | None:
    var = model.by_vr.get(vr) if vr is not None else None
    return var if var is not None and var.is_float and not var.dimensions else None


def _column(var: Variable, role: str) -> Column:
    nominal = abs(_float(var.nominal, 1.0))
    nominal = nominal if np.isfinite(nominal) and nominal > 0 else 1.0
    return Column(var.vr, var.name, role, nominal, _float(var.minimum, -np.inf),
                  _float(var.maximum, np.inf))


def build_layout(ctx: ProbeContext) -> tuple[JacobianLayout | None, str]:
    """The DAE-mode Jacobian's rows, columns and declared sparsity, or None and why."""
    model, manifest = ctx.model, ctx.manifest
    if model is None or manifest is None:
        return None, "no model description or manifest"
    cols: list[Column] = []
    seen: set[int] = set()

    def add(var: Variable | None, role: str) -> None:
        if var is not None and var.vr not in seen:
            seen.add(var.vr)
            cols.append(_column(var, role))

    for vr in model.state_vrs():
        add(_scalar_float(model, vr), "state")
    for ref in manifest.algebraic:
        add(_scalar_float(model, ref.vr), "algebraic")
    for var in model.variables:
        if var.causality == "input" and var.variability == "continuous":
            add(_scalar_float(model, var.vr), "input")
    independent = [v for v in model.variables if v.causality == "independent"]
    if independent:
        add(_scalar_float(model, independent[0].vr), "time")
    rows = _rows(model, manifest, seen)
    if not rows or not cols:
        return None, "no residuals, derivatives or outputs, or no knowns, to differentiate"
    return _with_pattern(rows, cols, model), ""


def _rows(model: ModelDescription, manifest, knowns: set[int]) -> list[tuple[Row, Unknown]]:
    out: list[tuple[Row, Unknown]] = []
    taken: set[int] = set()
    for kind, role in (("Residual", "residual"), ("ContinuousStateDerivative", "derivative"),
                       ("Output", "output")):
        listed = manifest.unknowns(kind)
        # An element kind the manifest leaves out (open question Q-02): take the core list,
        # but claim nothing about its dependencies (those describe ODE mode).
        inherited = not listed and kind != "Residual"
        for u in (tuple(model.unknowns(kind)) if inherited else listed):
            var = _scalar_float(model, u.vr)
            if var is None or var.vr in taken or var.vr in knowns:
                continue
            taken.add(var.vr)
            claim = u.dependencies is not None and not inherited
            nominal = abs(_float(var.nominal, np.nan))
            out.append((Row(var.vr, var.name, role, claim,
                            Location(file=u.file, line=u.line, path=u.path),
                            nominal if np.isfinite(nominal) and nominal > 0 else None), u))
    return out


def _with_pattern(rows: list[tuple[Row, Unknown]], cols: list[Column],
                  model: ModelDescription) -> JacobianLayout:
    index = {c.vr: j for j, c in enumerate(cols)}
    row_cols: list[list[int]] = []
    kinds_by_row: list[dict[int, str]] = []
    for row, u in rows:
        if not row.explicit:
            row_cols.append(list(range(len(cols))))
            kinds_by_row.append({})
            continue
        kinds = dict(zip(u.dependencies or (), u.dependencies_kind or ()))
        listed = [index[vr] for vr in (u.dependencies or ()) if vr in index]
        row_cols.append(listed)
        kinds_by_row.append({index[vr]: k for vr, k in kinds.items() if vr in index})
    pattern = col.Pattern.from_rows(len(cols), row_cols)
    kinds = tuple(kinds_by_row[i].get(j, "dependent")
                  for i, j in zip(pattern.rows.tolist(), pattern.cols.tolist()))
    # Time is a known of the FMU's derivatives only where a dependencies list names it (PD-05).
    explicit_time = {j for (row, _), cs in zip(rows, row_cols) if row.explicit for j in cs
                     if cols[j].role == "time"}
    dd = np.array([c.role != "time" or j in explicit_time for j, c in enumerate(cols)])
    return JacobianLayout(tuple(r for r, _ in rows), tuple(cols), pattern, kinds, dd)


# ------------------------------------------------------------------- the evaluator at a point

class _At:
    """The evaluator at one point, the knowns as a vector (time included)."""

    def __init__(self, ev: Evaluator, layout: JacobianLayout, point: Point):
        self.ev, self.layout, self.point = ev, layout, point
        self.row_vrs = [r.vr for r in layout.rows]
        self.dd_idx = np.flatnonzero(layout.dd_columns)
        self.dd_vrs = [layout.cols[j].vr for j in self.dd_idx]
        self.time = [j for j, c in enumerate(layout.cols) if c.role == "time"]
        missing = [c.vr for c in layout.cols if c.role != "time" and c.vr not in point.values]
        known = dict(point.values)
        if missing:  # the sampler did not set them: read the instance's own values
            known.update(zip(missing, ev.evaluate(point, missing).tolist()))
        self.x = np.array([point.t if c.role == "time" else float(known[c.vr])
                           for c in layout.cols])
        self.base = self.at(np.zeros(len(layout.cols)))

    def at(self, delta: np.ndarray) -> Point:
        x = self.x + delta
        t = float(x[self.time[0]]) if self.time else self.point.t
        values = {c.vr: float(v) for c, v in zip(self.layout.cols, x) if c.role != "time"}
        return Point(t, values, self.point.label)

    def fun(self, delta: np.ndarray) -> np.ndarray:
        return np.asarray(self.ev.evaluate(self.at(delta), self.row_vrs), dtype=float)

    def directional(self, seed: np.ndarray) -> np.ndarray:
        return np.asarray(self.ev.directional(self.base, self.row_vrs, self.dd_vrs,
                                              np.asarray(seed, dtype=float)[self.dd_idx]), float)

    def adjoint(self, v: np.ndarray) -> np.ndarray:
        out = np.full(len(self.layout.cols), np.nan)
        out[self.dd_idx] = self.ev.adjoint(self.base, self.row_vrs, self.dd_vrs,
                                           np.asarray(v, dtype=float))
        return out


# ------------------------------------------------------------------------------- the survey

def survey(ctx: ProbeContext, settings: Settings = Settings()) -> Survey:
    """The Jacobian measured at every sampling point, once per FMU (memoised in ctx.facts)."""
    memo = ctx.facts.get(FACT)
    if isinstance(memo, Survey):
        return memo
    result = _survey(ctx, settings)
    ctx.facts[FACT] = result
    _publish_jacobian(ctx, result)
    return result


def _survey(ctx: ProbeContext, settings: Settings) -> Survey:
    layout, reason = build_layout(ctx)
    if layout is None or ctx.dae is None:
        failure = ctx.facts.get("dae_error")
        return Survey(None, reason or "DAE mode could not be started" + (
            f" ({failure})" if failure else ""))
    me = ctx.model.model_exchange if ctx.model is not None else None
    use = settings.use_derivatives and me is not None
    result = Survey(layout, directional=bool(use and me.flag("providesDirectionalDerivatives")),
                    adjoint=bool(use and me.flag("providesAdjointDerivatives")))
    colouring = (col.colour_columns(layout.pattern) if settings.coloured
                 else col.one_per_group(layout.pattern))
    row_colouring = (col.colour_rows(layout.pattern) if settings.coloured
                     else col.one_per_group(layout.pattern, rows=True))
    rng = np.random.default_rng((ctx.seed, 740))
    start_time = min((p.t for p in ctx.points), default=0.0)
    for point in ctx.points:
        measured = _measure_point(ctx.dae, layout, point, result, colouring, row_colouring,
                                  rng, settings, start_time)
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
    sources = col.Sources(at.fun, at.directional if result.directional else None,
                          at.adjoint if result.adjoint else None, layout.dd_columns)
    try:
        entries = col.measure(sources, layout.pattern, colouring, steps, at.x, rng,
                              row_colouring=row_colouring, method=settings.method,
                              directions=settings.directions, suspicion=settings.suspicion,
                              ulps=settings.ulps)
    except FmiError as exc:  # e.g. a value out of range refused: nothing to compare here
        result.failures.append(("evaluate", point, exc))
        return None
    return PointSurvey(point, at.x, entries)


def _publish_jacobian(ctx: ProbeContext, s: Survey) -> None:
    if s.layout is None:
        return
    observed: set[tuple[int, int]] = set()
    for ps in s.points:
        e = ps.entries
        moved = ~e.zero & (e.fd != 0)
        observed.update(zip(e.rows[moved].tolist(), e.cols[moved].tolist()))
    p = s.layout.pattern
    info = ctx.facts.setdefault("info", {})
    info["jacobian"] = {
        "rows": [r.name for r in s.layout.rows], "cols": [c.name for c in s.layout.cols],
        "declared": [[i, j] for i, j in zip(p.rows.tolist(), p.cols.tolist())
                     if s.layout.rows[i].explicit],
        "observed": sorted([i, j] for i, j in observed)}


def _surveyed(ctx: ProbeContext, *, min_points: int = 1) -> Survey:
    """The survey, or ProbeSkipped with the reason it has nothing to compare."""
    s = survey(ctx)
    if s.layout is None:
        raise ProbeSkipped(s.reason)
    if len(s.points) < min_points:
        raise ProbeSkipped(f"{len(s.points)} sampling point(s) could be measured, "
                           f"{min_points} needed")
    return s


def _record_errors(ctx: ProbeContext, code: str, items: list[tuple[str, float, float]]) -> None:
    info = ctx.facts.setdefault("info", {})
    errors = info.setdefault("probe_errors", [])
    items = sorted(items, key=lambda it: -(it[1] / it[2]) if it[2] > 0 else -np.inf)
    room = max(0, MAX_PROBE_ERRORS - len(errors))
    errors.extend({"rule": code, "entry": entry, "error": float(err), "tolerance": float(tol)}
                  for entry, err, tol in items[:room])


# ------------------------------------------------------------------------ comparing entries

@dataclass
class _Worst:
    """The worst point of one entry: the excess ratio and what to show as evidence."""

    ratio: float
    ps: PointSurvey
    items: dict


def _row_scale(layout: JacobianLayout, e: col.Entries, *,
               declared_only: bool = False) -> np.ndarray:
    """S_i = sum_j |J_ij| * nominal_j over the measured entries of each row, shape (m,)."""
    weights = np.abs(np.nan_to_num(e.fd)) * layout.nominal[e.cols]
    if declared_only:
        weights = weights * e.declared
    return np.bincount(e.rows, weights=weights, minlength=len(layout.rows))


def _point_evidence(layout: JacobianLayout, ps: PointSurvey, limit: int = 20) -> dict:
    values = {c.name: float(v) for c, v in zip(layout.cols, ps.x) if c.role != "time"}
    shown = dict(list(values.items())[:limit])
    return {"label": ps.point.label, "t": float(ps.point.t), "values": shown}


def _keep_worst(worst: dict, key, ratio: float, ps: PointSurvey, items: dict) -> None:
    if key not in worst or ratio > worst[key].ratio:
        worst[key] = _Worst(ratio, ps, items)


def _mismatches(s: Survey, which: str, *, rtol: float, margin: float, ulps: float) -> dict:
    """Entries where the FMU's value (``dd`` or ``adj``) and the finite difference disagree."""
    layout = s.layout
    assert layout is not None
    worst: dict[tuple[int, int], _Worst] = {}
    for ps in s.points:
        e = ps.entries
        fmu = e.dd if which == "dd" else e.adj
        scale = _row_scale(layout, e)[e.rows] / layout.nominal[e.cols]
        err = e.error(ulps)
        tol = margin * err + rtol * scale
        diff = np.abs(fmu - e.fd)
        bad = np.isfinite(fmu) & np.isfinite(e.fd) & (diff > tol)  # non-finite: nan-or-inf
        if which == "adj":
            # An adjoint that equals a wrong directional derivative is the same fault, reported
            # once by directional-derivative-mismatch: here only what is the adjoint's own.
            shared = np.abs(e.adj - e.dd) <= rtol * scale + margin * err
            bad &= ~(shared & (np.abs(e.dd - e.fd) > tol))
        for k in np.flatnonzero(bad):
            _keep_worst(worst, (int(e.rows[k]), int(e.cols[k])),
                        float(diff[k] / tol[k]) if tol[k] > 0 else np.inf, ps,
                        {"fmu": float(fmu[k]), "finite_difference": float(e.fd[k]),
                         "error_estimate": float(err[k]), "tolerance": float(tol[k]),
                         "row_scale": float(scale[k] * layout.nominal[e.cols[k]]),
                         "declared": bool(e.declared[k])})
    return worst


def _entry_violations(s: Survey, worst: dict, message: str) -> Iterator[Violation]:
    layout = s.layout
    assert layout is not None
    for (i, j), w in sorted(worst.items()):
        yield Violation(message, layout.rows[i].location, evidence(
            entry=layout.entry(i, j), unknown=layout.rows[i].name, known=layout.cols[j].name,
            **w.items, scale="row scale S_i = sum_j |J_ij| * nominal_j; tolerance = margin * "
            "error_estimate + rtol * S_i / nominal_j", point=_point_evidence(layout, w.ps)),
            subject=layout.entry(i, j))


def _errors(worst: dict, layout: JacobianLayout) -> list[tuple[str, float, float]]:
    return [(layout.entry(i, j), abs(w.items.get("fmu", 0.0) - w.items["finite_difference"]),
             w.items["tolerance"]) for (i, j), w in worst.items()]


def _failures(s: Survey, call: str) -> Iterator[Violation]:
    """The first refusal of the FMU's derivative function, if any (one finding, not one per
    point)."""
    for flag, point, exc in s.failures:
        if flag != call:
            continue
        fn = "fmi3GetDirectionalDerivative" if call == "directional" else "fmi3GetAdjointDerivative"
        yield Violation(
            f"{fn} fails in DAE mode with residuals, derivatives and outputs as unknowns and "
            "states, algebraic variables and inputs as knowns (fmi-ls-dae allows both)",
            evidence=evidence(call=exc.call, status=exc.status, log=list(exc.log)[:10],
                              point=point.label))
        return


# ------------------------------------------------------------------------------- the probes

def directional_derivative_mismatch(ctx: ProbeContext, *, rtol: float = 1e-5,
                                    margin: float = 10.0, ulps: float = 100.0
                                    ) -> Iterator[Violation]:
    """fmi3GetDirectionalDerivative against finite differences of the function (DAE-50)."""
    s = _surveyed(ctx)
    failures = list(_failures(s, "directional"))
    if not s.directional and not failures:
        raise ProbeSkipped("the FMU does not provide directional derivatives")
    yield from failures
    worst = _mismatches(s, "dd", rtol=rtol, margin=margin, ulps=ulps)
    _record_errors(ctx, "DAE740", _errors(worst, s.layout))
    yield from _entry_violations(
        s, worst, "fmi3GetDirectionalDerivative gives {subject} that finite differences of the "
        "function do not confirm")


def adjoint_derivative_mismatch(ctx: ProbeContext, *, rtol: float = 1e-5, margin: float = 10.0,
                                ulps: float = 100.0, dot_rtol: float = 1e-6
                                ) -> Iterator[Violation]:
    """fmi3GetAdjointDerivative against finite differences, and the dot-product test
    v(Js) = (vJ)s against the directional derivative (PD-06, DAE-50)."""
    s = _surveyed(ctx)
    failures = list(_failures(s, "adjoint"))
    if not s.adjoint and not failures:
        raise ProbeSkipped("the FMU does not provide adjoint derivatives")
    yield from failures
    worst = _mismatches(s, "adj", rtol=rtol, margin=margin, ulps=ulps)
    _record_errors(ctx, "DAE741", _errors(worst, s.layout))
    yield from _entry_violations(
        s, worst, "fmi3GetAdjointDerivative gives {subject} that finite differences of the "
        "function do not confirm")
    if worst:
        return
    directional_ok = not _mismatches(s, "dd", rtol=1e-5, margin=10.0, ulps=ulps)
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
                         point=_point_evidence(s.layout, ps)))
            return


def dependency_undeclared(ctx: ProbeContext, *, rtol: float = 1e-8, margin: float = 10.0,
                          ulps: float = 100.0) -> Iterator[Violation]:
    """A partial derivative clearly non-zero for a known the dependencies leave out (MS-20)."""
    s = _surveyed(ctx)
    layout = s.layout
    assert layout is not None
    worst: dict[tuple[int, int], _Worst] = {}
    for ps in s.points:
        e = ps.entries
        scale = _row_scale(layout, e, declared_only=True)[e.rows]
        nominal = layout.nominal[e.cols]
        err = e.error(ulps)
        size = np.abs(e.fd) * nominal
        tol = margin * err * nominal + rtol * scale
        clear = ~e.declared & ~e.zero & np.isfinite(size) & (size > tol)
        for k in np.flatnonzero(clear):
            if not layout.rows[e.rows[k]].explicit:
                continue
            _keep_worst(worst, (int(e.rows[k]), int(e.cols[k])),
                        float(size[k] / tol[k]) if tol[k] > 0 else np.inf, ps,
                        {"finite_difference": float(e.fd[k]), "error_estimate": float(err[k]),
                         "tolerance": float(tol[k] / nominal[k]),
                         "row_scale": float(scale[k])})
    _record_errors(ctx, "DAE742", [(layout.entry(i, j), abs(w.items["finite_difference"]),
                                    w.items["tolerance"]) for (i, j), w in worst.items()])
    for (i, j), w in sorted(worst.items()):
        yield Violation(
            "{subject} is clearly non-zero but the dependencies of the unknown do not list the "
            "known: an importer that colours its Jacobian from them gets it wrong",
            layout.rows[i].location, evidence(
                entry=layout.entry(i, j), unknown=layout.rows[i].name,
                known=layout.cols[j].name, known_value_reference=layout.cols[j].vr, **w.items,
                point=_point_evidence(layout, w.ps)), subject=layout.entry(i, j))
    yield from _reported_dependencies(ctx, layout)


def _reported_dependencies(ctx: ProbeContext, layout: JacobianLayout) -> Iterator[Violation]:
    """fmi3GetVariableDependencies against the manifest, when the FMU offers it."""
    me = ctx.model.model_exchange if ctx.model is not None else None
    reader = getattr(ctx.dae, "variable_dependencies", None)
    if not (me and me.flag("providesPerElementDependencies") and callable(reader)):
        return
    declared = {i: {layout.cols[j].vr for j in layout.pattern.row(i)}
                for i, r in enumerate(layout.rows) if r.explicit}
    knowns = {c.vr: c for c in layout.cols}
    for i, listed in declared.items():
        try:
            reported = {int(vr) for vr, *_ in reader(layout.rows[i].vr)}
        except FmiError:
            return
        for vr in sorted((reported & set(knowns)) - listed):
            entry = f"d({layout.rows[i].name})/d({knowns[vr].name})"
            yield Violation(
                "fmi3GetVariableDependencies reports {subject} but the manifest dependencies "
                "leave it out", layout.rows[i].location,
                evidence(entry=entry, known_value_reference=vr,
                         source="fmi3GetVariableDependencies"),
                subject=entry)


def dependency_never_observed(ctx: ProbeContext, *, min_points: int = 2
                              ) -> Iterator[Violation]:
    """A declared dependency whose function never moved at any sampling point."""
    s = _surveyed(ctx, min_points=min_points)
    layout = s.layout
    assert layout is not None
    seen: dict[tuple[int, int], bool] = {}
    for ps in s.points:
        e = ps.entries
        for i, j, declared, zero in zip(e.rows.tolist(), e.cols.tolist(), e.declared, e.zero):
            if declared and layout.rows[i].explicit:
                seen[(i, j)] = seen.get((i, j), False) or not zero
    for (i, j), moved in sorted(seen.items()):
        if not moved:
            yield Violation(
                "the dependencies list {subject} but the unknown did not change at all when the "
                "known was perturbed, at any sampling point", layout.rows[i].location,
                evidence(entry=layout.entry(i, j), points=len(s.points)),
                subject=layout.entry(i, j))


def dependencies_kind_violated(ctx: ProbeContext, *, rtol: float = 1e-6, margin: float = 10.0,
                               ulps: float = 100.0) -> Iterator[Violation]:
    """A ``constant``/``fixed``/``tunable``/``discrete`` entry whose partial derivative changes
    between sampling points (MS-31: such an unknown is affine in that known)."""
    s = _surveyed(ctx, min_points=2)
    layout = s.layout
    assert layout is not None
    kind_of = {(i, j): k for i, j, k in zip(layout.pattern.rows.tolist(),
                                            layout.pattern.cols.tolist(), layout.kinds)
               if k != "dependent" and layout.rows[i].explicit}
    samples: dict[tuple[int, int], list] = {}
    for ps in s.points:
        e = ps.entries
        scale = _row_scale(layout, e)
        err = e.error(ulps)
        for k, (i, j) in enumerate(zip(e.rows.tolist(), e.cols.tolist())):
            if (i, j) in kind_of and e.declared[k] and np.isfinite(e.fd[k]):
                samples.setdefault((i, j), []).append(
                    (float(e.fd[k]), float(err[k]), float(scale[i] / layout.nominal[j]), ps))
    for (i, j), values in sorted(samples.items()):
        hi = max(values, key=lambda v: v[0])
        lo = min(values, key=lambda v: v[0])
        tol = margin * (hi[1] + lo[1]) + rtol * max(v[2] for v in values)
        if hi[0] - lo[0] > tol:
            yield Violation(
                f"{{subject}} is declared '{kind_of[(i, j)]}' but changes between sampling "
                "points: the unknown is not affine in the known", layout.rows[i].location,
                evidence(entry=layout.entry(i, j), kind=kind_of[(i, j)], smallest=lo[0],
                         largest=hi[0], tolerance=tol,
                         points=[_point_evidence(layout, lo[3]), _point_evidence(layout, hi[3])]),
                subject=layout.entry(i, j))


# ------------------------------------------------------------------------------------ dg/dw

def _algebraic_blocks(s: Survey) -> Iterator[tuple[PointSurvey, np.ndarray, str]]:
    """dg/dw at every point, scaled: columns by the algebraic variables' nominals, rows by the
    residuals' nominals when declared, else equilibrated (a residual's scale is arbitrary)."""
    layout = s.layout
    assert layout is not None
    res = layout.indices("residual", of="rows")
    alg = layout.indices("algebraic")
    if res.size == 0 or res.size != alg.size:
        return  # residual-count-mismatch (static) explains a non-square dg/dw
    rpos = {int(i): a for a, i in enumerate(res)}
    cpos = {int(j): a for a, j in enumerate(alg)}
    source = "fmi3GetDirectionalDerivative" if s.directional else "finite differences"
    for ps in s.points:
        e = ps.entries
        g = np.zeros((res.size, alg.size))
        for k, (i, j) in enumerate(zip(e.rows.tolist(), e.cols.tolist())):
            if i in rpos and j in cpos:
                value = e.dd[k] if s.directional and not np.isnan(e.dd[k]) else e.fd[k]
                g[rpos[i], cpos[j]] = value
        if not np.all(np.isfinite(g)):
            continue  # nan-or-inf reports it
        g = g * layout.nominal[alg][None, :]
        for a, i in enumerate(res):
            nominal = layout.rows[i].nominal
            biggest = np.abs(g[a]).max(initial=0.0)
            g[a] = g[a] / nominal if nominal else (g[a] / biggest if biggest > 0 else g[a])
        yield ps, g, source


def _algebraic_survey(ctx: ProbeContext) -> Survey:
    s = _surveyed(ctx)
    assert s.layout is not None
    residuals = s.layout.indices("residual", of="rows").size
    algebraic = s.layout.indices("algebraic").size
    if residuals == 0 or residuals != algebraic:
        raise ProbeSkipped(f"dg/dw is {residuals} x {algebraic}: no square matrix to assess "
                           "(residual-count-mismatch reports a difference)")
    return s


def _condition(g: np.ndarray) -> tuple[float, bool, np.ndarray]:
    """2-norm condition number, whether numerically singular (smallest singular value below
    max(shape) * eps * largest, numpy's matrix_rank criterion), and the direction of the
    smallest singular value (which algebraic variables the near-singularity involves)."""
    if not np.all(np.isfinite(g)):
        return np.inf, True, np.zeros(g.shape[1])
    _, sv, vt = np.linalg.svd(g)
    if sv[0] == 0:
        return np.inf, True, vt[-1]
    singular = sv[-1] <= sv[0] * max(g.shape) * numdiff.EPS
    return (float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf), bool(singular), vt[-1]


def _worst_condition(s: Survey, singular: bool) -> tuple | None:
    worst = None
    for ps, g, source in _algebraic_blocks(s):
        cond, is_singular, direction = _condition(g)
        if is_singular == singular and (worst is None or cond > worst[1]):
            worst = (ps, cond, direction, source, g.shape[0])
    return worst


def _condition_violation(s: Survey, found: tuple, message: str, **extra) -> Violation:
    layout = s.layout
    assert layout is not None
    ps, cond, direction, source, n = found
    alg = layout.indices("algebraic")
    order = np.argsort(-np.abs(direction))[:5]
    involved = [layout.cols[alg[k]].name for k in order if abs(direction[k]) > 1e-3]
    res = layout.indices("residual", of="rows")
    return Violation(message, layout.rows[res[0]].location, evidence(
        condition_number=cond if np.isfinite(cond) else "inf", size=n, source=source,
        scale="columns by the algebraic variables' nominal values, rows by the residuals' "
        "nominal values or else equilibrated", involved=involved, **extra,
        point=_point_evidence(layout, ps)))


def algebraic_jacobian_ill_conditioned(ctx: ProbeContext, *, max_condition: float = 1e8
                                       ) -> Iterator[Violation]:
    """The scaled dg/dw has a condition number above ``max_condition`` (but is not singular)."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(s, singular=False)
    if found is not None and found[1] > max_condition:
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is ill-conditioned: an importer's Newton iteration loses accuracy",
            threshold=max_condition)


def algebraic_jacobian_singular(ctx: ProbeContext) -> Iterator[Violation]:
    """The scaled dg/dw is numerically singular at a sampling point (DAE-51)."""
    s = _algebraic_survey(ctx)
    found = _worst_condition(s, singular=True)
    if found is not None:
        yield _condition_violation(
            s, found, "dg/dw, the Jacobian of the residuals with respect to the algebraic "
            "variables, is singular: the DAE does not have index 1 here",
            threshold=f"smallest singular value <= {found[4]} * eps * largest")


# ------------------------------------------------------------------------- ODE against DAE

@dataclass
class _Solve:
    w: np.ndarray
    residual: np.ndarray
    iterations: int
    converged: bool


def _dgdw(ev: Evaluator, point: Point, res: list[int], alg: list[int], directional: bool,
          steps: np.ndarray) -> np.ndarray:
    """dg/dw from the FMU (column by column), or central differences without it."""
    n = len(alg)
    out = np.zeros((len(res), n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = 1.0
        if directional:
            out[:, k] = ev.directional(point, res, alg, e)
        else:
            plus = Point(point.t, {**point.values, alg[k]: point.values[alg[k]] + steps[k]})
            minus = Point(point.t, {**point.values, alg[k]: point.values[alg[k]] - steps[k]})
            out[:, k] = (ev.evaluate(plus, res) - ev.evaluate(minus, res)) / (2 * steps[k])
    return out


def _newton(ev: Evaluator, base: Point, res: list[int], alg: list[int], w0: np.ndarray,
            nominal: np.ndarray, noise: np.ndarray, weights: np.ndarray, directional: bool,
            max_iterations: int) -> _Solve:
    """Solve g(t, x, w, u) = 0 for w from w0: Newton with the FMU's dg/dw, halving the step
    while the weighted residual norm does not decrease; converged when every residual is
    within its rounding noise."""
    def point(w: np.ndarray) -> Point:
        return Point(base.t, {**base.values, **dict(zip(alg, w.tolist()))}, base.label)

    positive = weights[weights > 0]
    weights = np.where(weights > 0, weights, positive.min() if positive.size else 1.0)

    def size(g: np.ndarray) -> float:
        return float(np.linalg.norm(g / weights))

    w = np.asarray(w0, dtype=float).copy()
    g = ev.evaluate(point(w), res)
    for it in range(max_iterations):
        if np.all(np.abs(g) <= noise):
            return _Solve(w, g, it, True)
        jac = _dgdw(ev, point(w), res, alg, directional,
                    numdiff.step_sizes(w, nominal, method="central"))
        dw = np.linalg.lstsq(jac, -g, rcond=None)[0]
        lam = 1.0
        while True:
            trial = w + lam * dw
            g_trial = ev.evaluate(point(trial), res)
            if size(g_trial) < size(g) or lam < 1e-4:
                break
            lam /= 2
        w, g = trial, g_trial
        if np.max(np.abs(lam * dw) / nominal) <= 1e-14:
            return _Solve(w, g, it + 1, bool(np.all(np.abs(g) <= 1e3 * noise)))
    return _Solve(w, g, max_iterations, bool(np.all(np.abs(g) <= noise)))


def ode_dae_inconsistent(ctx: ProbeContext, *, rtol: float = 1e-6, margin: float = 10.0,
                         ulps: float = 100.0, max_iterations: int = 20) -> Iterator[Violation]:
    """At the same (t, x, u), the derivatives and outputs of ODE mode equal those of DAE mode
    at the algebraic variables that solve the residuals (DAE-42)."""
    s = _surveyed(ctx)
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
        found = _compare_modes(ctx, s, ps, res_i, cmp_i, alg_j, res, cmp, alg, rtol=rtol,
                               margin=margin, ulps=ulps, max_iterations=max_iterations)
        if found is not None and (worst is None or found[0] > worst[0]):
            worst = found
    if worst is not None:
        yield Violation(
            "ODE mode and DAE mode disagree: at the same time, states and inputs, the "
            "derivatives or outputs of ODE mode differ from those of DAE mode at the algebraic "
            "variables that solve the residuals", layout.rows[res_i[0]].location,
            evidence(worst[1]))


def _compare_modes(ctx, s: Survey, ps: PointSurvey, res_i, cmp_i, alg_j, res, cmp, alg, *,
                   rtol, margin, ulps, max_iterations):
    layout = s.layout
    values = {c.vr: float(v) for c, v in zip(layout.cols, ps.x)
              if c.role in ("state", "input")}
    ode_point = Point(ps.point.t, values, ps.point.label)
    try:
        ode = ctx.ode.evaluate(ode_point, cmp)
    except FmiError:
        return None  # ODE mode cannot evaluate here: the handshake probe reports it
    try:
        w0 = np.asarray(ctx.ode.evaluate(ode_point, alg), dtype=float)
    except FmiError:  # w is not readable in ODE mode: start from the sampling point's w
        w0 = ps.x[alg_j]
    e = ps.entries
    noise = margin * ulps * e.basis
    scale = _row_scale(layout, e)
    base = Point(ps.point.t, {**values, **dict(zip(alg, w0.tolist()))}, ps.point.label)
    try:
        g0 = ctx.dae.evaluate(base, res)
        res_tol = noise[res_i] + rtol * scale[res_i]
        if np.all(np.abs(g0) <= res_tol):
            solve = _Solve(w0, g0, 0, True)
        else:
            solve = _newton(ctx.dae, base, res, alg, w0, layout.nominal[alg_j],
                            noise[res_i], res_tol, s.directional, max_iterations)
        at = Point(base.t, {**base.values, **dict(zip(alg, solve.w.tolist()))}, base.label)
        dae = ctx.dae.evaluate(at, cmp)
    except (FmiError, np.linalg.LinAlgError):
        return None
    tol = rtol * (np.abs(ode) + scale[cmp_i]) + noise[cmp_i]
    diff = np.abs(dae - ode)
    finite = np.isfinite(diff) & np.isfinite(tol)   # non-finite values: nan-or-inf
    if not np.all(np.isfinite(g0)) or np.all(diff[finite] <= tol[finite]) and (
            solve.converged or np.all(np.abs(g0) <= res_tol)):
        return None
    diff = np.where(finite, diff, 0.0)
    k = int(np.argmax(diff / np.maximum(tol, np.finfo(float).tiny)))
    names = [layout.rows[i].name for i in cmp_i]
    return float(diff[k] / tol[k]) if tol[k] > 0 else np.inf, {
        "worst": names[k], "ode": dict(zip(names, ode.tolist())),
        "dae": dict(zip(names, dae.tolist())), "tolerance": dict(zip(names, tol.tolist())),
        "algebraic_ode": dict(zip([layout.cols[j].name for j in alg_j], w0.tolist())),
        "algebraic_dae": dict(zip([layout.cols[j].name for j in alg_j], solve.w.tolist())),
        "residual_at_ode_algebraic": dict(zip([layout.rows[i].name for i in res_i], g0.tolist())),
        "newton_iterations": solve.iterations, "newton_converged": solve.converged,
        "scale": "rtol * (|ODE value| + S_i) + margin * noise, S_i = sum_j |J_ij| * nominal_j",
        "point": _point_evidence(layout, ps)}


PROBES = {
    "DAE740": directional_derivative_mismatch,
    "DAE741": adjoint_derivative_mismatch,
    "DAE742": dependency_undeclared,
    "DAE743": dependency_never_observed,
    "DAE744": dependencies_kind_violated,
    "DAE745": algebraic_jacobian_ill_conditioned,
    "DAE746": algebraic_jacobian_singular,
    "DAE747": ode_dae_inconsistent,
}
