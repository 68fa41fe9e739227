"""The contract between the probe runner and the probes (dynamic rules).

A probe is a plain function, registered by rule code like the static checks, that runs INSIDE the
worker process (the only process that ever loads the FMU's binary) and yields
:class:`~conformance.findings.Violation` objects. It never decides code or severity.

    def initial_residual_nonzero(ctx: ProbeContext, *, rtol: float = 1e-6, atol: float = 1e-10
                                 ) -> Iterator[Violation]: ...

The runner (``conformance.probes.runner``) starts the worker, hands it the model, manifest, seed
and the probes to run, enforces the time and memory limits, and turns a crash, hang or memory
blow-up into a ``binary-*`` finding naming the FMI call in progress. Violations of probes that
completed before a crash are kept.

Every FMI call goes through an :class:`Evaluator` (implemented by ``conformance.probes.session``
on top of fmpy), which records the call in progress, the FMI status and the FMU's log messages.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable, Mapping, Protocol, Sequence

import numpy as np

from ..findings import Violation
from ..manifest import Manifest
from ..model import ModelDescription


class FmiError(Exception):
    """An FMI call returned fmi3Error/fmi3Fatal (or fmi3Discard where a value was needed).

    ``call`` is the FMI function name, ``status`` its status name, ``log`` the FMU's messages.
    """

    def __init__(self, call: str, status: str, log: Sequence[str] = ()):
        super().__init__(f"{call} returned {status}")
        self.call, self.status, self.log = call, status, tuple(log)


class ProbeSkipped(Exception):
    """Raised by a probe that cannot run on this FMU (e.g. DAE mode could not be started);
    the message is the reason, reported in ``rules_skipped``. An :class:`FmiError` escaping a
    probe is reported the same way (the probe could not complete, it found nothing)."""


@dataclass(frozen=True)
class Point:
    """A sampling point: time and the values of states, algebraic variables and inputs by vr."""

    t: float
    values: Mapping[int, float]
    label: str = ""          # e.g. "start", "near-3"


class Evaluator(Protocol):
    """An instance in Continuous-Time Mode, in one mode (DAE or ODE), driven by value reference.

    All arrays are float64, ordered as the sequences of value references passed in.
    """

    mode: str                                  # "dae" or "ode"
    calls: int                                 # FMI calls made so far (for the benchmarks)

    def evaluate(self, point: Point, unknowns: Sequence[int]) -> np.ndarray:
        """Set t and the point's knowns (states via fmi3SetContinuousStates or SetFloat64,
        algebraic variables (DAE mode), inputs), then read ``unknowns`` with fmi3GetFloat64."""
        ...

    def directional(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                    seed: np.ndarray) -> np.ndarray:
        """fmi3GetDirectionalDerivative at the point: J[unknowns, knowns] @ seed."""
        ...

    def adjoint(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                seed: np.ndarray) -> np.ndarray:
        """fmi3GetAdjointDerivative at the point: seed @ J[unknowns, knowns]."""
        ...


@dataclass
class ProbeContext:
    """What a probe may use. ``dae``/``ode`` are None when that mode could not be started (the
    handshake probe reports why); ``points`` are the seeded sampling points, the first being
    the FMU's own initial point in DAE mode."""

    model: ModelDescription
    manifest: Manifest | None
    draft: str | None
    seed: int
    rng: np.random.Generator
    points: Sequence[Point]
    dae: Evaluator | None
    ode: Evaluator | None
    new_instance: Callable[[str], Evaluator]    # a fresh instance in mode "dae" or "ode"
    facts: dict[str, object] = field(default_factory=dict)  # shared between probes (memo)


Probe = Callable[..., Iterable[Violation]]


# Keys a probe may put into the report's per-FMU ``info`` (through ``ctx.facts["info"]``),
# read by the HTML reporter for its plots:
#   "jacobian": {"rows": [names], "cols": [names],
#                "declared": [[i, j], ...], "observed": [[i, j], ...]}
#   "probe_errors": [{"rule": code, "entry": "d(g1)/d(y)", "error": float,
#                     "tolerance": float}, ...]
#   "points": [{"label": str, "t": float, "values": {name: float}}], "seed": int
INFO_KEYS = ("jacobian", "probe_errors", "points", "seed")
