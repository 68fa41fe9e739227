"""Two workers at once for a large FMU: which probe families run in which, and when.

A probe family may read what another family found in the same worker (``ctx.facts``): the
simulation trusts the FMU's directional derivatives only when the derivative survey confirmed
them, and leaves a gap between the modes to ode-dae-inconsistent (derivatives), to the
event-indicator rules and to next-event-time-not-ahead (events) when those found it;
invariant-drift reads the simulation's runs; dg/dw reads the derivative survey. Those
families, derivatives, events and simulation, form the first lane. Every other family reads
nothing another family found, only what the worker measures for itself (its instances, its
points, which are the same in both workers: same seed, same sampling), so they form the
second: evaluation (the handshake among it), read-back (the start values, the reads, the rare
calls), initialization and endurance. The first cause (instances-not-independent,
:mod:`.stage`) is asked in the worker whose probe found something, which measures it itself.

Both workers are told every probe the check plans (``ProbeJob.planned``), so that a probe that
leaves a verdict to a rule "to run" sees the same plan as in one worker. Each lane keeps the
order of the one-worker run (the start values first, the rare calls and the endurance probes
last), and each worker's instances live in a process of their own, so the verdicts are those of
one worker; ``tests/probes/test_lanes.py`` checks that on FMUs whose probes find something.
One thing differs by design: each lane restarts its own workers, at most ``max_restarts`` times
(option of binary-crashed), so an FMU that crashes in every probe is reported crashing in the
probes of both lanes, where one worker gives up after the first few. An FMI function that hung
or returned fmi3Fatal in one lane is not called by the other's next workers either.

Two workers are worth it only when the probes take long: an FMU with at least
:data:`LARGE_MODEL` variables (a small FMU would pay a second worker's start, about half a
second, for nothing). The choice depends on the FMU alone, not on the machine or on ``-j``: the
findings are the same either way, but the measured numbers of the evidence may differ in their
last digits (an FMU that solves its algebraic loop by Newton's method starts from where its
instance was left, and the lanes leave their instances in other places), and a report must be
the same wherever it is made. ``lsdae check --probe-workers`` chooses otherwise.

:class:`Lanes` runs the lanes' drivers at once (``conformance.probes.machinery.runner`` builds
them).
"""
from __future__ import annotations

import threading
from typing import Any, Protocol, Sequence

from ...report.catalogue import RuleSpec
from .registry import FAMILY_OF

#: The families that read each other's facts (see the docstring): the first lane.
FIRST_LANE: frozenset[str] = frozenset({"derivatives", "simulation", "events"})

#: Variables of modelDescription.xml from which ``auto`` uses two workers.
LARGE_MODEL = 1000


def workers_for(model: Any, chosen: int = 0) -> int:
    """How many workers probe ``model``: ``chosen`` when it is 1 or 2, else (0, ``auto``) two
    for a model of at least :data:`LARGE_MODEL` variables, else one."""
    if chosen in (1, 2):
        return chosen
    size = len(getattr(model, "variables", ()) or ())
    return 2 if size >= LARGE_MODEL else 1


def split(probes: Sequence[RuleSpec], workers: int) -> list[list[RuleSpec]]:
    """The probes of each worker, each list in the order of ``probes``; one list when
    ``workers`` is 1 or one lane would be empty."""
    if workers < 2:
        return [list(probes)]
    first = [p for p in probes if FAMILY_OF.get(p.code) in FIRST_LANE]
    second = [p for p in probes if FAMILY_OF.get(p.code) not in FIRST_LANE]
    return [first, second] if first and second else [list(probes)]


class Lane(Protocol):
    """What :class:`Lanes` runs: a :class:`~conformance.probes.machinery.driver.Driver`."""

    def drive(self) -> None: ...

    def stop(self) -> None: ...


class Lanes:
    """Drivers that run at once: the first in this thread, each other one in a thread of its
    own. An exception here (an interrupt) stops them all before it goes on; one in a lane's
    thread (a defect of ours) is raised here once every lane ended."""

    def __init__(self, drivers: Sequence[Lane]):
        self.drivers = drivers
        self.errors: list[BaseException] = []

    def _run(self, driver: Lane) -> None:
        try:
            driver.drive()
        except BaseException as exc:  # handed to the first thread
            self.errors.append(exc)

    def drive(self) -> None:
        threads = [threading.Thread(target=self._run, args=(d,), daemon=True,
                                    name=f"lsdae-probe-lane-{n}")
                   for n, d in enumerate(self.drivers) if n]
        for thread in threads:
            thread.start()
        try:
            self.drivers[0].drive()
            for thread in threads:
                while thread.is_alive():
                    thread.join(0.1)      # short joins: an interrupt is not held up
        except BaseException:
            for driver in self.drivers:
                driver.stop()
            for thread in threads:
                thread.join()
            raise
        if self.errors:
            raise self.errors[0]
