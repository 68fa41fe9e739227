"""The :class:`~conformance.probes.api.Evaluator` on top of fmpy, used inside the worker process.

:class:`Library` loads the FMU's binary once (fmpy's ``FMU3Model``); every FMI call made through
it goes through one choke point, ``_call``, which

* writes the name of the call into the shared :class:`~conformance.probes.worker.CallRecord`
  *before* calling, so that the runner can name the call in progress when the process crashes,
  hangs or runs out of memory;
* counts the call;
* turns fmi3Discard, fmi3Error and fmi3Fatal into :class:`~conformance.probes.api.FmiError`
  carrying the messages the FMU logged during that call.

:class:`Instance` is one FMU instance: the handshake into Continuous-Time Mode in DAE or ODE mode
(:func:`start_instance`), and ``evaluate``/``directional``/``adjoint`` by value reference, using
the :class:`~conformance.probes.sampling.Layout` of the model (re-exported here). fmpy is
imported lazily.
"""
from __future__ import annotations

import ctypes
import logging
import os
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np

from .api import FmiError, Point, ProbeSkipped
from .sampling import Layout
from .worker import CallRecord

__all__ = ["CallRecord", "Dependency", "Instance", "Layout", "Library", "PointNotSet",
           "start_instance"]

log = logging.getLogger(__name__)

STATUS_NAMES = {0: "fmi3OK", 1: "fmi3Warning", 2: "fmi3Discard", 3: "fmi3Error", 4: "fmi3Fatal"}
MAX_LOG_MESSAGES = 200          # per call; an FMU that floods its logger is cut off here
MAX_MESSAGE_CHARS = 1000
INIT_CALLS = ("fmi3EnterInitializationMode", "fmi3ExitInitializationMode")
# fmi3DependencyKind in the order of the C enum; fmi3Independent has no XML counterpart (MS-13)
DEPENDENCY_KINDS = ("independent", "constant", "fixed", "tunable", "discrete", "dependent")
MAX_DEPENDENCIES = 10_000_000   # a larger count from the FMU is garbage, not an allocation


class Dependency(NamedTuple):
    """One entry of fmi3GetVariableDependencies: the independent's value reference, its
    dependenciesKind ("dependent", "constant", ..., or "invalid (k)" for a value outside the
    enum) and the element indices of independent and dependent (0 for scalars)."""

    vr: int
    kind: str
    element: int = 0
    dependent_element: int = 0


class PointNotSet(ProbeSkipped):
    """Setting a point's knowns failed inside evaluate/directional/adjoint.

    A :class:`ProbeSkipped`, not an :class:`FmiError`: the fault is a rejected set, which
    ``algebraic-not-settable`` (algebraic variables) and ``evaluation-failed`` (time, states,
    inputs) report; a probe that catches FmiError around an evaluation must not report it again.
    ``error`` is the FmiError of the set.
    """

    def __init__(self, point: Point, error: FmiError):
        first = f": {error.log[0]}" if error.log else ""
        super().__init__(f"cannot set point {point.label}: {error.call} returned "
                         f"{error.status}{first}")
        self.point, self.error = point, error


# ------------------------------------------------------------------------------ library

_RECORDING_CLASS: Any = None


def _recording_class() -> Any:
    """fmpy's FMU3Model with every FMI call recorded, counted and checked (built lazily)."""
    global _RECORDING_CLASS
    if _RECORDING_CLASS is None:
        from fmpy.fmi3 import FMU3Model

        class RecordingFMU3Model(FMU3Model):  # type: ignore[misc, valid-type]
            lsdae_record: CallRecord
            lsdae_calls = 0
            lsdae_log: list[str]
            lsdae_blocked: frozenset[str] = frozenset()
            lsdae_fatal = False

            def _call(self, fname: str, *args: Any) -> Any:
                function = self._functions[fname]
                if fname in self.lsdae_blocked:  # not an FmiError: probes must not report it
                    raise ProbeSkipped(f"{fname} is not called again: it did not return in an "
                                       "earlier probe (binary-timed-out)")
                del self.lsdae_log[:]  # the log holds the messages of the last call only
                self.lsdae_record.enter(fname)
                result = function(*args)
                self.lsdae_record.leave()
                self.lsdae_calls += 1
                if function.restype is ctypes.c_int and result not in (0, 1):
                    self.lsdae_fatal = self.lsdae_fatal or result == 4
                    status = STATUS_NAMES.get(result, f"the illegal status {result}")
                    raise FmiError(fname, status, self.lsdae_log)
                return result

        _RECORDING_CLASS = RecordingFMU3Model
    return _RECORDING_CLASS


class Library:
    """The FMU's binary, loaded once per worker process; creates :class:`Instance` objects."""

    def __init__(self, directory: str, layout: Layout, record: CallRecord, *,
                 blocked: Sequence[str] = ()):
        self.layout = layout
        self.record = record
        self.directory = directory
        self.log: list[str] = []
        self.instances: list[Instance] = []
        cls = _recording_class()
        # fmpy resolves every fmi3* symbol here (AR-07): a missing one raises. Loading runs
        # the library's constructors, so it is recorded like a call.
        record.enter("dlopen (loading the library)")
        self.fmu = cls(guid=layout.token, modelIdentifier=layout.model_identifier,
                       unzipDirectory=directory, instanceName="lsdae")
        record.leave()
        self.fmu.lsdae_record = record
        self.fmu.lsdae_log = self.log
        self.fmu.lsdae_blocked = frozenset(blocked)
        resources = os.path.join(directory, "resources")
        self.resource_path = resources + os.sep if os.path.isdir(resources) else None
        self._count = 0

    @property
    def calls(self) -> int:
        return self.fmu.lsdae_calls

    @property
    def fatal(self) -> bool:
        """An FMI call returned fmi3Fatal: no instance of this library may be used again."""
        return bool(self.fmu.lsdae_fatal)

    def logger(self, name: str) -> Callable[..., None]:
        def log_message(env: Any, status: int, category: bytes | None,
                        message: bytes | None) -> None:
            if len(self.log) >= MAX_LOG_MESSAGES:
                return
            text = (message or b"").decode("utf-8", "replace")[:MAX_MESSAGE_CHARS]
            label = STATUS_NAMES.get(status, str(status)).removeprefix("fmi3")
            self.log.append(f"[{label}] {name}: {text}")
        return log_message

    def next_name(self, mode: str) -> str:
        self._count += 1
        return f"lsdae-{mode}-{self._count}"

    def free_all(self) -> None:
        for inst in list(self.instances):
            inst.free()


# ------------------------------------------------------------------------------ instance

def _vrs(values: Sequence[int]) -> Any:
    return (ctypes.c_uint * len(values))(*values)


def _doubles(values: Sequence[float] | np.ndarray) -> Any:
    return (ctypes.c_double * len(values))(*[float(v) for v in values])


class Instance:
    """One FMU instance, driven by value reference; the Evaluator once in Continuous-Time Mode.

    ``mode`` is the mode it was started in ("dae" or "ode"); ``calls`` counts its FMI calls;
    ``started`` says how DAE mode was reached ("configuration" or "runtime-switch").
    """

    def __init__(self, library: Library, *, name: str):
        from fmpy.fmi3 import fmi3LogMessageCallback

        self.library = library
        self.layout = library.layout
        self.name = name
        self.mode = "ode"
        self.started = ""
        self.calls = 0
        self.initialised = False
        self._callback = fmi3LogMessageCallback(library.logger(name))  # kept alive here
        fmu = library.fmu
        self.component = self._fmi(
            "fmi3InstantiateModelExchange", name.encode(), self.layout.token.encode(),
            library.resource_path.encode() if library.resource_path else None,
            False, False, None, self._callback, instance=False)
        if not self.component:
            raise FmiError("fmi3InstantiateModelExchange", "NULL", library.log)
        library.instances.append(self)
        self._fmu = fmu

    def _fmi(self, fname: str, *args: Any, instance: bool = True) -> Any:
        self.calls += 1
        function = getattr(self.library.fmu, fname)
        return function(self.component, *args) if instance else function(*args)

    # -- state machine -------------------------------------------------------------------

    def enter_configuration_mode(self) -> None:
        self._fmi("fmi3EnterConfigurationMode")

    def exit_configuration_mode(self) -> None:
        self._fmi("fmi3ExitConfigurationMode")

    def enter_initialization_mode(self, start_time: float) -> None:
        self._fmi("fmi3EnterInitializationMode", False, 0.0, start_time, False, 0.0)
        self.initialised = True

    def exit_initialization_mode(self) -> None:
        self._fmi("fmi3ExitInitializationMode")

    def update_discrete_states(self) -> None:
        """fmi3UpdateDiscreteStates until no further update is needed (at most 10 times)."""
        flags = [ctypes.c_bool() for _ in range(5)]
        next_time = ctypes.c_double()
        for _ in range(10):
            self._fmi("fmi3UpdateDiscreteStates", *(ctypes.byref(f) for f in flags),
                      ctypes.byref(next_time))
            if not flags[0].value:
                break

    def enter_continuous_time_mode(self) -> None:
        self._fmi("fmi3EnterContinuousTimeMode")

    def enter_event_mode(self) -> None:
        self._fmi("fmi3EnterEventMode")

    def free(self) -> None:
        """Terminate (if initialised) and free the instance; errors here are ignored."""
        if not self.component:
            return
        try:
            if self.initialised:
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
        self._fmi("fmi3SetBoolean", _vrs([vr]), 1, values, 1)

    def get_boolean(self, vr: int) -> bool:
        values = (ctypes.c_bool * 1)()
        self._fmi("fmi3GetBoolean", _vrs([vr]), 1, values, 1)
        return bool(values[0])

    def get_float64(self, vrs: Sequence[int]) -> np.ndarray:
        out = np.zeros(len(vrs))
        if vrs:
            self._fmi("fmi3GetFloat64", _vrs(vrs), len(vrs),
                      out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(vrs))
        return out

    def set_float64(self, vrs: Sequence[int], values: Sequence[float] | np.ndarray) -> None:
        if vrs:
            self._fmi("fmi3SetFloat64", _vrs(vrs), len(vrs), _doubles(values), len(vrs))

    def set_time(self, t: float) -> None:
        self._fmi("fmi3SetTime", float(t))

    def set_states(self, values: Sequence[float] | np.ndarray) -> None:
        self._fmi("fmi3SetContinuousStates", _doubles(values), len(values))

    def get_states(self, n: int) -> np.ndarray:
        out = np.zeros(n)
        self._fmi("fmi3GetContinuousStates", out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                  n)
        return out

    def get_derivatives(self, n: int | None = None) -> np.ndarray:
        """fmi3GetContinuousStateDerivatives for the states of this instance's mode."""
        n = len(self.layout.states_for(self.mode)) if n is None else n
        out = np.zeros(n)
        self._fmi("fmi3GetContinuousStateDerivatives",
                  out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
        return out

    # -- the Evaluator -------------------------------------------------------------------

    def set_point(self, point: Point, *, algebraic: bool = True) -> None:
        """Set t, the states, the inputs and (DAE mode, unless ``algebraic`` is false) the
        algebraic variables of ``point``."""
        self.set_time(point.t)
        states = self.layout.states_for(self.mode)
        if states and all(vr in point.values for vr in states):
            self.set_states([point.values[vr] for vr in states])
        dae = self.mode == "dae" and algebraic
        knowns = [vr for vr in (*(self.layout.algebraic if dae else ()), *self.layout.inputs)
                  if vr in point.values]
        self.set_float64(knowns, [point.values[vr] for vr in knowns])

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
        return [Dependency(int(independents[k]),
                           DEPENDENCY_KINDS[kinds[k]] if 0 <= kinds[k] < len(DEPENDENCY_KINDS)
                           else f"invalid ({kinds[k]})", int(elements[k]),
                           int(dependent_elements[k])) for k in range(n)]

    def _derivative(self, fname: str, unknowns: Sequence[int], knowns: Sequence[int],
                    seed: np.ndarray, n_out: int) -> np.ndarray:
        seed = np.asarray(seed, dtype=float)
        out = np.zeros(n_out)
        self._fmi(fname, _vrs(list(unknowns)), len(unknowns), _vrs(list(knowns)), len(knowns),
                  _doubles(seed), len(seed), out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                  n_out)
        return out


# ----------------------------------------------------------------------------- handshake

def configure(inst: Instance, value: bool) -> None:
    """Configuration Mode: set the enable parameter (Instantiated -> Instantiated)."""
    vr = inst.layout.enable
    assert vr is not None
    inst.enter_configuration_mode()
    inst.set_boolean(vr, value)
    inst.exit_configuration_mode()


def reconfigure(inst: Instance, value: bool) -> None:
    """Reconfiguration Mode: set the enable parameter (Event Mode -> Event Mode)."""
    configure(inst, value)


def start_instance(library: Library, mode: str, *, runtime_switch: bool = True) -> Instance:
    """A new instance in Continuous-Time Mode, in ``mode`` ("dae" or "ode").

    DAE mode: Configuration Mode with the switch set true, then the ordinary initialisation
    (DAE-12). An FMU without an enable parameter is permanently in DAE mode and is initialised
    without Configuration Mode. Under alpha.1 an FMU may refuse to initialise in DAE mode
    (DAE-14); then, when the switch is tunable and ``runtime_switch`` is true, the instance is
    initialised in ODE mode and switched in Reconfiguration Mode (DAE-13).
    """
    layout = library.layout
    if mode == "ode" and layout.enable_status != "ok":
        raise ProbeSkipped("the FMU has no usable enable parameter, hence no ODE mode"
                           if layout.enable_status == "unusable" else
                           "the FMU has no enable parameter: it is permanently in DAE mode")
    if mode == "dae" and layout.enable_status == "unusable":
        raise ProbeSkipped("the enable parameter cannot be used (see the static findings)")
    inst = Instance(library, name=library.next_name(mode))
    try:
        if mode == "dae" and layout.enable is not None:
            configure(inst, True)
        try:
            inst.enter_initialization_mode(layout.start_time)
            inst.exit_initialization_mode()
            inst.started = "configuration"
        except FmiError as exc:
            if not (mode == "dae" and runtime_switch and layout.enable_tunable
                    and exc.call in INIT_CALLS):
                raise
            inst.free()
            inst = Instance(library, name=library.next_name(mode))
            inst.enter_initialization_mode(layout.start_time)
            inst.exit_initialization_mode()
            reconfigure(inst, True)
            inst.started = "runtime-switch"
        inst.update_discrete_states()
        inst.enter_continuous_time_mode()
    except BaseException:
        try:
            inst.free()
        except FmiError:
            pass
        raise
    inst.mode = mode
    return inst
