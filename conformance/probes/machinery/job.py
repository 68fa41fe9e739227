"""What the parent sends the probe worker: the job's payload and the worker's entry point.

Plain data, importable without numpy: the parent builds a :class:`ProbeJob` and pickles it into
the job file; the worker (:func:`conformance.probes.machinery.stage.run_job`, named by
:data:`ENTRY`) unpickles it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

ENTRY = "conformance.probes.machinery.stage:run_job"

#: lsdae's own step that narrows a crash to one variable (:mod:`.narrowing`): its code in the
#: job and, with the mode after a blank, in the call record.
NARROW = "narrow"


@dataclass
class ProbeJob:
    """The payload of a probe job: what the probes run on, and which probes with which options."""

    model: Any                     # ModelDescription
    manifest: Any                  # Manifest | None
    draft: str | None
    seed: int
    probes: list[tuple[str, str, dict[str, Any]]] = field(default_factory=list)  # code, name, opts
    endurance: str = "quick"       # the endurance level: "quick" or "long" ("off": not run)
    died: list[str] = field(default_factory=list)  # probes during which a worker died before
    # every probe the check plans, in every worker (code, name, options); empty: ``probes``
    planned: list[tuple[str, str, dict[str, Any]]] = field(default_factory=list)
