"""The handshake probes: switching DAE mode on and off (``enable-handshake``), a refused
initialisation in DAE mode (``dae-initialization-refused``, information under alpha.1), and
fmi3Reset returning the instance to its start values and ODE mode (``reset-incomplete``).

Each probe opens its own instances from the loaded :class:`~conformance.runtime.library.Library`
(``ctx.facts["library"]``) and walks the FMI calls one by one, so a finding names the call that
failed and the sequence before it.
"""
from __future__ import annotations

import math
from typing import Any, Iterator

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ..instruments.api import FmiError, ProbeContext, ProbeSkipped
from ..instruments.common import (close, error_evidence, layout_of, manifest_location, new_instance,
                                  var_location)
from ..instruments.instantiation import Held, instantiated_values, read_held
from ...runtime.errors import Unsettled
from ...runtime.instance import MAX_START_UPDATES, Instance, KnownNotSet
from ...runtime.layout import Layout
from ...runtime.library import Library
from ...runtime.modes import INIT_CALLS, configure, reconfigure

# -------------------------------------------------------------------------- enable-handshake


class _Steps:
    """Runs the calls of a handshake one by one and remembers how far it got."""

    def __init__(self) -> None:
        self.done: list[str] = []
        self.trying = ""     # the step in progress (the one that failed, after an FmiError)

    def __call__(self, label: str, fn: Any, *args: Any) -> Any:
        self.trying = label
        result = fn(*args)
        self.done.append(label)
        return result


def enable_handshake(ctx: ProbeContext) -> Iterator[Violation]:
    """DAE-12, DAE-13, DAE-11: switch DAE mode on in Configuration Mode (and, for a tunable
    switch, off and on again in Reconfiguration Mode); with the switch false, run as an ODE FMU.

    An fmi3Error from fmi3Enter/ExitInitializationMode in DAE mode is not reported here: alpha.1
    allows it (DAE-14), and ``dae-initialization-refused`` reports it as information.
    """
    layout = layout_of(ctx)
    library: Library = ctx.facts["library"]  # type: ignore[assignment]
    if layout.enable_status == "unusable":
        raise ProbeSkipped("the enable parameter cannot be used (see the static findings)")
    where = manifest_location(ctx, layout.enable, ("Enable",))
    subject = layout.name(layout.enable) if layout.enable is not None else None
    yield from _dae_handshake(ctx, layout, library, where, subject)
    if layout.enable is not None:
        yield from _ode_handshake(ctx, layout, library, where, subject)


def _dae_handshake(ctx: ProbeContext, layout: Layout, library: Library, where: Location,
                   subject: str | None) -> Iterator[Violation]:
    steps = _Steps()
    vr = layout.enable
    inst = None
    try:
        inst = steps("fmi3InstantiateModelExchange", new_instance, library, "handshake-dae")
        if vr is not None:
            steps("fmi3EnterConfigurationMode", inst.enter_configuration_mode)
            steps("fmi3SetBoolean(true)", inst.set_boolean, vr, True)
            steps("fmi3ExitConfigurationMode", inst.exit_configuration_mode)
        try:
            steps("fmi3EnterInitializationMode", inst.enter_initialization_mode,
                  layout.start_time)
            if vr is not None and not steps("fmi3GetBoolean", inst.get_boolean, vr):
                yield Violation(
                    "the enable parameter {subject} reads back false in Initialization Mode "
                    "after fmi3SetBoolean(true) in Configuration Mode", where,
                    evidence(sequence=steps.done, expected=True, actual=False), subject,
                    part="switch-read-back")
                return
            steps("fmi3ExitInitializationMode", inst.exit_initialization_mode)
        except FmiError as exc:
            if exc.call in INIT_CALLS:
                return  # DAE-14: allowed under alpha.1, reported by dae-initialization-refused
            raise
        steps("fmi3UpdateDiscreteStates", inst.update_discrete_states)
        if vr is not None and layout.enable_tunable:
            yield from _reconfigure(inst, vr, steps, where, subject)
        steps("fmi3EnterContinuousTimeMode", inst.enter_continuous_time_mode)
        steps("fmi3GetContinuousStateDerivatives", inst.get_derivatives,
              len(layout.states))
    except Unsettled as exc:   # an importer would loop in Event Mode for ever
        yield Violation(
            f"switching DAE mode on fails: {exc}", where,
            evidence(call="fmi3UpdateDiscreteStates", sequence=steps.done, mode="dae",
                     calls=MAX_START_UPDATES), subject, cause=UNSETTLED)
    except FmiError as exc:
        # the tunable switch refused in Reconfiguration Mode (entering it from Event Mode,
        # the set, or leaving it): not the switch at instantiation
        refused = steps.trying.startswith(RECONFIGURE)
        yield Violation(
            f"switching DAE mode on fails: {exc.call} returned {exc.status} after "
            f"{' -> '.join(steps.done) or 'nothing'}", where,
            evidence(error_evidence(exc), sequence=steps.done, mode="dae"), subject,
            part="reconfiguration-refused" if refused else None)
    finally:
        if inst is not None:
            inst.free()


RECONFIGURE = "fmi3EnterConfigurationMode (Reconfiguration"
#: One cause: the event iteration after initialisation does not settle, in either mode.
UNSETTLED = "the event iteration after initialisation does not settle"


def _reconfigure(inst: Instance, vr: int, steps: _Steps, where: Location,
                 subject: str | None) -> Iterator[Violation]:
    """DAE-13: Event Mode -> Reconfiguration Mode, switch off and on again, read back."""
    for value in (False, True):
        steps(f"{RECONFIGURE}, set {str(value).lower()})", reconfigure, inst, value)
        if steps("fmi3GetBoolean", inst.get_boolean, vr) != value:
            yield Violation(
                "the tunable enable parameter {subject} does not read back "
                f"{str(value).lower()} after it was set in Reconfiguration Mode", where,
                evidence(sequence=steps.done, expected=value, actual=not value), subject,
                part="switch-read-back")


def _ode_handshake(ctx: ProbeContext, layout: Layout, library: Library, where: Location,
                   subject: str | None) -> Iterator[Violation]:
    """DAE-11: with the switch false (its start value), an ordinary Model Exchange FMU."""
    steps = _Steps()
    inst = None
    point = None
    try:
        inst = steps("fmi3InstantiateModelExchange", new_instance, library, "handshake-ode")
        steps("fmi3EnterInitializationMode", inst.enter_initialization_mode, layout.start_time)
        if steps("fmi3GetBoolean", inst.get_boolean, layout.enable):
            yield Violation(
                "the enable parameter {subject} reads true after instantiation: an FMU must "
                "start in ODE mode", where, evidence(sequence=steps.done, expected=False,
                                                     actual=True), subject,
                part="switch-true-at-start")
        steps("fmi3ExitInitializationMode", inst.exit_initialization_mode)
        steps("fmi3UpdateDiscreteStates", inst.update_discrete_states)
        steps("fmi3EnterContinuousTimeMode", inst.enter_continuous_time_mode)
        for point in ctx.points:
            inst.set_point(point)
            steps(f"fmi3GetContinuousStateDerivatives at {point.label}", inst.get_derivatives,
                  len(layout.ode_states))
    except Unsettled as exc:   # an importer would loop in Event Mode for ever
        yield Violation(
            f"with the enable parameter false the FMU does not run as an ordinary ODE FMU: {exc}",
            where, evidence(call="fmi3UpdateDiscreteStates", sequence=steps.done, mode="ode",
                            calls=MAX_START_UPDATES), subject, part="ode-run-fails",
            cause=UNSETTLED)
    except FmiError as exc:
        if isinstance(exc, KnownNotSet) and exc.kind == "inputs":
            return  # an input refused in ODE mode is input-not-settable's finding
        at = f" at point {point.label}" if point is not None else ""
        yield Violation(
            f"with the enable parameter false the FMU does not run as an ordinary ODE FMU: "
            f"{exc.call} returned {exc.status}{at}", where,
            evidence(error_evidence(exc), sequence=steps.done, mode="ode",
                     point=point.label if point else None), subject, part="ode-run-fails",
            cause=causes.failing(_STATE_AT.get(exc.call, "Continuous-Time Mode" if point
                                               else "Initialization Mode"), "ODE mode"))
    finally:
        if inst is not None:
            inst.free()


#: The state an instance is in when a call of the handshake's sequence fails: a run that stops
#: there and the reads refused there are one defect (``causes.failing``).
_STATE_AT = {"fmi3EnterInitializationMode": "Instantiated",
             "fmi3ExitInitializationMode": "Initialization Mode",
             "fmi3UpdateDiscreteStates": "Event Mode", "fmi3EnterContinuousTimeMode": "Event Mode"}


# ---------------------------------------------------------------- dae-initialization-refused


def dae_initialization_refused(ctx: ProbeContext) -> Iterator[Violation]:
    """DAE-14: fmi3Enter/ExitInitializationMode returns an error in DAE mode (information)."""
    layout = layout_of(ctx)
    library: Library = ctx.facts["library"]  # type: ignore[assignment]
    if layout.enable_status == "unusable":
        raise ProbeSkipped("the enable parameter cannot be used (see the static findings)")
    inst = new_instance(library, "init-dae")
    try:
        if layout.enable is not None:
            configure(inst, True)
        inst.enter_initialization_mode(layout.start_time)
        inst.exit_initialization_mode()
    except FmiError as exc:
        if exc.call not in INIT_CALLS:
            return  # a failing switch is enable-handshake's finding
        switched = ctx.dae is not None and getattr(ctx.dae, "started", "") == "runtime-switch"
        then = ("the probes switch DAE mode on at runtime, from Event Mode" if switched else
                "DAE mode cannot be probed")
        yield Violation(
            f"the FMU refuses to initialise in DAE mode: {exc.call} returned {exc.status}; "
            f"alpha.1 allows this (DAE-14), {then}",
            manifest_location(ctx, layout.enable, ("Enable",)),
            evidence(error_evidence(exc), dae_mode_probed="runtime-switch" if switched
                     else None), subject=exc.call,
            cause=causes.failing(_STATE_AT.get(exc.call, "Initialization Mode"), "DAE mode"))
    finally:
        inst.free()



# ------------------------------------------------------------------------- reset-incomplete


def reset_incomplete(ctx: ProbeContext, *, rtol: float, atol: float) -> Iterator[Violation]:
    """MV-23, DAE-11: after fmi3Reset the instance holds the start values of modelDescription.xml
    and is in ODE mode (the switch false). The probe switches DAE mode on, sets the states and
    inputs of a sampled point, resets, and reads back in Instantiated: a variable (or the
    switch) that kept its value is named. Only variables with a start value the static stage
    accepts are compared (a fresh instance is no reference: an FMU that keeps state across
    instances is instances-not-independent's finding, not this one's). Where a fresh instance
    already held another value than the XML start, the reset only has to restore that value:
    start-value-not-applied reports the first cause. Every other variable a fresh instance
    reads in Instantiated (every start value of every type) must read the same after the reset
    (:func:`_against_fresh`). Time is not read there: in Instantiated it has no value yet (FMI
    3.0.2 §2.2.6: its initial value is the startTime of fmi3EnterInitializationMode)."""
    layout = layout_of(ctx)
    if ctx.dae is None:
        raise ProbeSkipped("DAE mode could not be started (see enable-handshake)")
    vrs = [vr for vr in dict.fromkeys([*layout.states, *layout.inputs])
           if vr in layout.start and vr not in layout.flagged_start]
    # Where a fresh instance already does not hold the XML start, start-value-not-applied
    # reports the first cause: fmi3Reset only has to return to what instantiation left.
    snapshot = instantiated_values(ctx)
    fresh = snapshot.by_vr()
    others = [h for h in snapshot.items if h.held is not None and
              h.var.vr not in (*vrs, layout.enable)
              and h.var.vr not in layout.flagged_start]
    again = [Held(h.var, h.start) for h in others]
    expected = [layout.start[vr] for vr in vrs]
    instantiated = [_instantiated(fresh.get(vr), layout.start[vr]) for vr in vrs]
    switch = layout.enable if layout.enable_status == "ok" else None
    expected_switch = False if switch is not None else None
    instantiated_switch = _instantiated(fresh.get(switch), False) if switch is not None else None
    if not vrs and switch is None and not others:
        raise ProbeSkipped("no state or input with a start value, and no enable parameter")
    point = ctx.points[1] if len(ctx.points) > 1 else ctx.points[0]
    inst = ctx.new_instance("dae")
    try:
        inst.set_point(point, algebraic=False)  # type: ignore[attr-defined]
        inst.reset()  # type: ignore[attr-defined]
        try:
            got = inst.get_float64(vrs)  # type: ignore[attr-defined]
            got_switch = inst.get_boolean(switch) if switch is not None else None  # type: ignore
            read_held(inst, again)  # every other variable a fresh instance answered for
        except FmiError as exc:
            raise ProbeSkipped(f"after fmi3Reset the FMU does not answer {exc.call} in "
                               f"Instantiated ({exc.status}): the reset cannot be checked"
                               ) from None
        switched = _in_dae_mode(inst, snapshot, switch, got_switch)
    finally:
        inst.free()  # type: ignore[attr-defined]
    kept = switch is not None and got_switch not in (expected_switch, instantiated_switch)
    # The first cause: an instance the reset left in DAE mode is compared with a fresh instance
    # in DAE mode too (the switch set in Configuration Mode). What only the mode explains is a
    # consequence of the switch, listed in its finding; what a fresh DAE-mode instance does
    # not read either is a defect of its own.
    dae = snapshot.by_vr("dae") if kept and snapshot.dae is not None else None
    consequences: list[dict[str, Any]] = []
    own = list(_against_fresh(ctx, layout, others, again, point, rtol=rtol, atol=atol, dae=dae,
                              consequences=consequences))
    for vr, a, b, held in zip(vrs, got, expected, instantiated):
        if any(close(float(a), float(v), rtol=rtol, atol=atol, scale=layout.scale(vr))
               for v in (b, held)):
            continue
        in_dae = dae.get(vr) if dae is not None else None
        if in_dae is not None and in_dae.held is not None and close(
                float(a), float(in_dae.held[0]), rtol=rtol, atol=atol, scale=layout.scale(vr)):
            consequences.append({"variable": layout.name(vr), "after_reset": float(a),
                                 "instantiated": float(held),
                                 "instantiated_dae_mode": float(in_dae.held[0])})
            continue
        own.append(Violation(
            "after fmi3Reset {subject} kept a value set before the reset instead of its "
            "start value (MV-23)", var_location(ctx, vr),
            evidence(after_reset=float(a), start=float(b), set_before=point.values.get(vr),
                     instantiated=float(held), point=point.label, scale=layout.scale(vr)),
            subject=layout.name(vr)))
    if switched:
        yield from _dae_mode_after_reset(ctx, layout, snapshot, switched, own, point,
                                         rtol=rtol, atol=atol)
    if kept:
        told = (f"; {len(consequences)} variable(s) read after the reset as in DAE mode, which "
                "the switch explains: " + ", ".join(f"'{c['variable']}'" for c in consequences)
                if consequences else "")
        yield Violation(
            f"after fmi3Reset the enable parameter {{subject}} is still {str(got_switch).lower()}"
            f": the FMU stays in DAE mode, and the next run starts in the wrong mode (DAE-11)"
            + told, manifest_location(ctx, switch, ("Enable",)),
            evidence(after_reset=got_switch, start=expected_switch, point=point.label,
                     consequences=consequences, compared_with="a fresh instance in DAE mode "
                     "(the switch set true in Configuration Mode)" if dae is not None else
                     "a fresh instance (no DAE-mode snapshot: " + snapshot.dae_reason + ")"),
            subject=layout.name(switch), part="switch-kept")
    yield from own


def _in_dae_mode(inst: Any, snapshot: Any, switch: int | None, got_switch: Any
                 ) -> list[Held]:
    """After a reset that set the switch back to false, the switch set true again in
    Configuration Mode and every variable the fresh DAE-mode snapshot read, read again: a
    value the reset kept may show in DAE mode only (ODE mode computes it when read). Empty
    when there is no DAE-mode snapshot, the switch was kept, or the FMU refuses."""
    if switch is None or got_switch is not False or not snapshot.dae:
        return []
    items = [Held(h.var, h.start) for h in snapshot.dae if h.held is not None]
    try:
        configure(inst, True)
        read_held(inst, items)
    except FmiError:
        return []
    return items


def _dae_mode_after_reset(ctx: ProbeContext, layout: Layout, snapshot: Any,
                          switched: list[Held], own: list[Violation], point: Any, *,
                          rtol: float, atol: float) -> Iterator[Violation]:
    """Each variable that reads, after the reset and the switch set true again, otherwise than
    a fresh instance in DAE mode reads it (and was not named in ODE mode already)."""
    named = {v.subject for v in own}
    fresh = snapshot.by_vr("dae")
    for h1 in switched:
        h0 = fresh.get(h1.var.vr)  # type: ignore[arg-type]
        if h0 is None or h0.held is None or h1.held is None or h1.var.name in named:
            continue
        if all(_same(h0.var.type, a, b, layout.scale(h0.var.vr), rtol, atol)  # type: ignore
               for a, b in zip(h0.held, h1.held)):
            continue
        yield Violation(
            "after fmi3Reset and the enable parameter set true again in Configuration Mode, "
            "{subject} reads a value set or computed before the reset, not what a fresh "
            "instance reads in DAE mode (MV-23)", var_location(ctx, h0.var.vr),  # type: ignore
            evidence(after_reset=_plain(h1.held), instantiated_dae_mode=_plain(h0.held),
                     type=h0.var.type, causality=h0.var.causality, mode="DAE mode",
                     point=point.label),
            subject=h0.var.name)


def _against_fresh(ctx: ProbeContext, layout: Layout, fresh: list[Held], after: list[Held],
                   point: Any, *, rtol: float, atol: float, dae: dict[int, Held] | None = None,
                   consequences: list[dict[str, Any]] | None = None) -> Iterator[Violation]:
    """Every other variable a fresh instance read in Instantiated (start values of every type)
    against its reading after fmi3Reset: "the same state as if fmi3Instantiate had been called"
    (FMI 3.0.2 §2.3.1). ``dae``: when the reset kept the switch true, what a fresh instance
    reads in DAE mode; a variable that reads as it does there is a consequence of the switch
    (appended to ``consequences``), not a finding."""
    for h0, h1 in zip(fresh, after):
        if h1.held is None:
            exc = h1.error
            if exc is not None and exc.after is not None:
                continue  # a consequence of the refusal before it (SM-04)
            yield Violation(
                f"after fmi3Reset {exc.call if exc else 'fmi3Get'} of {{subject}} returns "
                f"{exc.status if exc else 'an error'} in Instantiated, where a fresh instance "
                "answers it", var_location(ctx, h0.var.vr),  # type: ignore[arg-type]
                evidence(error_evidence(exc) if exc else {}, instantiated=h0.held,
                         point=point.label), subject=h0.var.name)
            continue
        if all(_same(h0.var.type, a, b, layout.scale(h0.var.vr), rtol, atol)  # type: ignore
               for a, b in zip(h0.held, h1.held)):  # type: ignore[arg-type]
            continue
        in_dae = dae.get(h0.var.vr) if dae is not None else None  # type: ignore[arg-type]
        if in_dae is not None and in_dae.held is not None and all(
                _same(h0.var.type, a, b, layout.scale(h0.var.vr), rtol, atol)  # type: ignore
                for a, b in zip(in_dae.held, h1.held)):  # type: ignore[arg-type]
            if consequences is not None:
                consequences.append({"variable": h0.var.name, "after_reset": _plain(h1.held),
                                     "instantiated": _plain(h0.held),
                                     "instantiated_dae_mode": _plain(in_dae.held)})
            continue
        yield Violation(
            "after fmi3Reset {subject} reads a value set or computed before the reset, not "
            "what a fresh instance reads (MV-23)", var_location(ctx, h0.var.vr),  # type: ignore
            evidence(after_reset=_plain(h1.held), instantiated=_plain(h0.held),
                     type=h0.var.type, causality=h0.var.causality, point=point.label),
            subject=h0.var.name)


def _same(type_: str, a: Any, b: Any, scale: float, rtol: float, atol: float) -> bool:
    if type_ in ("Float32", "Float64"):
        a, b = float(a), float(b)
        return (math.isnan(a) and math.isnan(b)) or a == b or close(
            a, b, rtol=rtol, atol=atol, scale=scale)
    return bool(a == b)


def _plain(values: Any) -> Any:
    values = [float(v) if isinstance(v, float) else v for v in values]
    return values[0] if len(values) == 1 else values


def _instantiated(held: Held | None, start: Any) -> Any:
    """What fmi3Reset must restore: the XML start, or what a fresh instance held instead."""
    if held is None or held.held is None or len(held.held) != 1:
        return start
    value = held.held[0]
    return bool(value) if isinstance(start, bool) else float(value)


PROBES = {
    "DAE710": enable_handshake,
    "DAE711": dae_initialization_refused,
    "DAE712": reset_incomplete,
}
