"""The importers' paths into the binary: continuous states set through fmi3SetFloat64.

Importers set the states in two ways. fmusim (through fmi-rs) sets the states and the algebraic
variables in one fmi3SetFloat64 call inside its IDA residual function; others use
fmi3SetContinuousStates. FMI 3.0.2 allows both in Continuous-Time Mode (SG-05 of the digest:
the Continuous-Time Mode table lists fmi3SetFloat64 beside fmi3SetContinuousStates, while the
definition of ``local`` names only the latter). The probes set the same point in DAE mode on two
fresh instances, the states through fmi3SetContinuousStates on one and through fmi3SetFloat64 on
the other, and compare what the FMU gives back (docs/importers.md tells which importer takes
which path):

    state-set-ignored             fmi3OK, but the value is not used (error)
    state-not-settable-by-value   fmi3SetFloat64 on a state is refused (warning)

The measurement is shared by both rules (``ctx.facts``), so the FMU is driven once.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np

from ...report.findings import Violation, evidence
from ...runtime.instance import Instance
from ..instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from ..instruments.common import (close, dae_of, error_evidence, fresh_instance, layout_of,
                                  unknown_location, unknowns_of, var_location)

_FACT = "importer_paths.states"


@dataclass(frozen=True)
class _Paths:
    """Both paths at one point: what each instance gave back."""

    point: Point
    states: tuple[int, ...]
    unknowns: tuple[int, ...]
    reference: np.ndarray                  # fmi3SetContinuousStates: unknowns, then derivatives
    by_value: np.ndarray | None            # fmi3SetFloat64: the same, None if refused
    read_back: np.ndarray | None           # fmi3GetFloat64 of the states after fmi3SetFloat64
    read_back_states: np.ndarray | None    # fmi3GetContinuousStates after fmi3SetFloat64
    refused: FmiError | None


def _point(ctx: ProbeContext) -> Point:
    """A sampled point away from the start, so that a state that keeps its initial value shows."""
    return ctx.points[1] if len(ctx.points) > 1 else ctx.points[0]


def _read(inst: Instance, unknowns: tuple[int, ...], nx: int) -> np.ndarray:
    return np.concatenate([inst.get_float64(list(unknowns)), inst.get_derivatives(nx)])


def _measure(ctx: ProbeContext) -> _Paths | None:
    memo = ctx.facts.get(_FACT)
    if memo is not None or _FACT in ctx.facts:
        return memo  # type: ignore[return-value]
    dae_of(ctx)
    layout = layout_of(ctx)
    states = tuple(layout.states)
    point = _point(ctx)
    if not states or any(vr not in point.values for vr in states):
        ctx.facts[_FACT] = None
        return None
    unknowns = tuple(unknowns_of(layout))
    values = [point.values[vr] for vr in states]
    knowns = [vr for vr in (*layout.algebraic, *layout.inputs) if vr in point.values]
    with fresh_instance(ctx, "dae") as inst:
        try:
            inst.set_point(point)                       # fmi3SetContinuousStates
            reference = _read(inst, unknowns, len(states))
        except FmiError as exc:
            raise ProbeSkipped(f"the point cannot be evaluated through fmi3SetContinuousStates "
                               f"({exc.call} returned {exc.status}; evaluation-failed reports "
                               "it)") from None
    by_value = read_back = read_back_states = None
    refused = None
    with fresh_instance(ctx, "dae") as inst:
        inst.set_time(point.t)
        try:
            inst.set_float64(list(states), values)     # the importers' other path
        except FmiError as exc:
            refused = exc
        if refused is None:
            inst.set_float64(knowns, [point.values[vr] for vr in knowns])
            by_value = _read(inst, unknowns, len(states))
            read_back = inst.get_float64(list(states))
            read_back_states = inst.get_states(len(states))
    paths = _Paths(point, states, unknowns, reference, by_value, read_back, read_back_states,
                   refused)
    ctx.facts[_FACT] = paths
    return paths


# ------------------------------------------------------------------------- state-set-ignored


def state_set_ignored(ctx: ProbeContext, *, rtol: float) -> Iterator[Violation]:
    """fmi3SetFloat64 on the states returns fmi3OK in Continuous-Time Mode (DAE mode), and the
    FMU uses the values: they read back (fmi3GetFloat64, fmi3GetContinuousStates), and the
    residuals, derivatives and outputs equal those of the fmi3SetContinuousStates path."""
    paths = _measure(ctx)
    if paths is None or paths.by_value is None:
        return  # no states, or refused: state-not-settable-by-value
    layout = layout_of(ctx)
    point = paths.point
    set_values = [point.values[vr] for vr in paths.states]
    for what, got in (("fmi3GetFloat64", paths.read_back),
                      ("fmi3GetContinuousStates", paths.read_back_states)):
        assert got is not None
        wrong = [i for i, vr in enumerate(paths.states)
                 if not close(float(got[i]), set_values[i], rtol=rtol, atol=0.0,
                              scale=layout.scale(vr))]
        if wrong:
            first = paths.states[wrong[0]]
            yield Violation(
                "fmi3SetFloat64 on the continuous state {subject} returns fmi3OK in "
                f"Continuous-Time Mode (DAE mode), but {what} gives another value: the FMU "
                "ignores states set by value", var_location(ctx, first),
                evidence(point=point.label, t=point.t, read_with=what,
                         states={layout.name(paths.states[i]): {
                             "set": set_values[i], "read_back": float(got[i])} for i in wrong},
                         rtol=rtol, scale="nominal or magnitude of each state"),
                layout.name(first))
            return
    names = [*(layout.name(vr) for vr in paths.unknowns),
             *(f"fmi3GetContinuousStateDerivatives[{i}]" for i in range(len(paths.states)))]
    vrs = [*paths.unknowns, *layout.derivatives]
    differ = [i for i in range(len(names))
              if np.isfinite(paths.reference[i]) and np.isfinite(paths.by_value[i])
              and not close(float(paths.reference[i]), float(paths.by_value[i]), rtol=rtol,
                            atol=0.0, scale=layout.scale(vrs[i]))]
    if differ:
        first = differ[0]
        where = (unknown_location(ctx, vrs[first]) if first < len(paths.unknowns)
                 else var_location(ctx, paths.states[0]))
        yield Violation(
            "with the states set through fmi3SetFloat64 {subject} differs from its value with "
            "the same states set through fmi3SetContinuousStates (DAE mode, same t, algebraic "
            "variables and inputs): the FMU does not use states set by value",
            where,
            evidence(point=point.label, t=point.t,
                     differences={names[i]: {"fmi3SetContinuousStates": float(paths.reference[i]),
                                             "fmi3SetFloat64": float(paths.by_value[i])}
                                  for i in differ[:10]},
                     rtol=rtol, scale="nominal or magnitude of each value"),
            names[first])


# --------------------------------------------------------------- state-not-settable-by-value


def state_not_settable_by_value(ctx: ProbeContext) -> Iterator[Violation]:
    """fmi3SetFloat64 on the continuous states is accepted in Continuous-Time Mode, DAE mode:
    the path fmusim (fmi-rs) takes."""
    paths = _measure(ctx)
    if paths is None or paths.refused is None:
        return
    layout = layout_of(ctx)
    exc = paths.refused
    first = paths.states[0]
    yield Violation(
        f"fmi3SetFloat64 on the continuous states ({{subject}} first) returns {exc.status} in "
        "Continuous-Time Mode (DAE mode): importers that set the states by value, as fmusim "
        "does through fmi-rs, cannot integrate this FMU; FMI 3.0.2 allows fmi3SetFloat64 "
        "beside fmi3SetContinuousStates there (SG-05)",
        var_location(ctx, first),
        evidence(error_evidence(exc), point=paths.point.label, t=paths.point.t,
                 states=[layout.name(vr) for vr in paths.states],
                 accepted_path="fmi3SetContinuousStates"),
        layout.name(first))


PROBES = {
    "DAE730": state_set_ignored,
    "DAE731": state_not_settable_by_value,
}
