"""The start-value probe (DAE713): a fresh instance holds the XML start values.

After ``fmi3InstantiateModelExchange`` and before any ``fmi3Set*``, ``fmi3Get*`` returns each
variable's ``start`` where ``initial`` is exact or approx (MV-23, SG-01): an importer that
trusts the XML (to show initial values, to compute a consistent start, to decide what to set)
otherwise starts from another point than the binary. The snapshot comes from
:mod:`..instruments.instantiation`, shared with ``reset-incomplete``, which stays silent on what
this probe explains.
"""
from __future__ import annotations

import math
from typing import Any, Iterator

from ...report import causes
from ...report.findings import Violation, evidence
from ..instruments.api import ProbeContext, ProbeSkipped
from ..instruments.common import var_location
from ..instruments.instantiation import Held, instantiated_values


def differs(type_: str, held: Any, start: Any, *, rtol: float, float32_rtol: float) -> bool:
    """Whether a value read differs from its start: floats within ``rtol`` (``float32_rtol``
    for Float32, whose start is rounded to single precision), everything else exactly."""
    if type_ in ("Float32", "Float64"):
        held = float(held)
        if not math.isfinite(held):
            return True
        tol = float32_rtol if type_ == "Float32" else rtol
        return abs(held - start) > tol * max(abs(held), abs(start))
    if type_ == "Boolean":
        return bool(held) != start
    return held != start


def mismatched(h: Held, *, rtol: float, float32_rtol: float) -> list[int]:
    """The element indices of ``h`` whose value differs from the start (empty when unread)."""
    if h.held is None:
        return []
    return [k for k, (a, b) in enumerate(zip(h.held, h.start))
            if differs(h.var.type, a, b, rtol=rtol, float32_rtol=float32_rtol)]


def start_value_not_applied(ctx: ProbeContext, *, rtol: float,
                            float32_rtol: float) -> Iterator[Violation]:
    """MV-23, SG-01: right after instantiation every variable with initial exact or approx
    holds its XML start value, in ODE mode and again after the switch was set true in
    Configuration Mode (DAE mode): one finding per variable, naming the modes that show it."""
    snapshot = instantiated_values(ctx)
    if snapshot.reason:
        raise ProbeSkipped(snapshot.reason)
    read = [h for h in snapshot.items if h.held is not None]
    dae = {h.var.vr: h for h in snapshot.dae or () if h.held is not None}
    if not read and not dae:
        # the first refusal: the calls after an fmi3Error were not made (read_held)
        first = next((h.error.after or h.error for h in snapshot.items if h.error), None)
        raise ProbeSkipped(f"nothing could be read after instantiation ({first.call} "
                           f"returned {first.status})" if first else "nothing could be read")
    options = {"rtol": rtol, "float32_rtol": float32_rtol}
    odes = {h.var.vr: h for h in read}
    for vr in dict.fromkeys([*odes, *dae]):
        shown = [(mode, h, wrong) for mode, h in (("ODE", odes.get(vr)), ("DAE", dae.get(vr)))
                 if h is not None and (wrong := mismatched(h, **options))]
        if shown:
            yield _finding(ctx, shown, rtol=rtol, float32_rtol=float32_rtol)


def _finding(ctx: ProbeContext, shown: list[tuple[str, Held, list[int]]], *, rtol: float,
             float32_rtol: float) -> Violation:
    """One variable's finding: the first mode that shows it (ODE before DAE), the other in the
    evidence."""
    mode, h, wrong = shown[0]
    k = wrong[0]
    element = f" (element {k}, {len(wrong)} of {len(h.start)} differ)" if len(h.start) > 1 \
        else ""
    fname = "fmi3GetInt64" if h.var.type == "Enumeration" else f"fmi3Get{h.var.type}"
    tolerance = {"Float64": rtol, "Float32": float32_rtol}.get(h.var.type)  # else exact
    modes = " and ".join(m for m, _, _ in shown)
    after = ("after fmi3InstantiateModelExchange, before any fmi3Set*" if mode == "ODE" else
             "after fmi3InstantiateModelExchange and the enable parameter set true in "
             "Configuration Mode, before any other fmi3Set*")
    only = " only (ODE mode holds it)" if modes == "DAE" else ""
    return Violation(
        f"{after}, {fname} returns {_show(h.held[k])} for "
        f"{{subject}}{element}, whose XML start is {_show(h.start[k])} "
        f"(initial=\"{h.var.initial}\"), in {modes} mode{only}: an importer that trusts the "
        "XML starts from another point than the binary", var_location(ctx, h.var.vr),
        evidence(value_reference=h.var.vr, type=h.var.type, initial=h.var.initial,
                 start=h.start[k], held=h.held[k], element=k if len(h.start) > 1 else None,
                 elements_differing=len(wrong), elements=len(h.start),
                 state="Instantiated (no fmi3Set* called but the switch's)", modes=modes,
                 held_by_mode={m: _plain(x.held[k]) for m, x, _ in shown}, rtol=tolerance),
        subject=h.var.name, cause=causes.through(h.var.name))


def _plain(value: Any) -> Any:
    return value if isinstance(value, (bool, int, float, str)) or value is None else str(value)


def _show(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return repr(value) if isinstance(value, float) else str(value)


PROBES = {
    "DAE713": start_value_not_applied,
}
