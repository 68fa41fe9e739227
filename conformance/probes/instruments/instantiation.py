"""What a fresh instance holds right after ``fmi3InstantiateModelExchange``, before any set.

Shared by ``start-value-not-applied`` (:mod:`..readback.start_values`), which compares it with the
XML start values, and ``reset-incomplete`` (:mod:`..evaluation.handshake`), which must not blame
fmi3Reset for returning to what instantiation left when that already differs from the XML (one
fault, one finding: the first cause). Not a family: it registers no probe.

The variables read are those whose XML ``start`` the instance must hold (MV-23, SG-01): a
``start`` attribute (or ``<Start>`` children) and an effective ``initial`` of exact or approx,
of every type fmi3Get<type> reads (Float32/64, the integer types, Enumeration, Boolean, String
scalars); arrays whose size the XML fixes (``<Dimension start>`` or the start of the structural
parameter it names) are read whole. A start the static stage flags (not a number, not finite)
is left out: the XML is at fault there, not the binary. Scalars of one type are read in one
call, so a model of 100k variables costs a handful of calls.

The snapshot is taken in each mode the FMU offers: on a fresh instance (ODE mode: the switch
false), and on another after the switch was set true in Configuration Mode (DAE mode, still in
Instantiated, where start values hold as they do in ODE mode: an algebraic variable that ODE
mode computes from the states may agree with its start by chance there, and hold another value
in DAE mode, where the importer gives it). It is taken once per worker and kept in ``ctx.facts``;
the probe stage runs ``start-value-not-applied`` first, so no other instance has been freed
yet (an FMU that keeps state across instances is ``instances-not-independent``'s finding).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ...model.description import ModelDescription, Variable
from ...runtime.records import GETTERS
from ...runtime.modes import configure
from .api import FmiError, ProbeContext
from .common import new_instance

FACT = "instantiation.values"
_BOOLEANS = {"true": True, "1": True, "false": False, "0": False}


@dataclass
class Held:
    """One variable: its XML start values and what the fresh instance returned."""

    var: Variable
    start: list[Any]                 # one per element (a single XML value is broadcast)
    held: list[Any] | None = None    # None: the get was refused (``error`` says how)
    error: FmiError | None = None


@dataclass
class Instantiated:
    """The snapshot: every variable read, or why none could be (``reason``). The independent
    variable is not read: it has no start, and no value before fmi3EnterInitializationMode
    gives it the startTime (FMI 3.0.2 §2.2.6), so an importer does not read it in Instantiated."""

    items: list[Held] = field(default_factory=list)
    reason: str = ""
    # the same variables (the switch left out) read after the switch was set true in
    # Configuration Mode; None when the FMU has no usable switch or it could not be set
    # (``dae_reason`` says why)
    dae: list[Held] | None = None
    dae_reason: str = ""

    def by_vr(self, mode: str = "ode") -> dict[int, Held]:
        items = self.items if mode == "ode" else (self.dae or [])
        return {h.var.vr: h for h in items if h.var.vr is not None}


def element_count(model: ModelDescription, var: Variable) -> int | None:
    """Element count of ``var`` from its ``<Dimension>`` elements, or None when not fixed."""
    count = 1
    for dim in var.dimensions:
        text = dim.start
        if text is None and dim.vr is not None:
            target = model.by_vr.get(dim.vr)
            text = target.start if target is not None else None
        try:
            size = int((text or "").strip())
        except ValueError:
            return None
        if size < 0:
            return None
        count *= size
    return count


def _parse(type_: str, token: str) -> Any:
    """One XML start token as the value fmi3Get<type> returns, or None if it is not one."""
    if type_ in ("Float32", "Float64"):
        try:
            value = float(token)
        except ValueError:
            return None
        return value if math.isfinite(value) else None
    if type_ == "Boolean":
        return _BOOLEANS.get(token.strip())
    if type_ == "String":
        return token
    try:
        return int(token)
    except ValueError:
        return None


def expected_starts(model: ModelDescription, var: Variable) -> list[Any] | None:
    """The values ``var`` must hold after instantiation, one per element, or None when it has
    none to hold or the XML does not say them clearly (a static finding's business).
    Neither a clocked variable (FMI 3.0.2 §2.2.7.2: read only in Event Mode while its clock
    ticks, or in Initialization Mode) nor the independent variable, even with a start, is read
    in Instantiated."""
    if (var.vr is None or var.start is None or var.initial not in ("exact", "approx")
            or var.type not in GETTERS or var.clocks or var.causality == "independent"):
        return None
    size = element_count(model, var)
    if not size:
        return None
    if var.type == "String":
        return [var.start] if size == 1 and not var.dimensions else None
    tokens = var.start.split()
    if len(tokens) not in (1, size):
        return None
    values = [_parse(var.type, t) for t in tokens]
    if any(v is None for v in values):
        return None
    return values * size if len(values) == 1 else values


def instantiated_values(ctx: ProbeContext) -> Instantiated:
    """The snapshot, taken once per worker (memoised in ``ctx.facts``)."""
    memo = ctx.facts.get(FACT)
    if isinstance(memo, Instantiated):
        return memo
    result = _take(ctx)
    ctx.facts[FACT] = result
    return result


def _take(ctx: ProbeContext) -> Instantiated:
    model = ctx.model
    library = ctx.facts.get("library")
    if model is None or library is None:
        return Instantiated(reason="the binary is not loaded")
    items = []
    for var in model.variables:
        start = expected_starts(model, var)
        if start is not None:
            items.append(Held(var, start))
    if not items:
        return Instantiated(reason="no variable has a start value the instance must hold")
    try:
        inst = new_instance(library, "instantiated")
    except FmiError as exc:
        return Instantiated(reason=f"{exc.call} returned {exc.status}: nothing to read")
    try:
        read_held(inst, items)
    finally:
        inst.free()
    result = Instantiated(items)
    _take_dae(library, result)
    return result


def _take_dae(library: Any, result: Instantiated) -> None:
    """The DAE-mode snapshot: a fresh instance, the switch set true in Configuration Mode, the
    same variables read in Instantiated (the switch itself left out: it holds what was set)."""
    layout = library.layout
    if layout.enable is None or layout.enable_status != "ok":
        result.dae_reason = "no usable enable parameter: the FMU has no DAE mode to read"
        return
    items = [Held(h.var, h.start) for h in result.items if h.var.vr != layout.enable]
    try:
        inst = new_instance(library, "instantiated-dae")
    except FmiError as exc:
        result.dae_reason = f"{exc.call} returned {exc.status}: nothing to read"
        return
    try:
        configure(inst, True)
        read_held(inst, items)
        result.dae = items
    except FmiError as exc:
        result.dae_reason = (f"setting the enable parameter in Configuration Mode failed: "
                             f"{exc.call} returned {exc.status}")
    finally:
        inst.free()


def read_held(inst: Any, items: list[Held]) -> None:
    """Scalars of one type in one call, each array in a call of its own. A refused call
    leaves its variables unread (``error``): FMI 3.0 allows fmi3Get* in Instantiated (SG-01),
    but a refusal is not a value the instance holds, so nothing is compared for them. After
    an fmi3Error (or fmi3Fatal) the instance is in Terminated, whose values serve debugging
    only (FMI 3.0.2 §2.3.8): the calls not made yet are not made, their variables unread with
    an error that follows the refusal (``after``), as the consequence it is (SM-04)."""
    scalars: dict[str, list[Held]] = {}
    calls: list[tuple[str, list[Held]]] = []
    for h in items:
        if len(h.start) == 1 and not h.var.dimensions:
            scalars.setdefault(h.var.type, []).append(h)
        else:
            calls.append((h.var.type, [h]))
    failed: FmiError | None = None
    for type_, group in [*calls, *scalars.items()]:
        if failed is None:
            failed = _get(inst, type_, group)
        else:
            _unread(type_, group, failed)


def _get(inst: Any, type_: str, group: list[Held]) -> FmiError | None:
    """Read ``group``; the error when the call put the instance in Terminated, else None."""
    try:
        values = inst.get_typed(type_, [h.var.vr for h in group],
                                sum(len(h.start) for h in group))
    except FmiError as exc:
        for h in group:
            h.error = exc
        return exc if exc.status in ("fmi3Error", "fmi3Fatal") else None
    k = 0
    for h in group:
        h.held = values[k:k + len(h.start)]
        k += len(h.start)
    return None


def _unread(type_: str, group: list[Held], failed: FmiError) -> None:
    """Mark ``group`` unread: its call was not made after ``failed``."""
    error = FmiError(GETTERS[type_][0], "not called")
    error.after = failed.after or failed
    for h in group:
        h.error = error
