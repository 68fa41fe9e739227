"""What instance calls give back besides numbers: a variable dependency, the result of an event
update, and the two ways setting a point can fail (which kind of known, which point); and which
fmi3Get<type> reads a variable of each type, into which C type."""
from __future__ import annotations

import ctypes
from typing import Any, NamedTuple, Sequence

from .errors import FmiError, Unavailable
from .point import Point


# fmi3Get<type> and its C element type, by the XML element of the variable (SG-09)
GETTERS: dict[str, tuple[str, Any]] = {
    "Float32": ("fmi3GetFloat32", ctypes.c_float), "Float64": ("fmi3GetFloat64", ctypes.c_double),
    "Int8": ("fmi3GetInt8", ctypes.c_int8), "UInt8": ("fmi3GetUInt8", ctypes.c_uint8),
    "Int16": ("fmi3GetInt16", ctypes.c_int16), "UInt16": ("fmi3GetUInt16", ctypes.c_uint16),
    "Int32": ("fmi3GetInt32", ctypes.c_int32), "UInt32": ("fmi3GetUInt32", ctypes.c_uint32),
    "Int64": ("fmi3GetInt64", ctypes.c_int64), "UInt64": ("fmi3GetUInt64", ctypes.c_uint64),
    "Enumeration": ("fmi3GetInt64", ctypes.c_int64), "Boolean": ("fmi3GetBoolean", ctypes.c_bool),
    "String": ("fmi3GetString", ctypes.c_char_p),
}


class Dependency(NamedTuple):
    """One entry of fmi3GetVariableDependencies: the independent's value reference, its
    dependenciesKind ("dependent", "constant", ..., or "invalid (k)" for a value outside the
    enum) and the element indices of independent and dependent (0 for scalars)."""

    vr: int
    kind: str
    element: int = 0
    dependent_element: int = 0


class KnownNotSet(FmiError):
    """Setting one kind of known of a point failed (in :meth:`Instance.set_point`).

    ``kind`` is what was being set: "time" (fmi3SetTime), "states" (fmi3SetContinuousStates),
    "algebraic variables", "inputs", or "algebraic variables and inputs" (one fmi3SetFloat64
    sets both when a point has both); ``vrs`` the value references, ``names`` their names,
    ``mode`` the instance's mode ("dae" or "ode", in Continuous-Time Mode). The call, status and
    log are those of the FmiError of the set.
    """

    def __init__(self, error: FmiError, kind: str, vrs: Sequence[int], names: Sequence[str],
                 mode: str):
        super().__init__(error.call, error.status, error.log)
        self.after = error.after
        self.kind, self.vrs, self.names, self.mode = kind, tuple(vrs), tuple(names), mode

    def describe(self) -> str:
        what = ""
        if self.vrs:
            shown = ", ".join(f"{n} (valueReference {vr})"
                              for n, vr in zip(self.names[:5], self.vrs[:5]))
            what = f" of the {self.kind} {shown}{', ...' if len(self.vrs) > 5 else ''}"
        first = f": {self.log[0]}" if self.log else ""
        return (f"{self.call}{what} returned {self.status} in {self.mode.upper()} mode, "
                f"Continuous-Time Mode{first}")


class PointNotSet(Unavailable):
    """Setting a point's knowns failed inside evaluate/directional/adjoint.

    An :class:`Unavailable` (a probe's ProbeSkipped), not an :class:`FmiError`: the fault is a
    rejected set, which ``algebraic-not-settable`` (algebraic variables),
    ``input-not-settable`` (inputs) and ``evaluation-failed`` (time, states) report; a probe
    that catches FmiError around an evaluation must not report it again.
    ``error`` is the :class:`KnownNotSet` of the set (``kind`` says what was being set).
    """

    def __init__(self, point: Point, error: FmiError):
        super().__init__(f"cannot set point {point.label}: {error.cause()}")
        self.point, self.error = point, error


class DiscreteStates(NamedTuple):
    """What fmi3UpdateDiscreteStates returned: discreteStatesNeedUpdate, terminateSimulation,
    nominalsOfContinuousStatesChanged, valuesOfContinuousStatesChanged, and nextEventTime
    (None when nextEventTimeDefined is false); ``calls``: how many calls gave it."""

    needs_update: bool
    terminate: bool
    nominals_changed: bool
    values_changed: bool
    next_time: float | None
    calls: int = 1
