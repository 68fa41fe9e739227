"""What a call into the FMU's binary can end in, besides a value.

:class:`FmiError` is an FMI call that returned fmi3Discard, fmi3Error or fmi3Fatal (where a value
was needed), with the messages the FMU logged during that call. :class:`Unavailable` says that
what was asked cannot be done on this FMU (no ODE mode without an enable parameter, a function
not called again after it hung); its message is the reason. The probe stage reports both as the
reason a rule did not run (``conformance.probes.instruments.api.ProbeSkipped`` is
:class:`Unavailable`).
"""
from __future__ import annotations

from typing import Sequence


class FmiError(Exception):
    """An FMI call returned fmi3Error/fmi3Fatal (or fmi3Discard where a value was needed).

    ``call`` is the FMI function name, ``status`` its status name, ``log`` the FMU's messages.
    ``after`` is the earlier call on the same instance that had returned fmi3Error or fmi3Fatal
    (set by the instance, None otherwise): that call put the instance in Terminated (SM-04), so
    this failure is its consequence, not a fault of its own.
    """

    def __init__(self, call: str, status: str, log: Sequence[str] = ()):
        super().__init__(f"{call} returned {status}")
        self.call, self.status, self.log = call, status, tuple(log)
        self.after: FmiError | None = None

    def describe(self) -> str:
        """The call, its status and the FMU's first log line, as one line."""
        first = f": {self.log[0]}" if self.log else ""
        return f"{self.call} returned {self.status}{first}"

    def cause(self) -> str:
        """What to blame: this call, or the earlier failure this one follows from."""
        if self.after is None:
            return self.describe()
        return (f"{self.after.describe()}; that put the instance in Terminated (SM-04), so "
                f"{self.call} failed after it")


class Unavailable(Exception):
    """What was asked cannot be done on this FMU; the message is the reason."""


class Unsettled(Unavailable):
    """The event iteration after initialisation does not settle: fmi3UpdateDiscreteStates keeps
    saying discreteStatesNeedUpdate, so Continuous-Time Mode may not be entered (FMI 3.0.2
    §2.3.5). What needs that mode is skipped with this reason; the probe that runs the FMU as
    an importer does reports it."""
