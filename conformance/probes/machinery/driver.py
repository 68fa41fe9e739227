"""Workers for one FMU, started until every probe has run or cannot run; deaths become findings.

:class:`Driver` starts ``python -m conformance.runtime.child`` (entry
:func:`conformance.probes.machinery.stage.run_job`) in the FMU's private temporary directory, reads
its events, enforces the time limits, and turns a crash, hang or memory blow-up into a ``binary-*``
finding naming the probe and the FMI call in progress, read from the shared
:class:`~conformance.runtime.callrecord.CallRecord` (a death during a probe of ``COUNTED``, the
endurance probes, also says after how many FMI calls). Each new worker is told the probes
during which an earlier one died (``ProbeJob.died``). The run it serves
(``conformance.probes.machinery.runner``) holds the outcome and the limits; its docstring gives the
policy.

What a death or a limit means, the binary's finding or lsdae's own limit, is decided by
:class:`.deaths.Diagnosis` (its docstring gives the rule: a limit reached while no FMI call was
in progress, or while only a short one was, is lsdae's own). For lsdae's own limits the probe is
listed as not run, with the limit and the reason, and the worker that was stopped for it is
replaced by a new one for the remaining probes, which the reason says too.
"""
from __future__ import annotations

import logging
import os
import pickle
import subprocess
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ...report.catalogue import RuleSpec
from ...report.findings import Location, Violation, evidence
from ...runtime.callrecord import CallRecord
from ...runtime.protocol import Job, violation_from_json
from ...runtime.supervisor import WorkerProcess
from .deaths import CRASHED, MEMORY, NOT_LOADABLE, TIMED_OUT, CallClock, Diagnosis
from .job import ENTRY, NARROW, ProbeJob

RUNNER_RULES = (CRASHED, TIMED_OUT, MEMORY, NOT_LOADABLE)
# The folder that holds conformance/ (one parent per dot of this module's name).
PACKAGE_ROOT = str(Path(__file__).resolve().parents[__name__.count(".")])

log = logging.getLogger(__name__)


@dataclass
class _Death:
    kind: str  # "end", "died", "timeout", "fmu-timeout", "load-failed", "fatal", "worker-error"
    probe: str = ""
    own: str = ""   # lsdae's own limit was reached (no FMI call in progress): the reason


class Driver:
    """Starts workers until every probe has run or cannot run; turns deaths into findings."""

    def __init__(self, run: Any, tmp: str, probes: list[RuleSpec], *,
                 others: list[RuleSpec] | None = None, blocked: list[str] | None = None,
                 lane: int = 0, narrowed: set[str] | None = None):
        """``others``: the probes the other lane's workers run (:mod:`.lanes`), which this
        lane's workers are told are planned; ``blocked``: the list of FMI functions not to be
        called again, shared by the lanes; ``lane``: this lane's number, in the steps' stats;
        ``narrowed``: the getters whose crash names one variable, shared by the lanes (one
        narrowing is enough)."""
        self.run, self.tmp, self.remaining = run, tmp, probes
        self.others, self.lane = list(others or ()), lane
        self.limits = run.limits
        self.call_file = os.path.join(tmp, "call")
        self.stderr_file = os.path.join(tmp, "worker.log")
        self.fmu_deadline = time.monotonic() + self.limits.fmu_seconds
        # FMI functions that hung or returned fmi3Fatal
        self.blocked: list[str] = [] if blocked is None else blocked
        self.died: list[str] = []      # probes during which a worker died or was killed
        self.diagnosis = Diagnosis(self)
        self.stopped = False           # stop(): the check was interrupted
        # crashes during a getter of several variables, to narrow to one ((call, how): value
        # references), and the getters whose crash already names one variable
        self.to_narrow: dict[tuple[str, str], tuple[int, ...]] = {}
        self.narrowed: set[str] = set() if narrowed is None else narrowed
        self._watch: WorkerProcess | None = None

    def stop(self) -> None:
        """End this lane from another thread: its worker is killed, and no new one started."""
        self.stopped = True
        if self._watch is not None:
            self._watch.signal_kill()

    def drive(self) -> None:
        self._drive()
        self._narrow()

    def _narrow(self) -> None:
        """One more worker for each crash during a getter of several variables: each of them
        read alone (:mod:`.narrowing`); a crash there is diagnosed as any other, and names the
        variable. Not when the check was stopped, or the per-FMU time is up."""
        for (call, _how), refs in list(self.to_narrow.items()):
            if self.stopped or time.monotonic() >= self.fmu_deadline or call in self.narrowed:
                return
            self._one_worker([(NARROW, NARROW, {"call": call, "refs": list(refs)})])

    def _drive(self) -> None:
        restarts, own = 0, 0
        while True:
            result = self._one_worker()
            if self.stopped:
                return
            if result.own:
                self._not_run_own(result)
            done = {c for c, _ in self.run.outcome.skipped} | self.run.outcome.run
            self.remaining = [r for r in self.remaining if r.code not in done]
            if result.kind == "end":
                self.run.skip(self.remaining, "the worker ended early", failed=True)
                return
            if result.kind == "load-failed":
                self.run.skip(self.remaining, "the binary cannot be loaded (binary-not-loadable)",
                              failed=True)
                return
            if result.kind == "fatal" and not self.remaining:
                return
            if result.kind == "fmu-timeout":
                self.run.skip(self.remaining, result.own or f"the per-FMU time limit of "
                              f"{self.limits.fmu_seconds:g} s was reached", failed=True)
                return
            if result.probe in ("setup", ""):
                self.run.skip(self.remaining, result.own or "the worker failed before the "
                              "probes could run (see the findings)", failed=True)
                return
            if not self.remaining:
                return
            restarts += 1
            own += bool(result.own)
            if restarts > self.limits.max_restarts:
                self.run.skip(self.remaining, f"the worker was restarted "
                              f"{self.limits.max_restarts} times" + (
                                  f", {own} of them after lsdae's own limits" if own else ""),
                              failed=True)
                return

    # -- one worker process --------------------------------------------------------------

    def _start(self, pseudo: list[tuple[str, str, dict[str, Any]]] | None = None
               ) -> subprocess.Popen[bytes]:
        """A worker for the remaining probes, or for ``pseudo`` (lsdae's own steps, such as
        :data:`.narrowing.NARROW`)."""
        ctx = self.run.ctx
        payload = ProbeJob(model=ctx.model, manifest=ctx.manifest, draft=ctx.draft,
                           seed=self.run.seed, endurance=self.run.endurance,
                           died=list(self.died),
                           probes=pseudo if pseudo is not None else
                           [(r.code, r.name, r.option_values) for r in self.remaining],
                           planned=[(r.code, r.name, r.option_values)
                                    for r in self.remaining + self.others] if self.others else [])
        job = Job(directory=os.path.join(self.tmp, "fmu"), call_file=self.call_file,
                  entry=ENTRY, payload=payload, blocked=list(self.blocked))
        job_file = os.path.join(self.tmp, "job.pickle")
        with open(job_file, "wb") as fh:
            pickle.dump(job, fh, protocol=pickle.HIGHEST_PROTOCOL)
        with open(self.call_file, "wb") as fh:
            fh.write(bytes(CallRecord.SIZE))
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (PACKAGE_ROOT, env.get("PYTHONPATH", "")) if p)
        # One thread per library and few malloc arenas keep the address space small.
        env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
                   MALLOC_ARENA_MAX="2", LSDAE_PROBE_PARENT=str(os.getpid()))
        limit = int(self.limits.address_space_mib) << 20
        with open(self.stderr_file, "wb") as err:
            return subprocess.Popen(
                [sys.executable, "-m", "conformance.runtime.child", job_file, str(limit)],
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=err, cwd=self.tmp,
                env=env, start_new_session=True)

    def _one_worker(self, pseudo: list[tuple[str, str, dict[str, Any]]] | None = None
                    ) -> _Death:
        proc = self._start(pseudo)
        watch = self._watch = WorkerProcess(proc)
        if self.stopped:   # stop() came while this worker started
            watch.signal_kill()
        clock = CallClock(self.call_file)
        current = "setup"
        step_deadline = time.monotonic() + self.limits.probe_seconds
        try:
            while True:
                clock.tick()
                now = time.monotonic()
                if now >= self.fmu_deadline or now >= step_deadline:
                    per_fmu = now >= self.fmu_deadline
                    watch.kill()
                    probe_time = now - (step_deadline - self.limits.probe_seconds)
                    probe, own = self.diagnosis.timed_out(current, per_fmu, clock.running(),
                                                          probe_time)
                    return _Death("fmu-timeout" if per_fmu else "timeout", probe, own)
                events, eof = watch.read(min(step_deadline, self.fmu_deadline) - now)
                for event in events:
                    kind = event.get("event")
                    if kind == "start":
                        current = str(event.get("code", ""))
                        step_deadline = time.monotonic() + self.limits.probe_seconds
                    elif kind == "partial":   # kept if the worker dies before "done"
                        self.run.outcome.violations.extend(
                            (str(event.get("code")), violation_from_json(v))
                            for v in event.get("violations") or [])
                    elif kind == "done":
                        self._stats(str(event.get("code", "")), event.get("stats"))
                        self._done(event)
                        current = ""
                        step_deadline = time.monotonic() + self.limits.probe_seconds
                    elif kind == "ready":
                        self._stats("setup", event.get("stats"))
                        watch.baseline = event.get("memory") or {}
                        for key, value in (event.get("info") or {}).items():
                            self.run.outcome.info.setdefault(key, value)
                        current = ""
                    elif kind == "load-failed":
                        self.run.emit(NOT_LOADABLE, replace(
                            violation_from_json(event.get("violation") or {}),
                            location=Location(file=self.run.binary)))
                        watch.finish()
                        return _Death("load-failed", "setup")
                    elif kind == "memory":
                        watch.memory_error = True
                    elif kind == "worker-error":
                        self.run.emit("internal-error", Violation(
                            f"the probe worker failed: {event.get('error')}",
                            evidence=evidence(traceback=str(event.get("traceback", "")))))
                        watch.finish()
                        return _Death("worker-error", "setup")
                    elif kind == "fatal":   # every instance is gone: that call is not made again
                        if event.get("call") and event["call"] not in self.blocked:
                            self.blocked.append(str(event["call"]))
                        watch.finish()
                        return _Death("fatal", str(event.get("code", "")))
                    elif kind == "end":
                        watch.finish()
                        return _Death("end")
                if eof and self.stopped:   # killed by stop(): nothing to diagnose
                    return _Death("end")
                if eof:  # the channel closed before "end": whatever the exit status, a death
                    watch.finish()
                    return _Death("died", *self.diagnosis.died(current, watch))
        finally:
            watch.kill()

    def _stats(self, step: str, stats: Any) -> None:
        """What one step of the worker cost (seconds, FMI calls, peak resident bytes): kept
        in the outcome and logged (``lsdae check -v``), never in the report."""
        if not isinstance(stats, dict):
            return
        entry = {"probe": step, **{k: stats.get(k) for k in ("seconds", "calls", "fmi_seconds",
                                                                 "peak_rss")}, "lane": self.lane}
        self.run.outcome.stats.append(entry)
        peak = entry["peak_rss"]
        log.debug("%s%s: %.3f s (%.3f s in the binary), %s FMI calls, peak resident %s",
                  f"[worker {self.lane + 1}] " if self.lane or self.others else "",
                  self.run.names(step), float(entry["seconds"] or 0.0),
                  float(entry["fmi_seconds"] or 0.0), entry["calls"],
                  f"{peak / (1 << 20):.0f} MiB" if isinstance(peak, int) else "unknown",
                  extra={"probe_stats": entry})

    def _done(self, event: dict[str, Any]) -> None:
        code = str(event.get("code"))
        if code == NARROW:   # lsdae's own step: no rule ran
            return
        outcome = self.run.outcome
        violations = [violation_from_json(v) for v in event.get("violations") or []]
        if event.get("replaces"):   # what "partial" sent is superseded by this event
            outcome.violations = [(c, v) for c, v in outcome.violations if c != code]
        outcome.violations.extend((code, v) for v in violations)
        consequences = [violation_from_json(v) for v in event.get("consequences") or []]
        outcome.consequences.extend((code, v) for v in consequences)
        violations += consequences   # the rule ran and found something (whoever reports it)
        skipped = event.get("skipped")
        if skipped and not violations:
            outcome.skipped.add((code, str(skipped)))
            outcome.not_run.add((code, str(skipped)))
        else:
            outcome.run.add(code)
        for key, value in (event.get("info") or {}).items():
            if key not in ("points", "seed"):
                outcome.info[key] = value

    def _not_run_own(self, death: _Death) -> None:
        """The probe a limit of lsdae's own stopped is not run, with the reason, and whether
        a new worker takes over the probes after it (the one stopped cannot go on)."""
        rule = next((r for r in self.run.rules if r.code == death.probe), None)
        if rule is None:
            return
        done = {c for c, _ in self.run.outcome.skipped} | self.run.outcome.run
        after = [r for r in self.remaining if r.code not in done and r.code != rule.code]
        goes_on = after and death.kind in ("timeout", "died")
        self.run.skip([rule], death.own + ("; the worker was stopped, and a new one runs the "
                                           "probes after it" if goes_on else ""), failed=True)

