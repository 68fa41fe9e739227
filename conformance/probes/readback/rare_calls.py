"""Calls importers make that the other probes never make (DAE738, DAE739).

    stop-time-refused       fmi3EnterInitializationMode refuses stopTimeDefined = true with the
                            stop time of the FMU's own experiment, or one just after the start
                            without a DefaultExperiment (fmpy's simulate_fmu passes it; error)
    illegal-call-accepted   an illegal call returns fmi3OK: fmi3SetBoolean on a Float64
                            variable, an output given as a known of a partial derivative, an
                            nSeed or nSensitivity that does not match the value references
                            (warning)

Each call is made on a fresh instance, freed afterwards, after the other probes (the registry
runs this family last but for the endurance probes), so a correct FMU loses nothing. The
buffers are always as large as the counts the FMU should expect, so an FMU that reads or writes
past what a wrong count announces touches only lsdae's memory. An FMU that crashes on an illegal
call is reported as ``binary-crashed`` (DAE701) naming the call and this probe: FMI lets an FMU
refuse any call with fmi3Error (SM-04), never end the process.
"""
from __future__ import annotations

import ctypes
from typing import Any, Callable, Iterator

import numpy as np

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ...model.description import MODEL_DESCRIPTION
from ...runtime.arrays import vr_array
from ...runtime.instance import Instance
from ...runtime.modes import configure
from ..instruments.api import FmiError, ProbeContext, ProbeSkipped
from ..instruments.common import error_evidence, layout_of, new_instance, var_location
from ..instruments.event_walk import stop_time
from ..instruments.jacobian_layout import MODE_NAMES


def _where(ctx: ProbeContext) -> Location:
    return Location(file=getattr(ctx.model, "file", None) or MODEL_DESCRIPTION)


def stop_time_refused(ctx: ProbeContext) -> Iterator[Violation]:
    """SM-05 (derived): fmi3EnterInitializationMode takes stopTimeDefined; a stop time inside the
    FMU's own experiment (the DefaultExperiment's, else just after the start) is accepted in
    every mode in which the FMU initialises without one."""
    layout = layout_of(ctx)
    library = ctx.facts["library"]
    t0 = layout.start_time
    stop = _own_stop_time(ctx, t0)
    # lsdae's own window, not a stop time of the FMU's experiment
    own = stop != getattr(getattr(ctx.model, "default_experiment", None), "stop_time", None)
    tried = 0
    for mode in layout.modes:
        held = getattr(ctx, mode)
        if held is None or getattr(held, "started", "") == "runtime-switch":
            continue   # not initialised in this mode at all, or only through a runtime switch
        tried += 1
        inst = new_instance(library, mode)
        try:
            if mode == "dae" and layout.enable is not None:
                configure(inst, True)
            try:
                inst.call("fmi3EnterInitializationMode", True, 1e-6, t0, True, stop)
            except FmiError as exc:
                yield Violation(
                    f"fmi3EnterInitializationMode returns {exc.status} with stopTimeDefined = "
                    f"true and stopTime = {stop:g} (start time {t0:g}; {MODE_NAMES[mode]}), "
                    "while it accepts the same start without a stop time: an importer that "
                    "passes its stop time (fmpy's simulate_fmu always does) cannot initialise "
                    "the FMU", _where(ctx),
                    evidence(error_evidence(exc), mode=mode, start_time=t0, stop_time=stop,
                             tolerance_defined=True, tolerance=1e-6, place=MODE_NAMES[mode]),
                    subject="fmi3EnterInitializationMode",
                    part="no-default-stop-time" if own else None,
                    cause=causes.FAULT.format("refuses a stop time in fmi3EnterInitializationMode"))
                continue
            inst.initialised = inst.initializing = True
        finally:
            inst.free()
    if not tried:
        raise ProbeSkipped("no mode initialises without a stop time")


def _own_stop_time(ctx: ProbeContext, start: float) -> float:
    """The DefaultExperiment's stopTime; without one, a stop time just after ``start`` (a
    window no FMU that initialises at ``start`` can call outside its validity)."""
    stop = stop_time(ctx, start)
    experiment = getattr(ctx.model, "default_experiment", None)
    if getattr(experiment, "stop_time", None) != stop:
        return start + 1e-6 * max(1.0, abs(start))
    return stop


def _refused(action: Callable[[], Any]) -> FmiError | None:
    """The FmiError ``action`` raised, or None when the FMU accepted the call."""
    try:
        action()
    except FmiError as exc:
        return exc
    return None


def _derivative(inst: Instance, fname: str, unknowns: list[int], knowns: list[int],
                n_seed: int, n_sens: int) -> None:
    """A partial-derivative call with the counts given; the buffers hold enough for the
    counts the FMU should expect (unknowns + knowns), whatever the counts say."""
    room = len(unknowns) + len(knowns) + 1
    seed = np.ones(room)
    out = np.zeros(room)
    inst.call(fname, vr_array(unknowns), len(unknowns), vr_array(knowns), len(knowns),
              seed.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n_seed,
              out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n_sens)


#: The kinds of illegal call: one defect each, whichever function and mode accept it (the
#: cause of the violations, folded into one finding by the engine).
_KINDS = {"SG-09": "a setter of another type", "PD-05": "an output as a known",
          "PD-01": "wrong counts of seeds or sensitivities"}


def _cases(ctx: ProbeContext, mode: str) -> Iterator[tuple[str, str, int, Any, str]]:
    """(what, digest id, value reference it is about, the call on a fresh instance, the call
    and argument in a few words)."""
    layout = layout_of(ctx)
    states = list(layout.states_for(mode))
    derivatives = list(layout.derivatives_for(mode))
    if mode == "ode" and layout.enable is not None and states:
        float_vr = states[0]
        yield ("fmi3SetBoolean on the Float64 variable {subject} in Configuration Mode", "SG-09",
               float_vr, lambda inst: _set_boolean(inst, float_vr), "fmi3SetBoolean")
    if not (derivatives and states):
        return
    knowns_ok = set(states) | set(layout.inputs) | (set(layout.algebraic) if mode == "dae"
                                                     else set())
    outputs = [vr for vr in layout.outputs_for(mode) if vr not in knowns_ok]
    unknown = derivatives[:1]
    functions = [("fmi3GetDirectionalDerivative", layout.provides_directional, False),
                 ("fmi3GetAdjointDerivative", layout.provides_adjoint, True)]
    for fname, provided, adjoint in functions:
        if not provided:
            continue
        if outputs:
            out = outputs[0]
            n_seed, n_sens = (1, 1)
            yield (f"{fname} with the output {{subject}} given as a known", "PD-05",
                   out, lambda inst, f=fname, o=out, a=n_seed, b=n_sens:
                   _derivative(inst, f, unknown, [o], a, b), f"{fname} (an output known)")
        knowns = states[:2]
        n_u, n_k = len(unknown), len(knowns)
        right_seed, right_sens = (n_u, n_k) if adjoint else (n_k, n_u)
        yield (f"{fname} with nSeed = {right_seed - 1} for {right_seed} seeded value(s) "
               "(of {subject} ...)", "PD-01", knowns[0],
               lambda inst, f=fname, s=right_seed, t=right_sens:
               _derivative(inst, f, unknown, knowns, s - 1, t), f"{fname} (nSeed)")
        yield (f"{fname} with nSensitivity = {right_sens + 1} for {right_sens} value(s) "
               "(of {subject} ...)", "PD-01", knowns[0],
               lambda inst, f=fname, s=right_seed, t=right_sens:
               _derivative(inst, f, unknown, knowns, s, t + 1), f"{fname} (nSensitivity)")


def _set_boolean(inst: Instance, vr: int) -> None:
    inst.enter_configuration_mode()
    values = (ctypes.c_bool * 1)(True)
    inst.call("fmi3SetBoolean", vr_array([vr]), 1, values, 1)


def illegal_call_accepted(ctx: ProbeContext) -> Iterator[Violation]:
    """SG-09, PD-01, PD-05 (and §2.2.4: illegal arguments give fmi3Error): each illegal call,
    on a fresh instance in Continuous-Time Mode, is refused. fmi3SetBoolean is made in
    Configuration Mode (entered from Instantiated, left before the instance is freed), where it
    breaks two rules at once: the type (SG-09) and FMI 3.0.2 §2.3.6 (a Float64 state is no
    structural parameter)."""
    layout = layout_of(ctx)
    library = ctx.facts["library"]
    started = [mode for mode in layout.modes if getattr(ctx, mode) is not None]
    if not started:
        raise ProbeSkipped("no mode of the FMU could be started")
    # an FMU without an enable parameter, states or partial derivatives has no call to refuse
    for mode in started:
        for what, spec, vr, call, label in _cases(ctx, mode):
            configuration = what.startswith("fmi3SetBoolean")
            try:
                inst = new_instance(library, mode) if configuration else ctx.new_instance(mode)
            except (FmiError, ProbeSkipped):
                continue
            try:
                error = _refused(lambda: call(inst))
            finally:
                inst.free()
            if error is None:
                call_name = what.split(" ")[0]
                yield Violation(
                    f"{what} is accepted ({MODE_NAMES[mode]}; fmi3OK or fmi3Warning): the FMU "
                    "does not detect this illegal call (FMI asks for fmi3Error only from an FMU "
                    "that detects one), so an importer's mistake goes unnoticed and the FMU "
                    "computes with what it was not given", var_location(ctx, vr),
                    evidence(mode=mode, spec=spec, call=call_name,
                             place=f"{label}, {MODE_NAMES[mode]}"),
                    subject=layout.name(vr), cause=f"illegal call accepted: {_KINDS[spec]}")


PROBES = {
    "DAE738": stop_time_refused,
    "DAE739": illegal_call_accepted,
}
