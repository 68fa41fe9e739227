"""The FMU as the integrators see it: a DAE residual (DAE mode) or an ODE right-hand side.

:class:`FmuDae` drives an instance in DAE mode in Continuous-Time Mode: it sets time, the states
(fmi3SetContinuousStates) and the algebraic variables (fmi3SetFloat64), and reads the state
derivatives (fmi3GetContinuousStateDerivatives) and the residuals (fmi3GetFloat64). Its partial
derivatives ``d[f; g]/d[x; w]`` come from fmi3GetDirectionalDerivative, one call per group of
columns that share no row in the *declared* sparsity (the manifest ``dependencies``; CPR
colouring, ``conformance.numerics.colouring``), which is what an importer does. Without directional
derivatives, coloured forward differences of the same evaluations stand in.

:class:`FmuOde` drives an instance in ODE mode: states in, derivatives out, the FMU solving its
algebraic equations itself; the Jacobian ``df/dx`` is coloured by the modelDescription's
ContinuousStateDerivative dependencies. The algebraic variables are read at the output times.

A call that returns fmi3Discard, or non-finite values, is an
:class:`~conformance.numerics.limits.EvaluationFailed` the integrator may recover from by a
smaller step; fmi3Error and fmi3Fatal are not recoverable.

Both are :class:`~conformance.numerics.events.EventSystem` s when the FMU lists event indicators
(``indicator_names``; in DAE mode the manifest's, else modelDescription's): the indicators are
read with fmi3GetEventIndicators after setting t, the states (and w), and an event runs
fmi3EnterEventMode at the values of the event, fmi3UpdateDiscreteStates (one call each time the
event loop in ``numerics/events.py`` asks), fmi3EnterContinuousTimeMode and
fmi3GetContinuousStates. An FMU without event indicators sees none of these calls.
"""
from __future__ import annotations

import math

from typing import Any, Iterable, Sequence

import numpy as np

from ..numerics import colouring as col
from ..numerics import numdiff
from ..numerics.limits import EvaluationFailed
from ..runtime.errors import FmiError
from ..runtime.instance import DiscreteStates

DIRECTIONAL, FINITE_DIFFERENCES = "directional derivatives", "finite differences"


def _failed(exc: FmiError) -> EvaluationFailed:
    return EvaluationFailed(exc.call, exc.status, exc.log,
                            recoverable=exc.status == "fmi3Discard")


def pattern_from(unknowns: Iterable[object | None], columns: Sequence[int]) -> col.Pattern:
    """The declared sparsity of ``unknowns`` (model Unknown records, None for a row that
    lists nothing) over ``columns`` (value references): a row without a ``dependencies``
    attribute depends on every column."""
    index = {vr: j for j, vr in enumerate(columns)}
    rows = []
    for u in unknowns:
        deps = getattr(u, "dependencies", None)
        rows.append(range(len(columns)) if deps is None
                    else [index[vr] for vr in deps if vr in index])
    return col.Pattern.from_rows(len(columns), rows)


class _Coloured:
    """Partial derivatives of ``rows`` with respect to ``cols`` at the values already set: a
    dense array, or (``sparse``) a CSC matrix of the declared entries only."""

    def __init__(self, inst, rows: list[int], cols: list[int], pattern: col.Pattern,
                 nominal: np.ndarray, use_directional: bool, *, sparse: bool = False):
        self.inst, self.pattern = inst, pattern
        self.rows, self.cols = tuple(rows), tuple(cols)   # tuples: converted once per call
        self.nominal = nominal
        self.colouring = col.colour_columns(pattern)
        self.use_directional = use_directional
        self.source = DIRECTIONAL if use_directional else FINITE_DIFFERENCES
        self.sparse = sparse

    def _matrix(self, values: np.ndarray) -> Any:
        """The declared entries' ``values`` (pattern order) as the Jacobian."""
        p = self.pattern
        if self.sparse:
            import scipy.sparse as sp  # scipy: only for a Jacobian too large to be dense

            return sp.csc_array((values, (p.rows, p.cols)), shape=p.shape)
        jac = np.zeros(p.shape)
        jac[p.rows, p.cols] = values
        return jac

    def refuse(self, note: str) -> None:
        """Finite differences from now on: the FMU's directional derivatives were not
        confirmed (``note`` says why; it becomes part of the source text)."""
        self.use_directional = False
        self.source = f"{FINITE_DIFFERENCES} ({note})"

    def product(self, seed: np.ndarray) -> np.ndarray:
        """The FMU's ``J @ seed`` at the values already set."""
        return self.inst.directional_as_set(self.rows, self.cols, seed)

    def directional(self) -> Any:
        values = np.zeros(self.pattern.nnz)
        p = self.pattern
        for g in range(self.colouring.count):
            out = self.inst.directional_as_set(self.rows, self.cols, self.colouring.seed(g))
            k = self.colouring.entries[g]
            values[k] = out[p.rows[k]]
        return self._matrix(values)

    def differences(self, fun, y: np.ndarray, f0: np.ndarray) -> Any:
        """Coloured forward differences (one evaluation per group; step sizes of numdiff)."""
        steps = numdiff.step_sizes(y, self.nominal, method="forward")
        values = np.zeros(self.pattern.nnz)
        p = self.pattern
        for g in range(self.colouring.count):
            seed = self.colouring.seed(g, steps)
            out = fun(y + seed)
            k = self.colouring.entries[g]
            h = steps[p.cols[k]]
            values[k] = (out[p.rows[k]] - f0[p.rows[k]]) / np.where(h > 0, h, 1)
        return self._matrix(values)


class _Events:
    """The event side of an instance (numerics.events.EventSystem); ``y`` starts with the
    ``nx`` states. The subclass's ``_set`` sets (t, y) and remembers it in ``_set_at``."""

    inst: Any
    nx: int
    indicator_names: list[str]
    _set_at: tuple[float, bytes] | None

    def _set(self, t: float, y: np.ndarray) -> None: ...

    def indicators(self, t: float, y: np.ndarray) -> np.ndarray:
        try:
            self._set(t, y)
            return self.inst.get_event_indicators(len(self.indicator_names))
        except FmiError as exc:
            self._set_at = None
            raise _failed(exc) from None

    def enter_event_mode(self, t: float, y: np.ndarray) -> None:
        try:
            self._set(t, y)
            self._set_at = None  # the event may change what (t, y) gives: set it again after
            self.inst.enter_event_mode()
        except FmiError as exc:
            raise _fatal(exc) from None

    def update_discrete_states(self) -> DiscreteStates:
        try:
            return self.inst.update_discrete_states_once()
        except FmiError as exc:
            raise _fatal(exc) from None

    def enter_continuous_time_mode(self) -> None:
        try:
            self.inst.enter_continuous_time_mode()
        except FmiError as exc:
            raise _fatal(exc) from None

    def read_states(self, y: np.ndarray) -> np.ndarray:
        out = np.array(y, dtype=float)
        try:
            out[:self.nx] = self.inst.get_states(self.nx)
        except FmiError as exc:
            raise _fatal(exc) from None
        return out


def _fatal(exc: FmiError) -> EvaluationFailed:
    """A failed call at an event: no smaller step gets past it."""
    return EvaluationFailed(exc.call, exc.status, exc.log, recoverable=False)


class FmuDae(_Events):
    """``F = [f; g]`` of an instance in DAE mode, with ``y = [x; w]`` (see numerics.consistent.DaeSystem)."""

    def __init__(self, inst, layout, manifest, *, dense_up_to: int,
                 use_directional: bool = True):
        self.inst, self.layout = inst, layout
        self.states, self.algebraic = tuple(layout.states), tuple(layout.algebraic)
        self.derivatives, self.residuals = tuple(layout.derivatives), tuple(layout.residuals)
        self.nx, self.nw = len(self.states), len(self.algebraic)
        cols = [*self.states, *self.algebraic]
        self.names = [layout.name(vr) for vr in cols]
        self.nominal = np.array([layout.scale(vr) for vr in cols], dtype=float)
        by_vr = {u.vr: u for kind in ("ContinuousStateDerivative", "Residual")
                 for u in (manifest.unknowns(kind) if manifest is not None else ())}
        pattern = pattern_from([by_vr.get(vr) for vr in (*self.derivatives, *self.residuals)],
                               cols)
        self.jac = _Coloured(inst, [*self.derivatives, *self.residuals], cols, pattern,
                             self.nominal, use_directional and layout.provides_directional,
                             sparse=len(cols) > dense_up_to)
        self.pattern = (pattern.rows, pattern.cols)   # what a sparse Jacobian may hold
        self.jacobian_source = self.jac.source
        self.indicator_names = [layout.name(vr) for vr in layout.event_indicators]
        self._set_at: tuple[float, bytes] | None = None

    @property
    def fmi_calls(self) -> int:
        return int(self.inst.calls)

    def _set(self, t: float, y: np.ndarray) -> None:
        key = (float(t), np.asarray(y, dtype=float).tobytes())
        if key == self._set_at:
            return
        self._set_at = None
        self.inst.set_time(t)
        self.inst.set_states(y[:self.nx])
        self.inst.set_float64(self.algebraic, y[self.nx:])
        self._set_at = key

    def evaluate(self, t: float, y: np.ndarray) -> np.ndarray:
        try:
            self._set(t, y)
            der = self.inst.get_derivatives(self.nx)
            res = self.inst.get_float64(self.residuals)
        except FmiError as exc:
            self._set_at = None
            raise _failed(exc) from None
        return np.concatenate([der, res])

    def partials(self, t: float, y: np.ndarray) -> Any:
        if not self.jac.use_directional:
            return self.jac.differences(lambda v: self.evaluate(t, v), np.asarray(y, float),
                                        self.evaluate(t, y))
        try:
            self._set(t, y)
            return self.jac.directional()
        except FmiError as exc:
            self._set_at = None
            raise _failed(exc) from None


class FmuOde(_Events):
    """``x' = f(t, x)`` of an instance in ODE mode (see ode.OdeSystem)."""

    def __init__(self, inst, layout, model, *, dense_up_to: int,
                 use_directional: bool = True):
        self.inst, self.layout = inst, layout
        self.states, self.derivatives = tuple(layout.ode_states), tuple(layout.ode_derivatives)
        self.algebraic = tuple(layout.algebraic)
        self.nx = len(self.states)
        self.names = [layout.name(vr) for vr in self.states]
        self.algebraic_names = [layout.name(vr) for vr in self.algebraic]
        self.nominal = np.array([layout.scale(vr) for vr in self.states], dtype=float)
        by_vr = {u.vr: u for u in model.unknowns("ContinuousStateDerivative")}
        pattern = pattern_from([by_vr.get(vr) for vr in self.derivatives], self.states)
        self.jac = _Coloured(inst, self.derivatives, self.states, pattern, self.nominal,
                             use_directional and layout.provides_directional,
                             sparse=self.nx > dense_up_to)
        self.pattern = (pattern.rows, pattern.cols)
        self.jacobian_source = self.jac.source
        self.indicator_names = [layout.name(vr) for vr in layout.ode_event_indicators]
        self._set_at: tuple[float, bytes] | None = None
        self._algebraic_readable = True
        self._event_mode = False   # entered Event Mode and not left it (terminateSimulation)
        self._at_event: tuple[float, np.ndarray] = (math.nan, np.empty(0))

    @property
    def fmi_calls(self) -> int:
        return int(self.inst.calls)

    def _set(self, t: float, x: np.ndarray) -> None:
        key = (float(t), np.asarray(x, dtype=float).tobytes())
        if key == self._set_at:
            return
        self._set_at = None
        self.inst.set_time(t)
        self.inst.set_states(x)
        self._set_at = key

    def evaluate(self, t: float, x: np.ndarray) -> np.ndarray:
        try:
            self._set(t, x)
            return self.inst.get_derivatives(self.nx)
        except FmiError as exc:
            self._set_at = None
            raise _failed(exc) from None

    def partials(self, t: float, x: np.ndarray) -> Any:
        if not self.jac.use_directional:
            return self.jac.differences(lambda v: self.evaluate(t, v), np.asarray(x, float),
                                        self.evaluate(t, x))
        try:
            self._set(t, x)
            return self.jac.directional()
        except FmiError as exc:
            self._set_at = None
            raise _failed(exc) from None

    def enter_event_mode(self, t: float, y: np.ndarray) -> None:
        # what the FMU computes at the event's (t, x) before it enters Event Mode: the output a
        # run the FMU ends there records, as the DAE-mode run records its own solve at (t, x)
        self._at_event = (float(t), self.algebraic_values(t, y))
        super().enter_event_mode(t, y)
        self._event_mode = True

    def enter_continuous_time_mode(self) -> None:
        super().enter_continuous_time_mode()
        self._event_mode = False

    def algebraic_values(self, t: float, x: np.ndarray) -> np.ndarray:
        """The algebraic variables the FMU computes in ODE mode (NaN if not readable). In Event
        Mode (a run the FMU ended with terminateSimulation, recording its last output at the
        event) they are those read at the event's (t, x) before the FMU entered Event Mode
        (nothing is set there: FMI 3.0.2 §2.3.5 allows neither fmi3SetTime nor
        fmi3SetContinuousStates), NaN at another time."""
        if not self.algebraic or not self._algebraic_readable:
            return np.full(len(self.algebraic), np.nan)
        if self._event_mode:
            at, values = self._at_event
            return values.copy() if at == float(t) else np.full(len(self.algebraic), np.nan)
        try:
            self._set(t, x)
            return self.inst.get_float64(self.algebraic)
        except FmiError:
            self._set_at = None
            self._algebraic_readable = False  # a local the FMU does not expose: stop asking
            return np.full(len(self.algebraic), np.nan)
