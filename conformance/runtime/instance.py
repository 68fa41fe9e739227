"""One FMU instance, driven by value reference: the Evaluator once in Continuous-Time Mode.

``evaluate``/``directional``/``adjoint`` take a :class:`~conformance.runtime.point.Point` and read
the unknowns asked for, using the :class:`~conformance.runtime.layout.Layout` of the model.
"""
from __future__ import annotations

import ctypes
from typing import Any, Sequence

import numpy as np

from .arrays import all_in, double_array, pick, present, vr_array
from .errors import FmiError, Unavailable, Unsettled
from .library import Library
from .point import Point
from .records import GETTERS, Dependency, DiscreteStates, KnownNotSet, PointNotSet

__all__ = ["Dependency", "DiscreteStates", "Instance", "KnownNotSet", "PointNotSet",
           "Unavailable"]

# fmi3DependencyKind in the order of the C enum; fmi3Independent has no XML counterpart (MS-13)
DEPENDENCY_KINDS = ("independent", "constant", "fixed", "tunable", "discrete", "dependent")
_KIND_NAMES = dict(enumerate(DEPENDENCY_KINDS))   # fmi3DependencyKind -> its name
MAX_DEPENDENCIES = 10_000_000   # a larger count from the FMU is garbage, not an allocation
MAX_START_UPDATES = 10          # fmi3UpdateDiscreteStates calls after initialisation


class Instance:
    """One FMU instance, driven by value reference; the Evaluator once in Continuous-Time Mode.

    ``mode`` is the mode it was started in ("dae" or "ode"); ``calls`` counts its FMI calls;
    ``started`` says how DAE mode was reached ("configuration" or "runtime-switch");
    ``discrete`` is what the event update after initialisation said (nextEventTime...).
    ``failure`` is the first call that returned fmi3Error or fmi3Fatal (SM-04: the instance is
    in Terminated since; a later failing call carries it as ``after``), cleared by fmi3Reset.
    ``configuring``: in Configuration or Reconfiguration Mode (entered, not yet exited).
    """

    def __init__(self, library: Library, *, name: str):
        from fmpy.fmi3 import fmi3LogMessageCallback  # fmpy: loaded under the memory limit

        self.library = library
        self.layout = library.layout
        self.name = name
        self.mode = "ode"
        self.started = ""
        self.calls = 0
        self._joined: dict[tuple[int, int], tuple[Any, Any, tuple[int, ...]]] = {}
        self.failure: FmiError | None = None
        self.initialised = False
        self.initializing = False    # in Initialization Mode, where fmi3Terminate is not allowed
        self.configuring = False     # in (Re)Configuration Mode: only Set and Exit are allowed
        self.discrete: DiscreteStates | None = None   # the update that ended initialisation
        self._callback = fmi3LogMessageCallback(library.logger(name))  # kept alive here
        self._fmu = library.fmu_for_instance()   # the library's, or a copy of its own (alone)
        self.component = self._fmi(
            "fmi3InstantiateModelExchange", name.encode(), self.layout.token.encode(),
            library.resource_path.encode() if library.resource_path else None,
            False, False, None, self._callback, instance=False)
        if not self.component:
            raise FmiError("fmi3InstantiateModelExchange", "NULL", library.log)
        library.instances.append(self)

    def _fmi(self, fname: str, *args: Any, instance: bool = True) -> Any:
        self.calls += 1
        function = getattr(self._fmu, fname)
        try:
            return function(self.component, *args) if instance else function(*args)
        except FmiError as exc:
            if self.failure is not None:
                exc.after = self.failure
            elif exc.status in ("fmi3Error", "fmi3Fatal"):
                self.failure = exc
            raise

    # -- state machine -------------------------------------------------------------------

    def enter_configuration_mode(self) -> None:
        self._fmi("fmi3EnterConfigurationMode")
        self.configuring = True

    def exit_configuration_mode(self) -> None:
        self._fmi("fmi3ExitConfigurationMode")
        self.configuring = False

    def enter_initialization_mode(self, start_time: float) -> None:
        self._fmi("fmi3EnterInitializationMode", False, 0.0, start_time, False, 0.0)
        self.initialised = True
        self.initializing = True

    def exit_initialization_mode(self) -> None:
        self._fmi("fmi3ExitInitializationMode")
        self.initializing = False

    def update_discrete_states(self) -> DiscreteStates:
        """fmi3UpdateDiscreteStates until no further update is needed or the FMU asks to
        terminate (at most ``MAX_START_UPDATES`` times); what the last call said, with the
        number of calls. An iteration that has not settled by then is :class:`Unavailable`
        (what needs the instance in Continuous-Time Mode is skipped with this reason): FMI 3.0.2
        §2.3.5, while discreteStatesNeedUpdate is true the importer "must stay in EventMode",
        so fmi3EnterContinuousTimeMode may not follow."""
        for calls in range(1, MAX_START_UPDATES + 1):
            update = self.update_discrete_states_once()
            if not update.needs_update or update.terminate:
                return update._replace(calls=calls)
        raise Unsettled("the event iteration after initialisation does not settle: "
                          "fmi3UpdateDiscreteStates still says discreteStatesNeedUpdate after "
                          f"{MAX_START_UPDATES} calls, and Continuous-Time Mode may not be "
                          "entered before it says false")

    def update_discrete_states_once(self) -> DiscreteStates:
        """One fmi3UpdateDiscreteStates: its flags and nextEventTime (None when not defined)."""
        flags = [ctypes.c_bool() for _ in range(5)]
        next_time = ctypes.c_double()
        self._fmi("fmi3UpdateDiscreteStates", *(ctypes.byref(f) for f in flags),
                  ctypes.byref(next_time))
        needs, terminate, nominals, values, defined = (bool(f.value) for f in flags)
        return DiscreteStates(needs, terminate, nominals, values,
                              float(next_time.value) if defined else None)

    def call(self, fname: str, *args: Any) -> Any:
        """One FMI call with raw ctypes arguments the caller built, counted and checked like
        every other: for probes that must pass what the methods here never pass (sentinels,
        wrong sizes), and for a run that makes the same call many times with C arrays made
        once."""
        return self._fmi(fname, *args)

    def enter_continuous_time_mode(self) -> None:
        self._fmi("fmi3EnterContinuousTimeMode")

    def enter_event_mode(self) -> None:
        self._fmi("fmi3EnterEventMode")

    def reset(self) -> None:
        """fmi3Reset: back to Instantiated, start values included (MV-23, DAE-11)."""
        self._fmi("fmi3Reset")
        self.failure = None
        self.initialised = False
        self.configuring = False
        self.mode = "ode"

    def free(self) -> None:
        """Leave (Re)Configuration Mode, terminate (if initialised, and not still in
        Initialization Mode, where FMI 3.0 does not list fmi3Terminate) and free the instance;
        errors here are ignored. An instance a call put in Terminated is only freed."""
        if not self.component:
            return
        if self.library.fatal:  # after fmi3Fatal no function may be called at all (SM-04)
            self.component = None
            if self in self.library.instances:
                self.library.instances.remove(self)
            return
        try:
            if self.configuring and self.failure is None:
                # FMI 3.0.2 §2.3.6, §2.3.7: (Re)Configuration Mode allows only fmi3Set* and
                # fmi3ExitConfigurationMode, and lies outside the super state fmi3FreeInstance
                # leaves: back to Instantiated or Event Mode first (still there if refused)
                self.exit_configuration_mode()
        except FmiError:
            pass
        try:
            # FMI 3.0.2 §2.3.8: fmi3Terminate is not allowed in Terminated, where an fmi3Error
            # (or fmi3Fatal) put the instance (§2.3.1); nor in Reconfiguration Mode (§2.3.7)
            if (self.initialised and not self.initializing and not self.configuring
                    and self.failure is None):
                self._fmi("fmi3Terminate")
        except FmiError:
            pass
        self._fmi("fmi3FreeInstance")
        self.component = None
        if self in self.library.instances:
            self.library.instances.remove(self)

    # -- values --------------------------------------------------------------------------

    def set_boolean(self, vr: int, value: bool) -> None:
        values = (ctypes.c_bool * 1)(value)
        self._fmi("fmi3SetBoolean", vr_array([vr]), 1, values, 1)

    def get_boolean(self, vr: int) -> bool:
        values = (ctypes.c_bool * 1)()
        self._fmi("fmi3GetBoolean", vr_array([vr]), 1, values, 1)
        return bool(values[0])

    def get_float64(self, vrs: Sequence[int]) -> np.ndarray:
        out = np.zeros(len(vrs))
        if vrs:
            self._fmi("fmi3GetFloat64", vr_array(vrs), len(vrs),
                      out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(vrs))
        return out

    def get_typed(self, type_: str, vrs: Sequence[int], n: int, *, fill: Any = None
                  ) -> list[Any]:
        """fmi3Get<type> of ``vrs`` holding ``n`` values in all (arrays serialized, SG-09), as
        Python numbers, booleans or strings (a NULL string reads as None); the buffer holds
        ``fill`` before the call when given (what an element the FMU does not write keeps)."""
        fname, ctype = GETTERS[type_]
        values = (ctype * n)(*([fill] * n if fill is not None else []))
        self._fmi(fname, vr_array(vrs), len(vrs), values, n)
        if type_ == "String":
            return [v.decode("utf-8", "replace") if v is not None else None for v in values]
        return list(values)

    def set_float64(self, vrs: Sequence[int], values: Sequence[float] | np.ndarray) -> None:
        if vrs:
            self._fmi("fmi3SetFloat64", vr_array(vrs), len(vrs), double_array(values), len(vrs))

    def set_time(self, t: float) -> None:
        self._fmi("fmi3SetTime", float(t))

    def set_states(self, values: Sequence[float] | np.ndarray) -> None:
        self._fmi("fmi3SetContinuousStates", double_array(values), len(values))

    def get_states(self, n: int) -> np.ndarray:
        out = np.zeros(n)
        self._fmi("fmi3GetContinuousStates", out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                  n)
        return out

    def get_nominals(self, n: int, fill: float = 0.0) -> np.ndarray:
        """fmi3GetNominalsOfContinuousStates into a buffer that holds ``fill`` before the call."""
        out = np.full(n, fill, dtype=float)
        self._fmi("fmi3GetNominalsOfContinuousStates",
                  out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
        return out

    def get_derivatives(self, n: int | None = None) -> np.ndarray:
        """fmi3GetContinuousStateDerivatives for the states of this instance's mode."""
        n = len(self.layout.states_for(self.mode)) if n is None else n
        out = np.zeros(n)
        self._fmi("fmi3GetContinuousStateDerivatives",
                  out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
        return out

    def number_of_event_indicators(self) -> int:
        """fmi3GetNumberOfEventIndicators."""
        count = ctypes.c_size_t()
        self._fmi("fmi3GetNumberOfEventIndicators", ctypes.byref(count))
        return int(count.value)

    def get_event_indicators(self, n: int) -> np.ndarray:
        """fmi3GetEventIndicators for ``n`` indicators (the FMU checks ``n``)."""
        out = np.zeros(n)
        self._fmi("fmi3GetEventIndicators", out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                  n)
        return out

    # -- the Evaluator -------------------------------------------------------------------

    def set_point(self, point: Point, *, algebraic: bool = True) -> None:
        """Set t, the states, the inputs and (DAE mode, unless ``algebraic`` is false) the
        algebraic variables of ``point``; a refused set is a :class:`KnownNotSet` saying what
        was being set (algebraic variables and inputs share one fmi3SetFloat64)."""
        self._known("time", (), lambda: self.set_time(point.t))
        values = point.values
        states = self.layout.states_for(self.mode)
        if states and all_in(states, values):
            self._known("states", states, lambda: self.set_states(pick(values, states)))
        dae = self.mode == "dae" and algebraic
        alg = present(self.layout.algebraic if dae else (), values)
        inputs = present(self.layout.inputs, values)
        knowns = self._knowns(alg, inputs)
        kind = ("algebraic variables and inputs" if alg and inputs
                else "algebraic variables" if alg else "inputs")
        self._known(kind, knowns, lambda: self.set_float64(knowns, pick(values, knowns)))

    def set_algebraic(self, point: Point) -> None:
        """Set the algebraic variables of ``point`` alone (a :class:`KnownNotSet` if refused)."""
        alg = present(self.layout.algebraic, point.values)
        self._known("algebraic variables", alg,
                    lambda: self.set_float64(alg, pick(point.values, alg)))

    def _knowns(self, alg: Sequence[int], inputs: Sequence[int]) -> Sequence[int]:
        """``alg`` then ``inputs``: one tuple per pair of the layout's tuples (kept, so the
        value references are converted once), a new list otherwise."""
        if not (isinstance(alg, tuple) and isinstance(inputs, tuple)):
            return [*alg, *inputs]
        key = (id(alg), id(inputs))
        held = self._joined.get(key)
        if held is None or held[0] is not alg or held[1] is not inputs:
            held = self._joined[key] = (alg, inputs, (*alg, *inputs))
        return held[2]

    def _known(self, kind: str, vrs: Sequence[int], action: Any) -> None:
        try:
            action()
        except FmiError as exc:
            error = KnownNotSet(exc, kind, vrs, [self.layout.name(vr) for vr in vrs],
                                self.mode)
            if self.failure is exc:
                self.failure = error
            raise error from None

    def _set_or_skip(self, point: Point) -> None:
        try:
            self.set_point(point)
        except FmiError as exc:
            raise PointNotSet(point, exc) from None

    def evaluate(self, point: Point, unknowns: Sequence[int]) -> np.ndarray:
        """Set ``point`` (PointNotSet if that fails), then fmi3GetFloat64 of ``unknowns``."""
        self._set_or_skip(point)
        return self.get_float64(list(unknowns))

    def directional(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                    seed: np.ndarray) -> np.ndarray:
        self._set_or_skip(point)
        return self._derivative("fmi3GetDirectionalDerivative", unknowns, knowns, seed,
                                len(unknowns))

    def adjoint(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                seed: np.ndarray) -> np.ndarray:
        self._set_or_skip(point)
        return self._derivative("fmi3GetAdjointDerivative", unknowns, knowns, seed, len(knowns))

    def directional_as_set(self, unknowns: Sequence[int], knowns: Sequence[int],
                           seed: np.ndarray) -> np.ndarray:
        """fmi3GetDirectionalDerivative at the values already set, no point set first: for
        callers that set time, states and algebraic variables themselves (the simulation)."""
        return self._derivative("fmi3GetDirectionalDerivative", unknowns, knowns, seed,
                                len(unknowns))

    def adjoint_as_set(self, unknowns: Sequence[int], knowns: Sequence[int],
                       seed: np.ndarray) -> np.ndarray:
        """fmi3GetAdjointDerivative at the values already set (see :meth:`directional_as_set`)."""
        return self._derivative("fmi3GetAdjointDerivative", unknowns, knowns, seed, len(knowns))

    def variable_dependencies(self, vr: int) -> list[Dependency]:
        """The per-element dependencies of ``vr`` in the instance's current state:
        fmi3GetNumberOfVariableDependencies, then fmi3GetVariableDependencies (FmiError if the
        FMU refuses either or reports an implausible count)."""
        count = ctypes.c_size_t()
        self._fmi("fmi3GetNumberOfVariableDependencies", vr, ctypes.byref(count))
        n = count.value
        if n > MAX_DEPENDENCIES:
            raise FmiError("fmi3GetNumberOfVariableDependencies",
                           f"an implausible nDependencies = {n}", self.library.log)
        if n == 0:
            return []
        dependent_elements = (ctypes.c_size_t * n)()
        independents = (ctypes.c_uint32 * n)()
        elements = (ctypes.c_size_t * n)()
        kinds = (ctypes.c_int * n)()
        self._fmi("fmi3GetVariableDependencies", vr, dependent_elements, independents,
                  elements, kinds, n)
        # whole C arrays to lists at once: indexing a ctypes array per element is slow
        return [Dependency(independent, _KIND_NAMES.get(kind, f"invalid ({kind})"), element,
                           dependent)
                for independent, kind, element, dependent in zip(
                    np.ctypeslib.as_array(independents).tolist(),
                    np.ctypeslib.as_array(kinds).tolist(),
                    np.ctypeslib.as_array(elements).tolist(),
                    np.ctypeslib.as_array(dependent_elements).tolist())]

    def _derivative(self, fname: str, unknowns: Sequence[int], knowns: Sequence[int],
                    seed: np.ndarray, n_out: int) -> np.ndarray:
        seed = np.asarray(seed, dtype=float)
        out = np.zeros(n_out)
        self._fmi(fname, vr_array(unknowns), len(unknowns), vr_array(knowns), len(knowns),
                  double_array(seed), len(seed),
                  out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n_out)
        return out
