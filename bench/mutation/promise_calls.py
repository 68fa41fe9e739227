"""Promises about call sequences and the helpers every promise check uses.

The comparison (:func:`compare`: 1e-10 relative, 1e-12 absolute, and 1e-8 for ODE mode's
residuals, which are zero only to the Newton tolerance), an instance brought to
Continuous-Time Mode (:func:`running`), and two checks that need their own sequences: each
variable read on its own right after the point changes (:func:`read_alone`), and event
iterations (:func:`events`). Only fmpy, through :mod:`fmu_view`; no lsdae code.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from .fmu_view import SceneLayout, Session, fixed_points
from .promise_jacobian import Violation

EQ_REL = 1e-10       # the same value (ODE mode's Newton result moves in its last digits)
ATOL = 1e-12         # for values near zero (residuals at a solution)
NOISE_ATOL = 1e-8    # ODE mode's residuals: zero up to the Newton iteration's tolerance
CONSISTENT_REL = 1e-8


def same(a: Any, b: Any, rel: float = EQ_REL, atol: float = ATOL) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return a == b or abs(a - b) <= rel * max(abs(a), abs(b)) + atol
    return a == b


def compare(key: str, names: list[str], got: list[Any], want: list[Any],
            rel: float = EQ_REL, noise: frozenset[str] = frozenset()) -> list[Violation]:
    """Violations where ``got`` differs from ``want``; the ``noise`` variables (ODE mode's
    residuals, which are zero only to the Newton tolerance) get NOISE_ATOL."""
    return [(f"{key} {n}", f"{g!r} instead of {w!r}") for n, g, w in zip(names, got, want)
            if not same(g, w, rel, NOISE_ATOL if n in noise else ATOL)]


def noise_of(lay: SceneLayout, mode: str) -> frozenset[str]:
    return frozenset(lay.variables[vr].name for vr in lay.residuals) if mode == "ode" \
        else frozenset()


def running(unzipped: Path, lay: SceneLayout, mode: str, name: str) -> Session:
    s = Session(unzipped, lay, name)
    if mode == "dae":
        s.configure_dae()
        s.call("enter init", s.model.enterInitializationMode, startTime=0.0)
    else:   # as simulators call it: a tolerance and a stop time defined
        s.call("enter init (tolerance 1e-6, stop time 1)", s.model.enterInitializationMode,
               tolerance=1e-6, startTime=0.0, stopTime=1.0)
    s.call("exit init", s.model.exitInitializationMode)
    s.call("enter CT", s.model.enterContinuousTimeMode)
    return s


def read_alone(s: Session, lay: SceneLayout, p: dict[str, Any], mode: str,
               values: list[Any]) -> list[Violation]:
    """Each variable read on its own right after the point is set, coming from another point,
    gives what it gave when everything was read (a read never returns a value computed for an
    earlier point: FMI 3.0.2 3.2.1, the variables are functions of the current t, x, u)."""
    names = [lay.variables[vr].name for vr in lay.all_vrs()]
    alone = []
    for vr in lay.all_vrs():
        for q in (moved(p), p):
            s.set_point(q["t"], q["x"], q["u"], q["w"] if mode == "dae" else None)
            if q is not p:
                s.read(lay.all_vrs())
        alone.append(s.read([vr])[0])
    return compare(f"3.2.1 a variable read alone is up to date ({mode})", names, alone, values,
                   noise=noise_of(lay, mode))


def moved(p: dict[str, Any]) -> dict[str, Any]:
    return {"t": p["t"], **{k: [v * 1.01 + 1e-3 for v in p[k]] for k in ("x", "u", "w")}}


def _after_event(s: Session, lay: SceneLayout, mode: str, t: float) -> list[Violation]:
    """The values read right after an event iteration are those of the new discrete state:
    setting the same point again (t, x, u, w unchanged) and reading must give them again."""
    vrs = lay.all_vrs()
    names = [lay.variables[vr].name for vr in vrs]
    first = s.read(vrs)
    x = [float(v) for v in s.vector("states", len(lay.states))]
    s.set_point(t, x, [float(v) for v in s.read(lay.inputs)],
                [float(v) for v in s.read(lay.algebraic)] if mode == "dae" else None)
    return compare(f"3.1 values read after an event iteration are up to date ({mode})", names,
                   first, s.read(vrs), noise=noise_of(lay, mode))


def events(unzipped: Path, lay: SceneLayout, mode: str) -> list[Violation]:
    """Event iterations at later and later times, on two instances whose output arguments hold
    true / false before each call: the FMU writes every output (the two agree),
    valuesOfContinuousStatesChanged is true only when a state changed, an announced
    nextEventTime is not in the past (FMI 3.0.2 2.3.5, fmi3UpdateDiscreteStates), and the
    values read after the iteration are up to date."""
    out: list[Violation] = []
    pair = [running(unzipped, lay, mode, f"events-{mode}-{k}") for k in (1, 2)]
    for p in sorted(fixed_points(lay, 4), key=lambda p: p["t"]):
        for s in pair:
            s.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
            s.call("fmi3EnterEventMode", s.model.enterEventMode)
        for _ in range(10):
            before = pair[0].vector("states", len(lay.states))
            first, second = (s.update_discrete_states(preset=k == 0) for k, s in enumerate(pair))
            if first != second:
                out.append((f"2.3.5 fmi3UpdateDiscreteStates writes every output ({mode})",
                            f"outputs preset true: {first}, preset false: {second}"))
            need, _term, _nominals, changed, defined, when = second
            if changed and pair[0].vector("states", len(lay.states)) == before:
                out.append((f"2.3.5 valuesOfContinuousStatesChanged only when a state changed "
                            f"({mode})", f"true at t = {p['t']}, states unchanged {before}"))
            if defined and not when >= p["t"]:
                out.append((f"2.3.5 nextEventTime not in the past ({mode})",
                            f"{when} announced at t = {p['t']}"))
            if not need:
                break
        for s in pair:
            s.call("fmi3EnterContinuousTimeMode", s.model.enterContinuousTimeMode)
        out += _after_event(pair[0], lay, mode, p["t"])
    for s in pair:
        s.free()
    return out
