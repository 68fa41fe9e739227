"""The invariant probe (DAE806): what a manifest's ``<Invariant>`` promises, along a trajectory.

``<Invariant>`` is in no text of 1.0.0-alpha.1 (D-13, Q-07; ``invariant-rejected-by-importers``
says who rejects it); the working group's "ODE with invariants" text defines it as a variable
that stays constant along every solution (an energy, a hidden constraint of an index-reduced
model). The probe takes the simulation runs of :mod:`.runs` (IDA in DAE mode, CVODE
in ODE mode, the settings of ``simulation-failed``), sets each output time's time, states and
(DAE mode) algebraic variables on the mode's instance, reads the invariant variables with
fmi3GetFloat64, and compares them with their value at the first output time. The integrators
move an invariant by about their tolerance; a drift above ``factor`` times the run's ``rtol``
(relative to the larger of the value and the nominal) is the model's, not the integrator's.
"""
from __future__ import annotations

from typing import Iterator

import numpy as np

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ..instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from ..instruments.common import layout_of
from ..instruments.jacobian_layout import MODE_NAMES
from .runs import run


def _invariants(ctx: ProbeContext) -> list[tuple[int, str, Location]]:
    """The scalar Float64 variables the manifest names in ``<Invariant>`` elements."""
    out = []
    for u in (ctx.manifest.unknowns("Invariant") if ctx.manifest is not None else ()):
        var = ctx.model.by_vr.get(u.vr) if u.vr is not None else None
        if var is not None and var.type == "Float64" and not var.dimensions:
            out.append((var.vr, var.name, Location(file=u.file, line=u.line, path=u.path)))
    return out


def invariant_drift(ctx: ProbeContext, *, factor: float) -> Iterator[Violation]:
    """The invariants stay at their initial value along the trajectory, in every mode the FMU
    has, within ``factor`` times the run's rtol."""
    invariants = _invariants(ctx)
    if not invariants:
        return  # nothing promised, nothing to probe (and no simulation run for it)
    layout = layout_of(ctx)
    reasons, ran = [], False
    for mode in layout.modes:
        try:
            traj = run(ctx, mode)
        except ProbeSkipped as exc:
            reasons.append(f"{MODE_NAMES[mode]}: {exc}")
            continue
        inst = getattr(ctx, mode)
        if inst is None or not traj.times:
            reasons.append(f"{MODE_NAMES[mode]}: no instance or no output time")
            continue
        values = _along(layout, inst, traj, [vr for vr, _, _ in invariants])
        if values is None:
            reasons.append(f"{MODE_NAMES[mode]}: the invariants cannot be read along the run")
            continue
        ran = True
        for k, (vr, name, where) in enumerate(invariants):
            yield from _drift(traj, values[:, k], vr, name, where, layout.scale(vr), mode,
                              factor)
    if not ran:
        raise ProbeSkipped("; ".join(reasons))


def _along(layout, inst, traj, vrs: list[int]) -> np.ndarray | None:
    """The invariants at every output time of ``traj``, shape (times, len(vrs)), or None."""
    by_name = {layout.name(vr): vr for vr in layout.names}
    columns = {by_name[n]: j for j, n in enumerate(traj.names) if n in by_name}
    out = np.full((len(traj.times), len(vrs)), np.nan)
    for i, t in enumerate(traj.times):
        values = {vr: float(traj.values[i, j]) for vr, j in columns.items()
                  if np.isfinite(traj.values[i, j])}
        values.update({vr: layout.start.get(vr, 0.0) for vr in layout.inputs})
        try:
            out[i] = inst.evaluate(Point(float(t), values, f"t={t:.6g}"), vrs)
        except (FmiError, ProbeSkipped):
            return None if i == 0 else out[:i]
    return out


def _drift(traj, series: np.ndarray, vr: int, name: str, where: Location, nominal: float,
           mode: str, factor: float) -> Iterator[Violation]:
    first = float(series[0])
    scale = max(abs(first), nominal)
    tolerance = factor * traj.rtol * scale
    gaps = np.abs(series - first)
    k = int(np.nanargmax(gaps)) if np.any(np.isfinite(gaps)) else 0
    if np.isfinite(gaps[k]) and gaps[k] > tolerance:
        yield Violation(
            f"the invariant {{subject}} drifts along the {MODE_NAMES[mode]} trajectory: "
            f"{first:.9g} at t = {traj.times[0]:.6g}, {float(series[k]):.9g} at "
            f"t = {traj.times[k]:.6g}, more than {factor:g} times the integration tolerance",
            where, evidence(mode=MODE_NAMES[mode], value_reference=vr, initial=first,
                            worst=float(series[k]), t_worst=float(traj.times[k]),
                            drift=float(gaps[k]), tolerance=tolerance,
                            scale="factor * rtol * max(|initial|, nominal)", rtol=traj.rtol,
                            times=len(series), place=f"{MODE_NAMES[mode]} trajectory"),
            subject=name, cause=causes.FAULT.format(f"drifts from the invariant '{name}'"))


PROBES = {
    "DAE806": invariant_drift,
}
