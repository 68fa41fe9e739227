"""The Continuous-Time Mode Jacobian as the derivative probes see it, in DAE or ODE mode: rows,
columns and declared sparsity.

**DAE mode** (switch on): the unknowns (rows) are the residuals, the state derivatives and the
outputs (not the event indicators: events in DAE mode are out of alpha.1's scope, Q-03); the
knowns (columns) the states, the algebraic variables, the inputs and time. The *declared* sparsity is the manifest's ``dependencies`` (what an importer
colours its own Jacobian with), with each entry's ``dependenciesKind``.

**ODE mode** (switch off, or an ordinary Model Exchange FMU): the rows are modelDescription's
``<ContinuousStateDerivative>``, ``<Output>`` and ``<EventIndicator>`` elements, the columns the
knowns of Continuous-Time Mode an importer can move (MS-10, PD-05): the states, the continuous
inputs and time; the declared sparsity is modelDescription's.

Event indicators and discrete outputs are measured by finite differences only: they are never
unknowns of fmi3GetDirectionalDerivative in Continuous-Time Mode (PD-03, PD-04), so a row says
whether the FMU's derivatives may be asked for it (``derivable``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model.attributes import declared_nominal, usable_bounds, usable_nominal
from ...report.findings import Location
from ...model.description import ModelDescription, Unknown, Variable
from ...numerics import colouring as col
from .api import ProbeContext


MODE_NAMES = {"dae": "DAE mode", "ode": "ODE mode"}


@dataclass(frozen=True)
class Row:
    vr: int
    name: str
    role: str                   # residual | derivative | output | indicator | initial
    explicit: bool              # the dependencies attribute is present (a claim)
    location: Location
    nominal: float | None = None  # declared nominal (residuals are scaled by it when given)
    derivable: bool = True      # may be an unknown of the FMU's derivative functions


@dataclass(frozen=True)
class Column:
    vr: int
    name: str
    role: str                   # state | algebraic | input | time
    nominal: float
    lower: float
    upper: float


@dataclass(frozen=True)
class JacobianLayout:
    """Rows, columns and the declared sparsity of a Jacobian (one mode)."""

    rows: tuple[Row, ...]
    cols: tuple[Column, ...]
    pattern: col.Pattern
    kinds: tuple[str, ...]              # dependenciesKind of each declared entry
    dd_columns: np.ndarray              # bool (n,): knowns passed to the FMU's derivatives
    mode: str = "dae"                   # "dae" or "ode"

    @property
    def dd_rows(self) -> np.ndarray:
        """bool (m,): the unknowns the FMU's derivative functions may be asked for."""
        return np.array([r.derivable for r in self.rows], dtype=bool)

    @property
    def nominal(self) -> np.ndarray:
        return np.array([c.nominal for c in self.cols])

    @property
    def row_nominal(self) -> np.ndarray:
        """The unknowns' declared nominal values, 1 where none is declared, shape (m,)."""
        return np.array([r.nominal or 1.0 for r in self.rows])

    def entry(self, i: int, j: int) -> str:
        return f"d({self.rows[i].name})/d({self.cols[j].name})"

    def indices(self, role: str, of: str = "cols") -> np.ndarray:
        items = self.cols if of == "cols" else self.rows
        return np.array([k for k, it in enumerate(items) if it.role == role], dtype=np.intp)


def _scalar_float(model: ModelDescription, vr: int | None) -> Variable | None:
    """A scalar Float64 variable: what fmi3GetFloat64, fmi3SetFloat64 and the state vector
    take (a Float32 or an array takes another call and is not probed)."""
    var = model.by_vr.get(vr) if vr is not None else None
    return var if var is not None and var.type == "Float64" and not var.dimensions else None


def _column(var: Variable, role: str) -> Column:
    lower, upper = usable_bounds(var.minimum, var.maximum)
    return Column(var.vr, var.name, role, usable_nominal(var.nominal), lower, upper)


def build_layout(ctx: ProbeContext, mode: str = "dae") -> tuple[JacobianLayout | None, str]:
    """The Jacobian's rows, columns and declared sparsity in ``mode``, or None and why."""
    model, manifest = ctx.model, ctx.manifest
    if model is None or (mode == "dae" and manifest is None):
        return None, "no model description or manifest"
    cols: list[Column] = []
    seen: set[int] = set()

    def add(var: Variable | None, role: str) -> None:
        if var is not None and var.vr not in seen:
            seen.add(var.vr)
            cols.append(_column(var, role))

    states = model.state_vrs()
    unsettable = [vr for vr in states if vr in model.by_vr and _scalar_float(model, vr) is None]
    if unsettable:  # fmi3SetContinuousStates takes them all, or the point is not set
        names = ", ".join(model.by_vr[vr].name for vr in unsettable[:3])
        return None, (f"a continuous state is not a scalar Float64 ({names}): the probes set "
                      "the state vector as scalar Float64 values only")
    for vr in states:
        add(_scalar_float(model, vr), "state")
    if mode == "dae":
        for ref in manifest.algebraic:
            add(_scalar_float(model, ref.vr), "algebraic")
    for var in model.variables:
        if var.causality == "input" and var.variability == "continuous":
            add(_scalar_float(model, var.vr), "input")
    independent = [v for v in model.variables if v.causality == "independent"]
    if independent:
        add(_scalar_float(model, independent[0].vr), "time")
    rows = _rows(model, manifest, seen) if mode == "dae" else _ode_rows(model, seen)
    if not rows or not cols:
        return None, "no residuals, derivatives, outputs or event indicators, or no knowns, to " \
                     "differentiate"
    return with_pattern(rows, cols, mode=mode), ""


def _row(var: Variable, role: str, u: Unknown, claim: bool) -> tuple[Row, Unknown]:
    derivable = role in ("residual", "derivative") or (
        role == "output" and var.variability == "continuous")
    return (Row(var.vr, var.name, role, claim, Location(file=u.file, line=u.line, path=u.path),
                declared_nominal(var.nominal), derivable), u)


_KINDS = (("Residual", "residual"), ("ContinuousStateDerivative", "derivative"),
          ("Output", "output"), ("EventIndicator", "indicator"))


def _rows(model: ModelDescription, manifest, knowns: set[int]) -> list[tuple[Row, Unknown]]:
    """DAE mode: no event indicators, whose DAE-mode meaning is open (Q-03: events in DAE mode
    are out of alpha.1's scope); event-indicators-failed and -inconsistent probe them."""
    out: list[tuple[Row, Unknown]] = []
    taken: set[int] = set()
    for kind, role in _KINDS[:3]:
        listed = manifest.unknowns(kind)
        # An element kind the manifest leaves out (open question Q-02): take the core list,
        # but claim nothing about its dependencies (those describe ODE mode).
        inherited = not listed and kind != "Residual"
        for u in (tuple(model.unknowns(kind)) if inherited else listed):
            var = _scalar_float(model, u.vr)
            if var is None or var.vr in taken or var.vr in knowns:
                continue
            taken.add(var.vr)
            out.append(_row(var, role, u, u.dependencies is not None and not inherited))
    return out


def _ode_rows(model: ModelDescription, knowns: set[int]) -> list[tuple[Row, Unknown]]:
    """modelDescription's unknowns of Continuous-Time Mode. An output that is itself a state
    is a known, not a row: whether its dependencies should name itself is open (FMI 3.0 says
    nothing; Reference-FMUs issue 657), which the static rule output-state-self-dependency
    reports as information."""
    out: list[tuple[Row, Unknown]] = []
    taken: set[int] = set()
    for kind, role in _KINDS[1:]:
        for u in model.unknowns(kind):
            var = _scalar_float(model, u.vr)
            if var is None or var.vr in taken or var.vr in knowns:
                continue
            taken.add(var.vr)
            out.append(_row(var, role, u, u.dependencies is not None))
    return out


def with_pattern(rows: list[tuple[Row, Unknown]], cols: list[Column], *,
                 mode: str = "dae") -> JacobianLayout:
    """The declared sparsity of ``rows`` over ``cols`` and each entry's dependenciesKind. A row
    without a ``dependencies`` attribute depends on every column; a dependenciesKind list whose
    length differs from the dependencies claims no kind (the static rules report it, and a
    probe finding must never be caused by the XML alone)."""
    index = {c.vr: j for j, c in enumerate(cols)}
    row_cols: list[list[int]] = []
    kinds_by_row: list[dict[int, str]] = []
    for row, u in rows:
        if not row.explicit:
            row_cols.append(list(range(len(cols))))
            kinds_by_row.append({})
            continue
        deps = u.dependencies or ()
        kinds = u.dependencies_kind or ()
        row_cols.append([index[vr] for vr in deps if vr in index])
        kinds_by_row.append({index[vr]: k for vr, k in zip(deps, kinds) if vr in index}
                            if len(kinds) == len(deps) else {})
    pattern = col.Pattern.from_rows(len(cols), row_cols)
    kinds_of = tuple(kinds_by_row[i].get(j, "dependent")
                     for i, j in zip(pattern.rows.tolist(), pattern.cols.tolist()))
    # Time is a known of the FMU's derivatives only where a dependencies list names it (PD-05).
    explicit_time = {j for (row, _), cs in zip(rows, row_cols) if row.explicit for j in cs
                     if cols[j].role == "time"}
    dd = np.array([c.role != "time" or j in explicit_time for j, c in enumerate(cols)])
    return JacobianLayout(tuple(r for r, _ in rows), tuple(cols), pattern, kinds_of, dd, mode)
