"""Event Mode probes: what fmi3UpdateDiscreteStates promises an importer (DAE734-DAE737).

Every Model Exchange importer calls fmi3UpdateDiscreteStates after initialisation and at each
event, and acts on its output arguments: it stays in Event Mode while discreteStatesNeedUpdate
is true, re-reads the states when valuesOfContinuousStatesChanged is true, and integrates up to
nextEventTime. The walk of ``instruments/event_walk.py`` (one fresh instance per mode) gives the
evidence:

    event-update-invalid            an output argument left unwritten, an iteration that never
                                    settles, or fmi3Error at a legal call (error)
    next-event-time-not-ahead       nextEventTime at or before the current time (error)
    values-stale-after-event        values read in Event Mode after the iteration differ from a
                                    fresh evaluation at the same point (error)
    states-changed-flag-spurious    valuesOfContinuousStatesChanged true while no state changed
                                    (warning)
"""
from __future__ import annotations

from typing import Iterator

import numpy as np

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ...model.description import MODEL_DESCRIPTION
from ...numerics.events import MAX_UPDATES
from ..instruments.api import NEXT_EVENT_FAULT, ProbeContext, ProbeSkipped, noted
from ..instruments.common import close, error_evidence, layout_of, var_location
from ..instruments.event_walk import Walk, walks
from ..instruments.jacobian_layout import MODE_NAMES


def _where(ctx: ProbeContext) -> Location:
    return Location(file=getattr(ctx.model, "file", None) or MODEL_DESCRIPTION)


def _place(mode: str, t: float) -> str:
    """Where a fault was seen: the mode and the event instant (the other mode's sighting of
    the same fault is folded into the first: ``Violation.cause``)."""
    return f"{mode}, t = {t:.10g}"


def _visited(all_walks: list[Walk]) -> None:
    if not any(w.instants or w.initial_next is not None for w in all_walks):
        reasons = "; ".join(f"{MODE_NAMES[w.mode]}: {w.stopped}" for w in all_walks if w.stopped)
        raise ProbeSkipped("no event instant could be reached" + (f" ({reasons})" if reasons
                                                                  else ""))


def event_update_invalid(ctx: ProbeContext) -> Iterator[Violation]:
    """FMI 3.0.2 §2.3.5: fmi3UpdateDiscreteStates writes each output argument (the importer acts
    on all of them), its event iteration settles, and it does not fail at a legal call."""
    all_walks = walks(ctx)
    _visited(all_walks)
    for w in all_walks:
        mode = MODE_NAMES[w.mode]
        for i in w.instants:
            if i.unwritten:
                yield Violation(
                    f"fmi3UpdateDiscreteStates returns fmi3OK at t = {i.t:.10g} ({mode}) without "
                    f"writing {', '.join(i.unwritten)}: an importer reads whatever its variables "
                    "held (a preset true discreteStatesNeedUpdate never ends the iteration)",
                    _where(ctx), evidence(mode=w.mode, t=i.t, unwritten=list(i.unwritten),
                                          call=i.updates, preset="0xA5 (neither false nor "
                                          "true); nextEventTime -7.77e307",
                                          place=_place(mode, i.t)),
                    subject=i.unwritten[0],
                    cause=causes.FAULT.format(
                        f"leaves {i.unwritten[0]} of fmi3UpdateDiscreteStates unwritten"))
                break
            if i.endless:
                yield Violation(
                    f"the event iteration at t = {i.t:.10g} ({mode}) does not settle: "
                    f"fmi3UpdateDiscreteStates still says discreteStatesNeedUpdate after "
                    f"{MAX_UPDATES} calls", _where(ctx),
                    evidence(mode=w.mode, t=i.t, calls=MAX_UPDATES, place=_place(mode, i.t)),
                    subject="discreteStatesNeedUpdate", part="iteration-not-settled",
                    cause=causes.FAULT.format("never settles an event iteration"))
                break
            if i.error is not None:
                yield Violation(
                    f"fmi3UpdateDiscreteStates returns {i.error.status} at t = {i.t:.10g} "
                    f"({mode}), in Event Mode entered from Continuous-Time Mode at the FMU's own "
                    "states: a legal call", _where(ctx),
                    evidence(error_evidence(i.error), mode=w.mode, t=i.t,
                             place=_place(mode, i.t)),
                    subject="fmi3UpdateDiscreteStates", part="update-refused",
                    cause=causes.FAULT.format("refuses fmi3UpdateDiscreteStates at an event"))
                break


def next_event_time_not_ahead(ctx: ProbeContext) -> Iterator[Violation]:
    """FMI 3.0.2 §3.1 (events t_i < t_i+1; a time event is the next one, T_next(t_i-1)), SM-06
    (time never goes back): a defined nextEventTime lies after the current time."""
    all_walks = walks(ctx)
    _visited(all_walks)
    for w in all_walks:
        mode = MODE_NAMES[w.mode]
        seen = [(w.start_time, w.initial_next, "at the end of initialisation")]
        seen += [(i.t, i.next_time, "at the event") for i in w.instants]
        for t, nxt, when in seen:
            if nxt is not None and nxt <= t:
                yield Violation(
                    f"fmi3UpdateDiscreteStates announces nextEventTime = {nxt:.17g} {when} at "
                    f"t = {t:.17g} ({mode}): the next time event must lie ahead, an importer "
                    "cannot go back to it (it skips it, or stops)", _where(ctx),
                    evidence(mode=w.mode, t=t, next_event_time=nxt, behind=t - nxt,
                             place=_place(mode, t)),
                    subject="nextEventTime",
                    cause=causes.NEXT_EVENT_NOT_AHEAD)
                break


def values_stale_after_event(ctx: ProbeContext, *, rtol: float, atol: float
                             ) -> Iterator[Violation]:
    """FMI 3.0.2 §2.3.5 and §3.1: fmi3Get* in Event Mode after fmi3UpdateDiscreteStates gives
    the values of the new discrete state, as a fresh evaluation at the same point does."""
    layout = layout_of(ctx)
    all_walks = walks(ctx)
    _visited(all_walks)
    compared = 0
    for w in all_walks:
        mode = MODE_NAMES[w.mode]
        found = False
        for i in w.instants:
            if i.at_event is None or i.fresh is None:
                continue
            compared += 1
            for vr, a, b in zip(i.vrs, i.at_event, i.fresh):
                if not (np.isfinite(a) and np.isfinite(b)):
                    continue
                if close(float(a), float(b), rtol=rtol, atol=atol, scale=layout.scale(vr)):
                    continue
                yield Violation(
                    f"at the event at t = {i.t:.10g} ({mode}), {{subject}} read in Event Mode "
                    f"right after fmi3UpdateDiscreteStates is {float(a):.17g}; set to the same "
                    f"point again it is {float(b):.17g}: the values read at the event instant "
                    "are not those of the new discrete state", var_location(ctx, vr),
                    evidence(mode=w.mode, t=i.t, at_event=float(a), fresh=float(b),
                             tolerance=atol + rtol * max(layout.scale(vr), abs(a), abs(b)),
                             rtol=rtol, atol=atol, scale="nominal or magnitude"),
                    subject=layout.name(vr), part="dae-mode" if w.mode == "dae" else None)
                found = True
                break
            if found:
                break
    if not compared:
        raise ProbeSkipped("no event iteration completed: nothing to compare")


def states_changed_flag_spurious(ctx: ProbeContext) -> Iterator[Violation]:
    """FMI 3.0.2 §2.3.5: valuesOfContinuousStatesChanged true means at least one continuous
    state changed its value (FMI 2.0 said the FMU must return false otherwise)."""
    all_walks = walks(ctx)
    _visited(all_walks)
    for w in all_walks:
        mode = MODE_NAMES[w.mode]
        for i in w.instants:
            before, after = i.states_before, i.states_after
            if not i.values_changed or before is None or after is None or not len(before):
                continue
            if np.array_equal(before, after):
                yield Violation(
                    f"fmi3UpdateDiscreteStates says valuesOfContinuousStatesChanged at "
                    f"t = {i.t:.10g} ({mode}), but every state holds the value it had before "
                    "the event: an importer re-initialises its integrator at every such event",
                    _where(ctx), evidence(mode=w.mode, t=i.t, states=[float(v) for v in after],
                                          place=_place(mode, i.t)),
                    subject="valuesOfContinuousStatesChanged",
                    cause=causes.FAULT.format(
                        "says valuesOfContinuousStatesChanged when no state changed"))
                break


PROBES = {
    "DAE734": event_update_invalid,
    "DAE735": noted(NEXT_EVENT_FAULT, "DAE735", next_event_time_not_ahead),
    "DAE736": values_stale_after_event,
    "DAE737": states_changed_flag_spurious,
}
