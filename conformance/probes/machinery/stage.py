"""The probe stage inside the worker process: load the binary, start the modes, run the probes.

The supervisor's child (``conformance.runtime.child``) calls :func:`run_job` with a
:class:`~conformance.runtime.protocol.Job` whose payload is a :class:`ProbeJob`. It loads the
binary, brings one instance into Continuous-Time Mode in DAE mode and one in ODE mode, samples
the points, and runs each probe in turn, sending one JSON event per step:

    {"event": "ready", "info": {...}}             setup done (points, seed)
    {"event": "load-failed", "violation": {...}}  the binary cannot be loaded
    {"event": "start", "code": "DAE7xx"}
    {"event": "partial", "code": ..., "violations": [...]}   a probe's findings, sent before
                                                  the first-cause re-check (kept if it dies)
    {"event": "done", "code": ..., "violations": [...], "skipped": reason|null, "info": {...},
     "consequences": [...], "replaces": bool (the violations of "partial" are superseded),
     "stats": {"seconds": s, "calls": n, "fmi_seconds": s, "peak_rss": bytes}}
    {"event": "memory", "code": ...}              Python itself ran out of memory
    {"event": "fatal", "code": ..., "call": ...}  a call returned fmi3Fatal: this process stops,
                                                  a fresh one runs the remaining probes and
                                                  never makes that call again
    {"event": "end"}

The runner (``conformance.probes.machinery.runner``) reads them and decides what a death means.
``stats`` (also in "ready", for the setup) is what the step cost: wall seconds, FMI calls and the
peak resident size of the worker during it; the driver logs them (``lsdae check -v``) and never puts
them in the report, which stays the same from run to run.

The first cause (``instances-not-independent``, DAE762): when a probe whose code DAE762's
``explains`` option lists found something and DAE762 is planned, the stage asks
:func:`.independence.survey` whether the instances of this process are independent. If they are
not, the probe is run again in a context where every instance is alone (a copy of the binary of
its own, ``Library.alone``; the points sampled the same way, with the same seed). What vanishes
there is sent as ``consequences``, not as violations: the runner folds them into DAE762's
finding, or restores them when DAE762 reported nothing. What the re-run still finds is the
probe's own finding, measured without the shared state.
"""
from __future__ import annotations

import mmap
import os
import sys
import time
import traceback
from typing import Any, Callable

import numpy as np

from ...report.findings import Violation, evidence
from ...runtime.callrecord import CallRecord
from ...runtime.child import memory_info, near_limit, reset_peak_memory
from ...runtime.layout import Layout
from ...runtime.library import Library
from ...runtime.modes import start_initialization, start_instance
from ...runtime.protocol import MEMORY_EXIT, Job, violation_json
from ..instruments.api import PLANNED, PLANNED_OPTIONS, FmiError, ProbeContext, ProbeSkipped
from ..instruments.common import renew_failed
from ..instruments.independence import FIRST, survey
from ..instruments.jacobian_layout import MODE_NAMES
from .deaths import not_loadable
from .job import ProbeJob
from .job import NARROW
from .narrowing import narrow
from .registry import FIRST_CAUSE, PROBES
from ..instruments.sampling import near_points, points_info, start_point

def run_job(job: Job, send: Callable[[dict[str, Any]], None]) -> int:
    """The child's entry point: run the probes of ``job``; returns the exit status."""
    return _Stage(job, send).run()


class _Stage:
    def __init__(self, job: Job, send: Callable[[dict[str, Any]], None]):
        self.job = job
        self.payload: ProbeJob = job.payload
        self.send = send
        self._sent: dict[str, Any] = {}   # the published-once info values already sent
        self._alone: ProbeContext | None = None   # every instance alone (the first cause)
        # every probe of the check, in this worker or in the other one (.lanes)
        self.planned = self.payload.planned or self.payload.probes
        self.first_cause: dict[str, Any] | None = next(
            (options for code, _, options in self.planned if code == FIRST_CAUSE), None)

    def run(self) -> int:
        started = time.perf_counter()
        with open(self.job.call_file, "r+b") as fh:
            record = CallRecord(mmap.mmap(fh.fileno(), CallRecord.SIZE))
        record.set_probe("setup")
        model = self.payload.model
        layout = Layout.build(model, self.payload.manifest)
        try:
            library = Library(self.job.directory, layout, record, blocked=self.job.blocked)
        except Exception as exc:  # fmpy raises plain Exception or AttributeError here
            self.send({"event": "load-failed",
                       "violation": violation_json(not_loadable(exc, self.job.directory))})
            return 0
        ctx = self._context(library, layout)
        self.send({"event": "ready", "info": self._info(ctx.facts["info"]),
                   "memory": memory_info(),
                   "stats": _stats(started, library.calls, library.seconds)})
        for code, name, options in self.payload.probes:
            renew_failed(ctx)  # a probe never inherits an instance another one terminated
            self._probe(ctx, record, code, name, options)
            if library.fatal:  # every instance is invalid now (SM-04): start afresh
                self.send({"event": "fatal", "code": code, "call": library.fatal_call})
                return 0
        record.set_probe("teardown")
        library.free_all()
        self.send({"event": "end"})
        return 0

    def _info(self, info: Any) -> dict[str, Any]:
        """The part of ``info`` to send with a "done" event: everything but the values of
        :data:`PUBLISHED_ONCE` already sent (the driver keeps what it received)."""
        if not isinstance(info, dict):
            return {}
        out = {}
        for key, value in info.items():
            if key in PUBLISHED_ONCE:
                if self._sent.get(key) is value:
                    continue
                self._sent[key] = value
            out[key] = value
        return out

    def _context(self, library: Library, layout: Layout) -> ProbeContext:
        facts: dict[str, Any] = {"layout": layout, "library": library, "info": {},
                                 PLANNED: frozenset(code for code, _, _ in self.planned),
                                 PLANNED_OPTIONS: {name: dict(options)
                                                   for _, name, options in self.planned}}
        evaluators: dict[str, Any] = {}
        modes: dict[str, str] = {}
        for mode in ("dae", "ode"):
            try:
                evaluators[mode] = start_instance(library, mode)
                modes[MODE_NAMES[mode]] = "probed"
            except (FmiError, ProbeSkipped) as exc:
                evaluators[mode] = None
                facts[f"{mode}_error"] = exc
                modes[MODE_NAMES[mode]] = f"not probed: {exc}"
        facts["info"]["modes"] = modes
        facts[FIRST] = evaluators["dae"]   # the process's first instance
        start = start_point(evaluators["dae"] or evaluators["ode"], layout,
                            facts.setdefault("start_nonfinite", {}))
        rng = np.random.default_rng(self.payload.seed)
        points = [start, *near_points(start, layout, rng)]
        facts["info"].update(points_info(points, layout, self.payload.seed))
        return ProbeContext(
            model=self.payload.model, manifest=self.payload.manifest, draft=self.payload.draft,
            seed=self.payload.seed, rng=rng, points=points, dae=evaluators["dae"],
            ode=evaluators["ode"], new_instance=lambda mode, start_values=None: start_instance(
                library, mode, start_values=start_values),
            facts=facts, endurance=self.payload.endurance, died=tuple(self.payload.died),
            new_initialization=lambda mode, values, t: start_initialization(
                library, mode, values, t))

    def _probe(self, ctx: ProbeContext, record: CallRecord, code: str, name: str,
               options: dict[str, Any]) -> None:
        record.set_probe(code)
        self.send({"event": "start", "code": code})
        library: Any = ctx.facts["library"]
        calls, inside = library.calls, library.seconds
        reset_peak_memory()
        started = time.perf_counter()
        violations: list[Any] = []
        skipped = None
        try:
            probe = PROBES[code] if code != NARROW else (
                lambda ctx, **o: narrow(ctx, record, **o))
            for v in probe(ctx, **options):
                violations.append(v)
        except ProbeSkipped as exc:
            skipped = str(exc) or "skipped by the probe"
        except FmiError as exc:
            skipped = exc.cause()
        except MemoryError:
            self._out_of_memory(code)
        except Exception as exc:  # a defect of ours: report it, run the next probe
            if near_limit():   # an import or allocation failed for want of address space
                self._out_of_memory(code)
            violations.append(Violation(
                f"probe {code} {name} failed: {type(exc).__name__}: {exc}",
                evidence=evidence(rule=code, traceback=traceback.format_exc(limit=8)),
                rule="internal-error"))
        consequences: list[Any] = []
        replaces = bool(violations and skipped is None and not library.fatal
                        and self._explained(code))
        if replaces:   # sent first: a death in the survey or the re-run must not lose them
            self.send({"event": "partial", "code": code,
                       "violations": [violation_json(v) for v in violations]})
            violations, consequences = self._first_cause(ctx, code, options, violations)
        self.send({"event": "done", "code": code, "replaces": replaces,
                   "violations": [violation_json(v) for v in violations],
                   "consequences": [violation_json(v) for v in consequences],
                   "skipped": skipped, "info": self._info(ctx.facts.get("info", {})),
                   "stats": _stats(started, library.calls - calls, library.seconds - inside)})

    def _explained(self, code: str) -> bool:
        """DAE762 is planned and its ``explains`` option lists ``code``."""
        cause = self.first_cause
        return cause is not None and code in str(cause["explains"]).split()

    def _first_cause(self, ctx: ProbeContext, code: str, options: dict[str, Any],
                     violations: list[Any]) -> tuple[list[Any], list[Any]]:
        """(own violations, consequences): the violations of ``code`` are consequences of
        instances that are not independent when they vanish with every instance alone."""
        cause: Any = self.first_cause
        try:
            if not survey(ctx, copies=cause["alone_copies"], rtol=cause["rtol"],
                          atol=cause["atol"]).found:
                return violations, []
            if self._alone is None:
                library: Any = ctx.facts["library"]
                self._alone = self._context(library.alone(cause["alone_copies"]),
                                            ctx.facts["layout"])  # type: ignore[arg-type]
            renew_failed(self._alone)
            again = list(PROBES[code](self._alone, **options))
        except (FmiError, ProbeSkipped):
            return violations, []   # no re-run: the findings stand as they are
        except Exception:  # a defect of ours in the re-run must not hide the findings
            traceback.print_exc(file=sys.stderr)
            return violations, []
        return (again, []) if again else ([], violations)


    def _out_of_memory(self, code: str) -> None:
        """Python ran out of address space in probe ``code``: end this worker as a memory
        death (the driver decides whose: ``conformance.probes.machinery.deaths``)."""
        self.send({"event": "memory", "code": code})
        sys.stderr.flush()
        os._exit(MEMORY_EXIT)


# Info values a probe publishes once as a new object and never changes in place: sent again
# only when replaced (at 10,000 variables they are megabytes of JSON).
PUBLISHED_ONCE = ("points", "seed", "jacobian", "simulation")


def _stats(started: float, calls: int, inside: float) -> dict[str, Any]:
    """What a step cost: wall seconds since ``started``, ``calls`` FMI calls and ``inside``
    seconds in them, the peak resident size since the last :func:`reset_peak_memory` (bytes;
    None off Linux)."""
    return {"seconds": round(time.perf_counter() - started, 6), "calls": int(calls),
            "fmi_seconds": round(inside, 6), "peak_rss": memory_info(("VmHWM",)).get("VmHWM")}
