"""Every variable an importer may read, read once in every state it may be read in, per mode.

FMI 3.0 lets an importer call fmi3Get<type> in Instantiated on the variables that have a start
value (SG-01: "Get variable start values"; not the independent variable, which has no start and
no value before fmi3EnterInitializationMode gives it the startTime, FMI 3.0.2 §2.2.6), and on
every variable in Initialization Mode, Event Mode and Continuous-Time Mode (SG-03, SG-04,
SG-05); a clocked variable only while its clock ticks, so it is left out. :func:`sweep` walks
one instance of a mode through those states (Instantiated -> Initialization -> Event ->
Continuous-Time Mode) and reads, in each, every such variable of every type the runtime reads
(``runtime.records.GETTERS``), one call per type. What comes back wrong is a :class:`Fault`:

* ``refused``: the call returned fmi3Error (or Discard, Fatal); the variables of a refused call
  are told apart by halving the call on fresh instances brought to the same state (a refusal
  puts the instance in Terminated, SM-04), at most ``MAX_INSTANCES`` of them per mode;
* ``unwritten``: the call returned fmi3OK but left an element of the caller's buffer as it was
  (read into NaN, and again into a finite sentinel: an element that keeps it was not written,
  the FMU answered for fewer values than it was asked);
* ``nan``: a floating-point variable reads NaN, where its value is not NaN (a NaN XML start).

It is ``evaluation-failed``'s read-back (``failures.py``); not a family, it registers no probe.
A transition that fails ends the walk of its mode: the rules of the handshake report it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from ...model.description import ModelDescription, Variable
from ...runtime.errors import Unavailable
from ...runtime.instance import Instance
from ...runtime.modes import configure
from ...runtime.records import GETTERS
from ..instruments.api import FmiError
from ..instruments.instantiation import element_count

STATES = ("Instantiated", "Initialization Mode", "Event Mode", "Continuous-Time Mode")
MAX_INSTANCES = 48           # fresh instances spent per mode on telling refused variables apart
SENTINEL = -1.2345678e300    # the second fill: a value no FMU computes by chance
SENTINEL_32 = -1.2345678e38  # the same for Float32 (within single precision)


@dataclass(frozen=True)
class Item:
    """One readable variable, its value reference and its serialized element count."""

    var: Variable
    vr: int
    size: int


@dataclass
class Fault:
    """A variable that did not read back in ``state`` of ``mode``."""

    item: Item
    state: str
    mode: str
    problem: str                    # "refused", "unwritten", "nan"
    call: str
    status: str = "fmi3OK"
    log: tuple[str, ...] = ()
    element: int | None = None


@dataclass
class Sweep:
    """The faults of one mode, and the states the walk could not reach (with the reason)."""

    faults: list[Fault] = field(default_factory=list)
    unreached: dict[str, str] = field(default_factory=dict)


def readable(model: ModelDescription, state: str) -> list[Item]:
    """The variables FMI 3.0 lets an importer read in ``state``, with their element counts."""
    items = []
    for var in model.variables:
        if var.vr is None or var.type not in GETTERS or var.clocks:
            continue
        if state == "Instantiated" and (var.start is None or var.causality == "independent"):
            continue   # no start to read; time has none before fmi3EnterInitializationMode
        size = element_count(model, var)
        if size and (var.type != "String" or size == 1):
            items.append(Item(var, var.vr, size))
    return items


def sweep(new: Callable[[str], Instance], model: ModelDescription, mode: str) -> Sweep:
    """Read every readable variable once in each state of ``mode`` ("dae" or "ode") on
    instances made by ``new(label)``; the instances are freed."""
    result = Sweep()
    walker = _Walker(new, mode, result)
    inst: Instance | None = None
    for k, state in enumerate(STATES):
        if inst is not None and not walker.advance(inst, k):
            return result
        for type_, group in _by_type(readable(model, state)).items():
            if inst is None and (inst := walker.reach(k)) is None:
                return result
            if not walker.read(inst, state, type_, group):
                inst.free()
                inst = None
                walker.locate(k, state, type_, group)
    if inst is not None:
        inst.free()
    return result


def _by_type(items: Sequence[Item]) -> dict[str, list[Item]]:
    groups: dict[str, list[Item]] = {}
    for item in items:
        groups.setdefault(item.var.type, []).append(item)
    return groups


class _Walker:
    """Brings instances of one mode to a state and reads groups of variables there."""

    def __init__(self, new: Callable[[str], Instance], mode: str, result: Sweep):
        self.new, self.mode, self.result = new, mode, result
        self.spent = 0

    def reach(self, k: int) -> Instance | None:
        """A fresh instance in ``STATES[k]``, or None (the reason in ``result.unreached``)."""
        try:
            inst = self.new(f"read-{self.mode}")
        except FmiError as exc:
            self.result.unreached[STATES[k]] = exc.describe()
            return None
        for step in range(k + 1):
            if not self.advance(inst, step):
                return None
        return inst

    def advance(self, inst: Instance, k: int) -> bool:
        """Take ``inst`` from ``STATES[k - 1]`` to ``STATES[k]`` (k = 0: configure the mode)."""
        try:
            if k == 0:
                if self.mode == "dae" and inst.layout.enable is not None:
                    configure(inst, True)
            elif k == 1:
                inst.enter_initialization_mode(inst.layout.start_time)
            elif k == 2:
                inst.exit_initialization_mode()
            else:
                inst.update_discrete_states()
                inst.enter_continuous_time_mode()
        except (FmiError, Unavailable) as exc:   # Unavailable: an event iteration unsettled
            for state in STATES[k:]:
                self.result.unreached[state] = (exc.describe() if isinstance(exc, FmiError)
                                                else str(exc))
            inst.free()
            return False
        return True

    def read(self, inst: Instance, state: str, type_: str, group: Sequence[Item]) -> bool:
        """Read ``group`` on ``inst``; False when the call was refused (faults not yet known)."""
        vrs = [item.vr for item in group]
        n = sum(item.size for item in group)
        floating = type_ in ("Float32", "Float64")
        try:
            values = inst.get_typed(type_, vrs, n, fill=math.nan if floating else None)
            if floating and any(math.isnan(v) for v in values):
                again = inst.get_typed(type_, vrs, n, fill=_sentinel(type_))
                self._unwritten(state, type_, group, values, again)
        except FmiError:
            return False
        return True

    def _unwritten(self, state: str, type_: str, group: Sequence[Item], first: list[Any],
                   second: list[Any]) -> None:
        k = 0
        fname = GETTERS[type_][0]
        for item in group:
            for e in range(item.size):
                a, b = first[k + e], second[k + e]
                problem = ("unwritten" if math.isnan(a) and not math.isnan(b) and
                           b == _sentinel(type_) else "nan" if math.isnan(a) else "")
                if problem and not (problem == "nan" and _nan_start(item.var)):
                    self.result.faults.append(Fault(item, state, self.mode, problem, fname,
                                                    element=e if item.size > 1 else None))
                    break
            k += item.size

    def locate(self, k: int, state: str, type_: str, group: Sequence[Item]) -> None:
        """Tell apart the variables of a refused call by halving it on fresh instances."""
        fname = GETTERS[type_][0]
        if len(group) == 1 or self.spent >= MAX_INSTANCES:
            self._refused(k, state, fname, group)
            return
        half = len(group) // 2
        for part in (group[:half], group[half:]):
            self.spent += 1
            inst = self.reach(k)
            if inst is None:
                return
            ok = self.read(inst, state, type_, part)
            inst.free()
            if not ok:
                self.locate(k, state, type_, part)

    def _refused(self, k: int, state: str, fname: str, group: Sequence[Item]) -> None:
        """Read ``group`` once more on a fresh instance to keep the call's status and log."""
        inst = self.reach(k)
        if inst is None:
            return
        try:
            inst.get_typed(group[0].var.type, [i.vr for i in group], sum(i.size for i in group))
            return  # not refused this time: no finding (evaluation-not-repeatable's business)
        except FmiError as exc:
            for item in group:
                self.result.faults.append(Fault(item, state, self.mode, "refused", exc.call,
                                                exc.status, tuple(exc.log[:10])))
        finally:
            inst.free()


def _sentinel(type_: str) -> float:
    """The finite sentinel as the FMU's type holds it (single precision for Float32)."""
    ctype = GETTERS[type_][1]
    return float(ctype(SENTINEL if type_ == "Float64" else SENTINEL_32).value)


def _nan_start(var: Variable) -> bool:
    return var.start is not None and var.start.strip().lower() in ("nan", "-nan", "+nan")
