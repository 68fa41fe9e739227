"""The contract between the probe runner and the probes (dynamic rules).

A probe is a plain function, registered by rule code like the static checks, that runs INSIDE the
worker process (the only process that ever loads the FMU's binary) and yields
:class:`~conformance.report.findings.Violation` objects. It never decides code or severity.

    def initial_residual_nonzero(ctx: ProbeContext, *, rtol: float = 1e-6, atol: float = 1e-10
                                 ) -> Iterator[Violation]: ...

The runner (``conformance.probes.machinery.runner``) starts the worker
(``conformance.runtime.child``, whose entry ``conformance.probes.machinery.stage`` runs the probes),
hands it the model, manifest, seed and the probes to run, enforces the time and memory limits, and
turns a crash, hang or memory blow-up into a ``binary-*`` finding naming the FMI call in progress.
Violations of probes that completed before a crash are kept.

Every FMI call goes through an :class:`Evaluator` (implemented by ``conformance.runtime.instance``
on top of fmpy), which records the call in progress, the FMI status and the FMU's log messages.
"""
from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

import numpy as np

from ...report.findings import Violation
from ...model.manifest import Manifest
from ...model.description import ModelDescription
from ...runtime.errors import FmiError, Unavailable
from ...runtime.point import Evaluator, Point

__all__ = ["EVENT_INDICATOR_FAULT", "Evaluator", "FmiError", "INFO_KEYS", "NEXT_EVENT_FAULT",
           "ODE_DAE_FAULT", "PLANNED", "PLANNED_OPTIONS", "Point", "Probe", "ProbeContext", "ProbeSkipped", "noted"]


# A probe that cannot run on this FMU raises ProbeSkipped; the message is the reason, reported in
# ``rules_skipped``. It is the runtime's Unavailable, so that what the runtime cannot do (no ODE
# mode, a call blocked after a hang, a point that cannot be set) skips the probe the same way. An
# FmiError escaping a probe is reported the same way (the probe could not complete).
ProbeSkipped = Unavailable


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
    # a fresh instance in mode "dae" or "ode"; start_values= (vr -> value) set before it starts
    new_instance: Callable[..., Evaluator]
    facts: dict[str, object] = field(default_factory=dict)  # shared between probes (memo)
    endurance: str = "quick"       # the endurance level (--endurance): "quick" or "long"
    died: tuple[str, ...] = ()     # probes during which an earlier worker of this FMU died
    # A fresh instance in Initialization Mode: (mode, start values by vr, start time) -> an
    # object with get_float64, directional_as_set and free (runtime.modes.start_initialization)
    new_initialization: Callable[[str, Mapping[int, float], float], Any] | None = None


Probe = Callable[..., Iterable[Violation]]


# Facts one family leaves for another (families never import each other): the first finding of
# the event-indicator probes, which the simulation probes read before blaming runs that
# root-find on those indicators; the first finding of ode-dae-inconsistent, which the
# trajectory comparison reads before leaving a gap at the initial point to it.
EVENT_INDICATOR_FAULT = "event_indicators.fault"
ODE_DAE_FAULT = "ode_dae.fault"
# the first finding of next-event-time-not-ahead, which the simulation's
# next-event-time-behind-during-simulation reads before reporting the same fault again
NEXT_EVENT_FAULT = "events.next_event_time"
# The codes the check runs (a frozenset), in this worker or in the other one (.lanes): a probe may
# leave a verdict to another rule only when that rule is to run.
PLANNED = "planned"
# The options of every planned probe, by rule name (a dict): what another rule's options say
# (directional-derivative-mismatch's tolerances) is the same in every worker.
PLANNED_OPTIONS = "planned.options"


def noted(fact: str, code: str, probe: Callable[..., Iterator[Violation]]
          ) -> Callable[..., Iterator[Violation]]:
    """``probe``, recording its first violation as ``"CODE: message"`` in ``ctx.facts[fact]``
    (another family reads it; the signature stays the probe's, for its options)."""
    def run(ctx: ProbeContext, **options: Any) -> Iterator[Violation]:
        for violation in probe(ctx, **options):
            ctx.facts.setdefault(fact, f"{code}: {violation.text}")
            yield violation
    run.__wrapped__ = probe  # type: ignore[attr-defined]
    run.__signature__ = inspect.signature(probe)  # type: ignore[attr-defined]
    run.__name__ = probe.__name__
    return run

# Keys a probe may put into the report's per-FMU ``info`` (through ``ctx.facts["info"]``),
# read by the HTML reporter for its plots:
#   "jacobian": {"rows": [names], "cols": [names], "mode": "dae" | "ode",
#                "declared": [[i, j], ...], "observed": [[i, j], ...]}
#   "probe_errors": [{"rule": code, "entry": "d(g1)/d(y)", "error": float,
#                     "tolerance": float}, ...]
#   "points": [{"label": str, "t": float, "values": {name: float}}], "seed": int
#   "endurance": {"level": str, "path_calls": int, "path_steps": int, "laps": int,
#                 "stopped": str, "budget_calls": int, "cycles": int}   (docs/json-report.md)
INFO_KEYS = ("jacobian", "probe_errors", "points", "seed", "endurance")
