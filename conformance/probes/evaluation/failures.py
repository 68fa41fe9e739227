"""The evaluation probes: non-finite values (``nan-or-inf``), evaluations that fail
(``evaluation-failed``) and inputs that cannot be set (``input-not-settable``); setting the
algebraic variables, the start and repeatability are in basic.py, whose docstring gives the
one-fault-one-finding split between them: here ``evaluation-failed`` owns time and states,
``input-not-settable`` the inputs, and a call on an instance already Terminated (SM-04) is
nobody's finding.
"""
from __future__ import annotations

import math
from typing import Any, Iterator

import numpy as np

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ..instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from ..instruments.common import (dae_of, error_evidence, layout_of, new_instance, renew,
                                  root_location, unknown_location, unknowns_of, var_location)
from ..instruments.instantiation import expected_starts
from .readable import Fault, sweep
from ...runtime.instance import Instance, KnownNotSet, PointNotSet
from ...runtime.layout import Layout

# ------------------------------------------------------------------------------- nan-or-inf


def nan_or_inf(ctx: ProbeContext, *, directional: bool) -> Iterator[Violation]:
    """No NaN or Inf at any sampled point: residuals, derivatives, outputs and algebraic
    variables in DAE mode; derivatives, outputs and algebraic variables in ODE mode; and, when
    the FMU provides directional derivatives, J @ 1 in DAE mode (every known at once, so a
    single non-finite partial shows)."""
    layout = layout_of(ctx)
    if ctx.dae is None and ctx.ode is None:
        dae_of(ctx)
    found: dict[str, dict[str, Any]] = {}
    initial = Point(0.0, {}, "start (as initialised)")
    for vr, v in dict(ctx.facts.get("start_nonfinite") or {}).items():  # see start_point
        _note(found, layout.name(vr), var_location(ctx, vr),
              "dae" if ctx.dae is not None else "ode", initial, v)
    for mode, inst in (("dae", ctx.dae), ("ode", ctx.ode)):
        if inst is None:
            continue
        unknowns = list(dict.fromkeys([*unknowns_of(layout, mode), *layout.algebraic]))
        for point in ctx.points:
            try:
                values = inst.evaluate(point, unknowns)
            except (FmiError, PointNotSet):
                continue  # evaluation-failed, algebraic-not-settable, enable-handshake (ODE)
            for vr, v in zip(unknowns, values):
                if not math.isfinite(v):
                    _note(found, layout.name(vr), var_location(ctx, vr), mode, point, v)
    dae = ctx.dae
    if directional and layout.provides_directional and dae is not None:
        _directional(ctx, layout, dae, found)
    for subject, item in found.items():
        yield Violation(
            f"{item['what']} {{subject}} is {item['value']} at {len(item['points'])} sampled "
            f"point(s), first at {item['points'][0]} ({item['mode']} mode)", item["location"],
            evidence(points=item["points"], value=item["value"], mode=item["mode"],
                     first_point={"label": item["first"].label, "t": item["first"].t}),
            subject)


def _note(found: dict[str, dict[str, Any]], subject: str, location: Location, mode: str,
          point: Point, value: float, what: str = "") -> None:
    item = found.setdefault(subject, {
        "what": what or "the value of", "location": location, "mode": mode, "points": [],
        "value": repr(float(value)), "first": point})
    if point.label not in item["points"]:
        item["points"].append(point.label)


def _directional(ctx: ProbeContext, layout: Layout, dae: Instance,
                 found: dict[str, dict[str, Any]]) -> None:
    unknowns = unknowns_of(layout)
    knowns = list(dict.fromkeys([*layout.states, *layout.algebraic, *layout.inputs]))
    if not unknowns or not knowns:
        return
    seed = np.ones(len(knowns))
    for point in ctx.points:
        try:
            column = dae.directional(point, unknowns, knowns, seed)
        except (FmiError, PointNotSet):
            return  # the derivative probes report a failing fmi3GetDirectionalDerivative
        for vr, v in zip(unknowns, column):
            if not math.isfinite(v):
                _note(found, f"d({layout.name(vr)})", unknown_location(ctx, vr), "dae", point,
                      v, what="the directional derivative (all knowns seeded with 1)")


# -------------------------------------------------------------------------- evaluation-failed


def evaluation_failed(ctx: ProbeContext) -> Iterator[Violation]:
    """DAE-41: in DAE mode, at every sampled point, time and states can be set and the
    residuals, derivatives and outputs read (fmi3GetFloat64, fmi3GetContinuousStateDerivatives).
    A rejected input is input-not-settable's finding, a rejected algebraic variable
    algebraic-not-settable's: the probe is skipped. The first failing call at a point is the
    finding; it put the instance in Terminated (SM-04), so the next point is evaluated on a
    fresh instance, and a call that fails after an earlier failure on the same instance is
    not reported. Before the points, every variable FMI 3.0 lets an importer read is read once
    in each state, in both modes (:mod:`.readable`)."""
    layout = layout_of(ctx)
    found = False
    for violation in _read_back(ctx, layout):
        found = True
        yield violation
    if ctx.dae is None and (found or layout.enable_status == "no-layer"):
        return
    dae = dae_of(ctx)
    unknowns = unknowns_of(layout)
    for point in ctx.points:
        if getattr(dae, "failure", None) is not None:
            dae = renew(ctx, "dae")
            if dae is None:
                return
        try:
            dae.set_point(point, algebraic=False)
        except FmiError as exc:
            kind = exc.kind if isinstance(exc, KnownNotSet) else ""
            if exc.after is not None or kind not in ("time", "states"):
                raise PointNotSet(point, exc) from None  # not a fault of time or states
            yield Violation(
                f"setting the {kind} in DAE mode fails at point {point.label}: "
                f"{exc.call} returned {exc.status}", root_location(ctx),
                evidence(error_evidence(exc), point=point.label, t=point.t, setting=kind,
                         mode="DAE mode, Continuous-Time Mode"), subject=exc.call,
                cause=causes.failing("Continuous-Time Mode", "DAE mode"))
            continue
        try:
            dae.set_algebraic(point)
        except FmiError as exc:  # algebraic-not-settable reports it
            raise PointNotSet(point, exc) from None
        for read, arg in ((dae.get_float64, unknowns), (dae.get_derivatives, len(layout.states))):
            try:
                read(arg)
            except FmiError as exc:
                if exc.after is not None:
                    raise ProbeSkipped(exc.cause()) from None
                yield Violation(
                    f"reading the residuals, derivatives and outputs in DAE mode fails at "
                    f"point {point.label}: {exc.call} returned {exc.status}",
                    root_location(ctx),
                    evidence(error_evidence(exc), point=point.label, t=point.t,
                             unknowns=[layout.name(vr) for vr in unknowns]),
                    subject=exc.call, cause=causes.failing("Continuous-Time Mode", "DAE mode"))
                break


_SPEC = {"Instantiated": "SG-01", "Initialization Mode": "SG-03", "Event Mode": "SG-04",
         "Continuous-Time Mode": "SG-05"}
_PROBLEM = {"unwritten": "returns fmi3OK but leaves its element of the caller's array "
                         "unwritten (the FMU answers for fewer values than it is asked for)",
            "nan": "returns NaN"}


def _read_back(ctx: ProbeContext, layout: Layout) -> Iterator[Violation]:
    """Every readable variable, once per state and mode: one finding per variable and problem
    (the first state it shows in, the others in the evidence). NaN in a residual, derivative,
    output or algebraic variable is nan-or-inf's, NaN against a start value in Instantiated
    start-value-not-applied's."""
    library = ctx.facts["library"]
    by_subject: dict[tuple[int, str], list[Fault]] = {}
    for mode in layout.modes:
        owned = {*unknowns_of(layout, mode), *layout.algebraic}
        result = sweep(lambda label: new_instance(library, label), ctx.model, mode)
        for fault in result.faults:
            var = fault.item.var
            if fault.problem == "nan" and (var.vr in owned or (
                    fault.state == "Instantiated" and expected_starts(ctx.model, var))):
                continue
            by_subject.setdefault((fault.item.vr, fault.problem), []).append(fault)
    for (vr, problem), faults in by_subject.items():
        # a refusal or an unwritten element in DAE mode's Initialization Mode, which alpha.1
        # leaves open, is its own sub-check only when it shows nowhere else
        judged = [f for f in faults if not (f.mode == "dae" and f.state == "Initialization Mode")]
        if problem == "nan":
            yield _read_back_finding(ctx, vr, problem, faults, part="nan-read-back")
        elif not judged:
            yield _read_back_finding(ctx, vr, problem, faults, part="dae-mode-initialization")
        elif problem == "unwritten":
            yield _read_back_finding(ctx, vr, problem, faults, part="unwritten")
        elif judged[0].state == "Instantiated":
            yield _read_back_finding(ctx, vr, problem, faults, part="refused-in-instantiated")
        else:
            yield _read_back_finding(ctx, vr, problem, faults,
                                     part="refused-after-initialization")


def _read_back_finding(ctx: ProbeContext, vr: int, problem: str, faults: list[Fault], *,
                       part: str) -> Violation:
    """One variable's finding: the first state and mode it shows in, the others in the
    evidence."""
    first = faults[0]
    where = [f"{f.state}, {f.mode.upper()} mode" for f in faults]
    more = f" (and {len(where) - 1} other state(s) or mode(s))" if len(where) > 1 else ""
    verb = _PROBLEM.get(problem, f"returns {first.status}")
    return Violation(
        f"{first.call} of {{subject}} {verb} in {where[0]}{more}, where FMI 3.0 lets an "
        f"importer read it ({_SPEC[first.state]})", var_location(ctx, vr),
        evidence(call=first.call, status=first.status, log=list(first.log), problem=problem,
                 state=first.state, mode=f"{first.mode.upper()} mode", where=where,
                 value_reference=vr, type=first.item.var.type, element=first.element,
                 causality=first.item.var.causality,
                 variability=first.item.var.variability),
        first.item.var.name, part=part, cause=_read_back_cause(first.item.var.name, problem,
                                                               faults))


def _read_back_cause(name: str, problem: str, faults: list[Fault]) -> tuple[str, ...]:
    """A read-back finding's cause: the variable, and, for a refusal or an unwritten element,
    each state and mode it shows in (the call that stops the FMU's run there fails too, and so
    do the reads of other variables there)."""
    keys = [causes.through(name)]
    if problem != "nan":
        keys += [causes.failing(f.state, f"{f.mode.upper()} mode") for f in faults]
    return tuple(dict.fromkeys(keys))


# ------------------------------------------------------------------------ input-not-settable


def input_not_settable(ctx: ProbeContext) -> Iterator[Violation]:
    """SG-05: in Continuous-Time Mode every continuous input accepts fmi3SetFloat64, in DAE
    mode and in ODE mode. Each input is set on its own, to its value at the start point; a
    refusal names the call, the input, its value reference, the mode and the FMU's log. A
    refused call puts the instance in Terminated (SM-04): the next input is tried on a fresh
    instance."""
    layout = layout_of(ctx)
    if not layout.inputs:
        return
    if ctx.dae is None and ctx.ode is None:
        dae_of(ctx)  # ProbeSkipped: no mode could be started
    start = ctx.points[0]
    for mode in ("dae", "ode"):
        inst = getattr(ctx, mode)
        for vr in layout.inputs:
            if inst is None:
                break
            value = start.values.get(vr, layout.start.get(vr, 0.0))
            try:
                inst.set_float64([vr], [value])
            except FmiError as exc:
                if exc.after is not None:
                    raise ProbeSkipped(exc.cause()) from None
                yield Violation(
                    f"fmi3SetFloat64 on the continuous input {{subject}} (valueReference {vr}) "
                    f"returns {exc.status} in {mode.upper()} mode, Continuous-Time Mode, where "
                    "FMI 3.0 allows setting it (SG-05)", var_location(ctx, vr),
                    evidence(error_evidence(exc), value_reference=vr, value=value,
                             mode=f"{mode.upper()} mode", state="Continuous-Time Mode",
                             point=start.label), layout.name(vr),
                    cause=causes.through(layout.name(vr)))
                if getattr(inst, "failure", None) is not None:
                    inst = renew(ctx, mode)


PROBES = {
    "DAE723": nan_or_inf,
    "DAE724": evaluation_failed,
    "DAE725": input_not_settable,
}
