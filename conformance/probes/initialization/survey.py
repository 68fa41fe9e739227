"""The Initialization-Mode survey read by the InitialUnknown probes (unknowns.py).

The rows, columns and declared sparsity come from :mod:`.layout`; the fresh instances
and their budget from :mod:`.instances`.

**Points.** The XML start values at the default start time, then seeded perturbations of
:func:`conformance.probes.instruments.sampling.near_points` (``STEP`` times each known's nominal
scale, within its ``min``/``max``, time forward only), drawn from a generator of its own seeded with
the run's seed, so that no other probe's points depend on whether these ran.

**Measuring.** Every function value is a fresh instance (``ctx.new_initialization``,
:func:`conformance.runtime.modes.start_initialization`): configured, the knowns set as start
values in Instantiated, fmi3EnterInitializationMode at the point's time, fmi3GetFloat64 of the
rows, freed. :func:`conformance.numerics.measure.measure` colours the columns by the declared
sparsity and verifies the declared zeros, as in Continuous-Time Mode; the FMU's directional
derivatives, when it provides them, come from one more instance per point, left in
Initialization Mode while the point is measured. ``max_instances`` bounds the instances over all
points: a point that would not fit is not measured, and one that runs out is dropped.
The survey is measured once per FMU and mode (DAE mode: the manifest's list; ODE mode:
modelDescription's, see :mod:`.layout`) and kept in ``ctx.facts``; ``max_instances``
bounds the surveys of both modes together, DAE mode first, and ``max_seconds`` each mode's (two
modes stay within the probe time limit of binary-timed-out). After a call returned fmi3Fatal no
survey calls the FMU again (SM-04).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...report.catalogue import default_catalogue
from ...numerics import colouring as col
from ...numerics import measure, numdiff
from ...runtime.layout import Layout
from ..instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from .instances import Factory, InitialPoint, InstanceCounter, OutOfTime, OverBudget, SurveySettings
from .layout import build_initial_layout, start_time
from ..instruments.jacobian import PointSurvey, Settings, Survey
from ..instruments.jacobian_layout import JacobianLayout
from ..instruments.sampling import near_points

FACT = "initial.survey"                   # DAE mode; ODE mode under FACT + ".ode"
SETTINGS_FACT = "initial.settings"
COUNTER_FACT = "initial.counter"          # the budget, shared by the modes' surveys
OWNER = "initial-dependency-undeclared"   # the rule whose options set the survey
SEED_SALT = 750
MEASURING = Settings()                    # how to measure: as in Continuous-Time Mode


@dataclass
class InitialSurvey(Survey):
    """A :class:`~conformance.probes.instruments.jacobian.Survey` of Initialization Mode: also the
    mode and the file whose list was verified, and the instances spent."""

    file: str = ""
    instances: int = 0
    budget_stop: str = ""
    out_of_time: str = ""     # the wall-clock safety net ran out: nothing may be judged
    fatal: str = ""           # a call returned fmi3Fatal: why the survey stopped
    interference: str = ""    # the instance kept open lost its values to the others
    # what confirm() needs: the instance factory and what is left of the budget
    factory: Any = field(default=None, repr=False, compare=False)
    counter: Any = field(default=None, repr=False, compare=False)
    confirmed: dict = field(default_factory=dict, repr=False, compare=False)


def settings_of(ctx: ProbeContext) -> SurveySettings:
    """The options given to the owner rule, else its catalogue defaults."""
    settings = ctx.facts.get(SETTINGS_FACT)
    if not isinstance(settings, SurveySettings):
        rule = default_catalogue().get(OWNER)
        values = rule.option_values if rule else {}
        settings = SurveySettings(int(values["points"]), int(values["max_instances"]),
                                  float(values["max_seconds"]))
        ctx.facts[SETTINGS_FACT] = settings
    return settings


def _key(mode: str) -> str:
    return FACT if mode == "dae" else f"{FACT}.{mode}"


def initial_survey(ctx: ProbeContext, mode: str = "dae") -> InitialSurvey:
    """The Initialization-Mode Jacobian of ``mode`` at every point, once per FMU (memoised)."""
    key = _key(mode)
    memo = ctx.facts.get(key)
    if isinstance(memo, InitialSurvey):
        return memo
    result = _run(ctx, settings_of(ctx), mode)
    ctx.facts[key] = result
    return result


def surveyed(ctx: ProbeContext, *, min_points: int = 1, mode: str = "dae") -> InitialSurvey:
    """The survey of ``mode``, or ProbeSkipped with the reason it has nothing to compare."""
    s = initial_survey(ctx, mode)
    if s.out_of_time:
        raise ProbeSkipped(s.out_of_time)
    if s.layout is None:
        raise ProbeSkipped(s.reason)
    if len(s.points) < min_points:
        why = s.reason or s.budget_stop or _failure(s) or "the other points failed"
        raise ProbeSkipped(f"{len(s.points)} point(s) could be measured in Initialization "
                           f"Mode, {min_points} needed: {why}" if s.points else why)
    return s


def _points(t0: float, layout: Layout, start: dict[int, float], count: int,
            rng: np.random.Generator) -> list[Point]:
    first = Point(t0, dict(start), "start")
    return [first, *near_points(first, layout, rng, count=max(0, count - 1))]


def _run(ctx: ProbeContext, settings: SurveySettings, mode: str) -> InitialSurvey:
    runtime_layout: Layout | None = ctx.facts.get("layout")  # type: ignore[assignment]
    if runtime_layout is None or ctx.new_initialization is None:
        return InitialSurvey(None, "the binary is not loaded", mode=mode)
    jl, start, reason = build_initial_layout(ctx, runtime_layout, mode)
    if jl is None:
        return InitialSurvey(None, reason, mode=mode)
    fatal = next((memo.fatal for memo in map(ctx.facts.get, map(_key, ("dae", "ode")))
                  if isinstance(memo, InitialSurvey) and memo.fatal), "")
    if fatal or getattr(ctx.facts.get("library"), "fatal", False):
        fatal = fatal or "an FMI call returned fmi3Fatal: no instance may be called (SM-04)"
        return InitialSurvey(None, fatal, mode=mode, fatal=fatal)
    me = ctx.model.model_exchange if ctx.model is not None else None
    result = InitialSurvey(jl, directional=bool(me and me.flag("providesDirectionalDerivatives")),
                           mode=mode, file=jl.rows[0].location.file or "")
    rng = np.random.default_rng((ctx.seed, SEED_SALT))
    points = _points(start_time(ctx.model, runtime_layout), runtime_layout, start,
                     settings.points, rng)
    colouring = col.colour_columns(jl.pattern)
    per_point = 1 + numdiff.CALLS_PER_DIRECTION[MEASURING.method] * (
        colouring.count + MEASURING.directions)
    counter = ctx.facts.setdefault(COUNTER_FACT, InstanceCounter(settings))
    counter.restart_clock()
    result.factory, result.counter = ctx.new_initialization, counter
    for point in points:
        need = per_point + (1 if result.directional else 0)
        if counter.left < need:
            result.budget_stop = (f"max_instances = {settings.max_instances} leaves room for "
                                  f"{len(result.points)} point(s); one needs about {need} "
                                  "fresh instances")
            break
        try:
            measured = _measure_point(ctx.new_initialization, mode, jl, point, result, colouring,
                                      rng, counter)
        except OutOfTime:
            result.out_of_time = counter.why
            break
        except OverBudget:
            result.budget_stop = (f"{counter.why} while point {point.label} was measured, "
                                  f"after {len(result.points)} point(s)")
            break
        except ProbeSkipped as exc:  # the runtime cannot go on (a call blocked after a hang)
            result.reason = str(exc)
            break
        if result.fatal:  # no call at all after fmi3Fatal (SM-04): the stage starts afresh
            result.reason = result.fatal
            break
        if measured is not None:
            result.points.append(measured)
    result.instances = counter.used
    if not result.points and not result.reason:
        result.reason = (result.budget_stop or _failure(result)
                         or "no point could be measured in Initialization Mode")
    return result


def _measure_point(factory: Factory, mode: str, layout: JacobianLayout, point: Point,
                   result: InitialSurvey, colouring: col.Colouring, rng: np.random.Generator,
                   counter: InstanceCounter) -> PointSurvey | None:
    at = InitialPoint(factory, mode, layout, point, counter)
    lower = np.array([c.lower for c in layout.cols])
    upper = np.array([c.upper for c in layout.cols])
    steps = numdiff.step_sizes(at.x, layout.nominal, method=MEASURING.method, lower=lower,
                               upper=upper)
    try:
        if result.directional:
            at.base = at.open(np.zeros(len(layout.cols)))
            if not result.probed:
                try:  # one probing call, so that a refusal is known before measuring
                    at.directional(np.zeros(len(layout.cols)))
                except FmiError as exc:
                    result.failures.append(("directional", point, exc))
                    result.directional = False
                    _note_fatal(result, exc)
                result.probed = True
                if result.fatal:
                    return None
        sources = measure.Sources(at.fun, at.directional if result.directional else None,
                                  None, layout.dd_columns)
        entries = measure.measure(sources, layout.pattern, colouring, steps, at.x, rng,
                                  method=MEASURING.method, directions=MEASURING.directions,
                                  suspicion=MEASURING.suspicion, ulps=MEASURING.ulps)
        if at.base is not None and not result.interference:
            _check_independent(at, entries.f0, point, result)
    except FmiError as exc:
        result.failures.append(("evaluate", point, exc))
        _note_fatal(result, exc)
        return None
    finally:
        if at.base is not None:
            at.base.free()
    return PointSurvey(point, at.x, entries)


def _check_independent(at: InitialPoint, f0: np.ndarray, point: Point,
                       result: InitialSurvey) -> None:
    """The directional derivatives come from an instance kept open while fresh ones give the
    function values: if it no longer holds the values a fresh instance computes at its point,
    the instances share state, its derivatives are taken elsewhere, and no verdict may rest on
    them (instances-not-independent reports the cause)."""
    held = np.asarray(at.base.get_float64(at.rows), dtype=float)
    scale = np.maximum(np.maximum(np.abs(held), np.abs(f0)), 1.0)
    off = np.abs(held - f0) > 1e-8 * scale
    if np.any(off):
        k = int(np.argmax(np.abs(held - f0) / scale))
        result.interference = (
            f"the instance kept open at point {point.label} no longer holds its values once "
            f"other instances were created ({at.layout.rows[k].name}: {held[k]:.9g} instead of "
            f"{f0[k]:.9g}): the FMU's instances share state (instances-not-independent), so "
            "its directional derivatives here cannot be judged")


def confirm(s: InitialSurvey, ps: PointSurvey, j: int, *, factor: float, ulps: float
            ) -> tuple[np.ndarray, np.ndarray] | None:
    """Column ``j`` at the point of ``ps`` measured again with central differences at
    ``factor`` times the survey's step: (values, error bounds), shape (m,), per unit of the
    known; None when it cannot be (no room within the bounds, the budget spent, the FMU failed).

    The unknowns of Initialization Mode come out of the FMU's own solver, whose error can be
    far above the rounding noise the error estimate assumes (an ill-conditioned dg/dw amplifies
    it) and correlated over a step, so that two step sizes may agree by chance. A finding is
    only reported when it holds at a step ``factor`` times larger too, where that noise weighs
    ``factor`` times less and the truncation error is estimated again.
    """
    key = (ps.point.label, j, factor)
    if key in s.confirmed:
        return s.confirmed[key]
    layout = s.layout
    assert layout is not None
    lower = np.array([c.lower for c in layout.cols])
    upper = np.array([c.upper for c in layout.cols])
    scale = factor * np.maximum(np.abs(ps.x), layout.nominal)
    steps = numdiff.step_sizes(ps.x, scale, method=MEASURING.method, lower=lower, upper=upper)
    out = None
    if steps[j] > 0 and s.counter is not None and not s.fatal:
        at = InitialPoint(s.factory, s.mode, layout, ps.point, s.counter)
        direction = np.zeros(len(layout.cols))
        direction[j] = steps[j]
        try:
            diff = numdiff.difference(at.fun, direction, method=MEASURING.method)
        except FmiError as exc:
            _note_fatal(s, exc)
        except OutOfTime:  # a finding it would have confirmed or cleared: no verdict at all
            s.out_of_time = s.counter.why
            raise ProbeSkipped(s.out_of_time) from None
        except (OverBudget, ProbeSkipped):
            pass
        else:
            noise = ulps * ps.entries.basis
            out = (diff.value / steps[j], diff.error(noise) / steps[j])
    s.confirmed[key] = out
    return out


def _note_fatal(s: InitialSurvey, exc: FmiError) -> None:
    if exc.status == "fmi3Fatal" and not s.fatal:
        s.fatal = (f"{exc.call} returned fmi3Fatal in Initialization Mode: no instance may be "
                   "called after it (SM-04)")


def _failure(s: InitialSurvey) -> str:
    """Why the first point that failed failed, in words ("" if none did)."""
    for what, point, exc in s.failures:
        if what != "evaluate":
            continue
        first = f": {exc.log[0]}" if exc.log else ""
        if exc.call == "fmi3SetFloat64":
            why = "the FMU rejects the start values of the knowns of Initialization Mode"
        elif exc.call == "fmi3EnterInitializationMode" and s.mode == "dae":
            why = "the FMU refuses to initialise in DAE mode (alpha.1 allows it, DAE-14)"
        else:
            why = "Initialization Mode could not be evaluated"
        return f"{why}: {exc.call} returned {exc.status} at point {point.label}{first}"
    return ""
