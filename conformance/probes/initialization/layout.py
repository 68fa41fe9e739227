"""The Jacobian of Initialization Mode as the InitialUnknown probes see it: rows, columns and
declared sparsity (for :mod:`.survey`).

**Which list.** In DAE mode the manifest's ``<InitialUnknown>`` elements replace the
modelDescription's (DAE-30): they are verified on DAE-mode instances, when the manifest lists
any (whether DAE mode inherits the modelDescription's list when it lists none is open, Q-02).
In ODE mode (the switch off, DAE-11, or an ordinary Model Exchange FMU) the modelDescription's
list is verified, whether or not the manifest has its own.

**Rows** are the scalar Float64 InitialUnknowns of that list. **Columns** are the knowns of
Initialization Mode that can be set as start values (MS-11, SG-01): scalar Float64 inputs and
variables with ``initial="exact"`` (parameters, states with an exact start, ...; never constants
or structural parameters), each with one finite XML start value, and the independent variable,
moved through the ``startTime`` of fmi3EnterInitializationMode and never below the
``<DefaultExperiment>`` start. Algebraic variables with ``initial="approx"`` are not perturbed:
their start values are guesses (Q-05), and a solution that depends on its guess is no
dependency. Nominal values and bounds are those of the runtime layout.
"""
from __future__ import annotations

import math


from ...model.attributes import declared_nominal
from ...report.findings import Location
from ...model.description import ModelDescription, Unknown, Variable
from ...runtime.layout import Layout
from ..instruments.api import ProbeContext
from ..instruments.jacobian_layout import Column, JacobianLayout, Row, with_pattern


def _number(text: str | None) -> float | None:
    """One finite number, or None (several tokens: an array start)."""
    tokens = (text or "").split()
    if len(tokens) != 1:
        return None
    try:
        value = float(tokens[0])
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _scalar_float64(model: ModelDescription, vr: int | None) -> Variable | None:
    var = model.by_vr.get(vr) if vr is not None else None
    return var if var is not None and var.type == "Float64" and not var.dimensions else None


def _role(var: Variable, states: set[int]) -> str | None:
    """The known's role in Initialization Mode, or None if it is no known that can be set as
    a start value (in Instantiated, where a clocked variable cannot be set: FMI 3.0.2 §2.2.7.2)."""
    if (var.variability == "constant" or var.causality in ("independent", "structuralParameter")
            or var.clocks):
        return None
    if var.causality == "input":
        return "input"
    if var.initial != "exact":
        return None
    if var.causality == "parameter":
        return "parameter"
    return "state" if var.vr in states else "exact"


def start_time(model: ModelDescription, layout: Layout) -> float:
    """The ``<DefaultExperiment>`` start time when it is a finite number, else the layout's."""
    experiment = model.default_experiment
    value = experiment.start_time if experiment is not None else None
    return float(value) if value is not None and math.isfinite(value) else layout.start_time


def choose_list(ctx: ProbeContext, layout: Layout, mode: str) -> tuple[list[Unknown], str]:
    """(the InitialUnknown elements ``mode`` promises, the reason when there are none)."""
    if mode not in layout.modes:
        return [], ("the FMU has no usable enable parameter, hence no ODE mode" if mode == "ode"
                    else "the FMU has no DAE mode")
    if mode == "dae":
        listed = list(ctx.manifest.unknowns("InitialUnknown")) if ctx.manifest else []
        return listed, "" if listed else (
            "the manifest lists no InitialUnknown (whether DAE mode inherits the "
            "modelDescription's list is open, Q-02)")
    core = list(ctx.model.unknowns("InitialUnknown"))
    return core, "" if core else "the modelDescription lists no InitialUnknown"


def build_initial_layout(ctx: ProbeContext, layout: Layout, mode: str
                         ) -> tuple[JacobianLayout | None, dict[int, float], str]:
    """(the Jacobian layout of Initialization Mode in ``mode``, the start value of each known
    that is not time, the reason when there is no layout)."""
    model = ctx.model
    if model is None:
        return None, {}, "no model description"
    unknowns, reason = choose_list(ctx, layout, mode)
    if not unknowns:
        return None, {}, reason
    states = set(layout.states_for(mode))
    cols: list[Column] = []
    start: dict[int, float] = {}
    for var in model.variables:
        if _scalar_float64(model, var.vr) is None or var.vr in start:
            continue
        role, value = _role(var, states), _number(var.start)
        if role is None or value is None:
            continue
        vr: int = var.vr  # type: ignore[assignment]
        lo, hi = layout.bounds.get(vr, (-math.inf, math.inf))
        cols.append(Column(vr, var.name, role, layout.scale(vr), lo, hi))
        start[vr] = min(max(value, lo), hi) if lo <= hi else value
    independent = [v for v in model.variables if v.causality == "independent"]
    if independent and _scalar_float64(model, independent[0].vr) is not None:
        time = independent[0]
        cols.append(Column(time.vr, time.name, "time", 1.0,  # type: ignore[arg-type]
                           start_time(model, layout), math.inf))
    rows = _rows(model, unknowns, {c.vr for c in cols})
    if not rows or not cols:
        return None, {}, ("no scalar Float64 InitialUnknown, or no known that can be set in "
                          "Initialization Mode, to differentiate")
    return with_pattern(rows, cols, mode=mode), start, ""


def _rows(model: ModelDescription, unknowns: list[Unknown], knowns: set[int]
          ) -> list[tuple[Row, Unknown]]:
    out: list[tuple[Row, Unknown]] = []
    taken: set[int] = set()
    for u in unknowns:
        var = _scalar_float64(model, u.vr)
        if var is None or var.vr is None or var.vr in taken or var.vr in knowns:
            continue
        taken.add(var.vr)
        out.append((Row(var.vr, var.name, "initial", u.dependencies is not None,
                        Location(file=u.file, line=u.line, path=u.path),
                        declared_nominal(var.nominal)), u))
    return out


