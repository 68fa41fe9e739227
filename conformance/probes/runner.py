"""Parent side of the probe stage: extract, start the worker, enforce the limits, collect.

:func:`run_probes` decides whether anything can be probed (a modelDescription, a manifest, a
Model Exchange binary for this platform), extracts ``binaries/<tuple>/`` and ``resources/`` into
a private temporary directory, and starts ``python -m conformance.probes.worker`` there: the
only process that ever loads the FMU's library. The worker reports each probe as a JSON line.

The runner never trusts the worker to finish:

* **time**: each probe, and the worker's setup, gets ``probe_seconds``; the whole FMU gets
  ``fmu_seconds`` (options of ``binary-timed-out``). A worker past either is killed (its whole
  process group) and the probe in progress becomes a ``binary-timed-out`` finding;
* **memory**: the worker limits its own address space to ``address_space_mib`` (option of
  ``binary-memory-limit``) with ``setrlimit(RLIMIT_AS)`` before importing anything. A worker that
  dies with its address space at 80 % of the limit or more (its peak, sampled from
  ``/proc/<pid>/status`` while it runs and, after death, its peak resident size from
  ``wait4`` plus the non-resident part it reported at start) or after a ``MemoryError``, is
  a ``binary-memory-limit`` finding;
* **crashes**: any other death before the worker said it was done (a signal, ``exit()``,
  ``abort()``) is a ``binary-crashed`` finding.

Each of these findings names the probe and the FMI call in progress, read from the shared
:class:`~conformance.probes.worker.CallRecord` file the worker writes before every FMI call.
Violations of probes that completed are kept, and a fresh worker runs the remaining probes (at
most ``max_restarts`` times, option of ``binary-crashed``). A death during setup ends probing of
that FMU: a new worker would only die again.
"""
from __future__ import annotations

import logging
import os
import pickle
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Sequence

from ..catalogue import RuleSpec, default_catalogue
from ..findings import Location, Violation, evidence
from ..manifest import MANIFEST
from .registry import PROBES
from .worker import CallRecord, Job, WorkerProcess, violation_from_json

log = logging.getLogger(__name__)

CRASHED, TIMED_OUT, MEMORY, NOT_LOADABLE = (
    "binary-crashed", "binary-timed-out", "binary-memory-limit", "binary-not-loadable")
RUNNER_RULES = (CRASHED, TIMED_OUT, MEMORY, NOT_LOADABLE)
MEMORY_FRACTION = 0.8        # a death at this share of the address-space limit is "memory"
STDERR_TAIL = 1500
PACKAGE_ROOT = str(Path(__file__).resolve().parents[2])


@dataclass(frozen=True)
class Limits:
    """The catalogue options of the runner rules."""

    probe_seconds: float = 20.0
    fmu_seconds: float = 60.0
    address_space_mib: int = 2048
    max_restarts: int = 3

    @classmethod
    def from_rules(cls, rules: dict[str, RuleSpec | None]) -> Limits:
        values: dict[str, Any] = {}
        for rule in rules.values():
            for key, value in (rule.option_values.items() if rule else ()):
                if key in cls.__dataclass_fields__:
                    values[key] = value
        return cls(**values)


@dataclass
class ProbeOutcome:
    """What the engine merges into the FMU's report."""

    violations: list[tuple[str, Violation]] = field(default_factory=list)
    run: set[str] = field(default_factory=set)
    skipped: set[tuple[str, str]] = field(default_factory=set)
    info: dict[str, Any] = field(default_factory=dict)


def host_platform_tuple() -> str:
    """The FMI 3 platform tuple of this machine, e.g. ``x86_64-linux``."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64", "i386": "x86", "i686": "x86",
            "armv7l": "aarch32"}.get(machine, machine)
    system = ("linux" if sys.platform.startswith("linux") else "darwin"
              if sys.platform == "darwin" else "windows" if sys.platform in ("win32", "cygwin")
              else sys.platform)
    return f"{arch}-{system}"


def library_extension() -> str:
    return {"darwin": ".dylib", "win32": ".dll", "cygwin": ".dll"}.get(sys.platform, ".so")


def run_probes(source: Any, ctx: Any, rules: Sequence[RuleSpec], *, seed: int = 0
               ) -> ProbeOutcome:
    """Run the enabled probe-stage ``rules`` on one FMU; never raises for a bad FMU."""
    return _Run(source, ctx, rules, seed).run()


class _Run:
    def __init__(self, source: Any, ctx: Any, rules: Sequence[RuleSpec], seed: int):
        self.source, self.ctx, self.seed = source, ctx, seed
        self.outcome = ProbeOutcome()
        self.rules = list(rules)
        self.by_name = {r.name: r for r in rules}
        catalogue = default_catalogue()
        self.runner_rules = {n: self.by_name.get(n) or catalogue.get(n) for n in RUNNER_RULES}
        self.limits = Limits.from_rules(self.runner_rules)
        self.tuple = host_platform_tuple()
        self.binary = ""

    # -- bookkeeping ---------------------------------------------------------------------

    def emit(self, rule_name: str, violation: Violation) -> None:
        """A violation of ``rule_name``: a runner rule, or a rule the engine resolves by name
        (``internal-error``); the engine drops it when the rule is not selected."""
        rule = self.runner_rules.get(rule_name)
        code = rule.code if rule else next(r.code for r in self.runner_rules.values() if r)
        self.outcome.violations.append((code, replace(violation, rule=rule_name)))

    def skip(self, rules: Iterable[RuleSpec], reason: str) -> None:
        self.outcome.skipped.update((r.code, reason) for r in rules)

    def names(self, code: str) -> str:
        if code == "setup":
            return "setup (loading the binary, entering Continuous-Time Mode)"
        if code == "teardown":
            return "teardown (fmi3Terminate, fmi3FreeInstance)"
        rule = next((r for r in self.rules if r.code == code), None)
        return f"probe {code} {rule.name}" if rule else f"probe {code or '?'}"

    # -- preconditions -------------------------------------------------------------------

    def _not_probeable(self) -> str | None:
        ctx = self.ctx
        if ctx.model is None:
            return "no modelDescription.xml could be read"
        if ctx.manifest is None:
            if MANIFEST in ctx.names:
                return "the manifest cannot be parsed: nothing to probe"
            return "no fmi-ls-dae manifest: an ordinary Model Exchange FMU"
        me = ctx.model.model_exchange
        if me is None or not me.model_identifier:
            return "the FMU has no <ModelExchange modelIdentifier=...> interface"
        self.binary = f"binaries/{self.tuple}/{me.model_identifier}{library_extension()}"
        if self.binary not in ctx.names:
            return f"no binary for {self.tuple}"
        return None

    def run(self) -> ProbeOutcome:
        reason = self._not_probeable()
        if reason:
            self.skip(self.rules, reason)
            self.outcome.info["probes"] = f"not run: {reason}"
            return self.outcome
        probes: list[RuleSpec] = []
        for rule in self.rules:
            if rule.name in RUNNER_RULES:
                continue
            if rule.code not in PROBES:
                self.skip([rule], "not implemented")
            elif not rule.applies_to(self.ctx.draft):
                self.skip([rule], f"does not apply to draft {self.ctx.draft}")
            else:
                probes.append(rule)
        tmp = tempfile.mkdtemp(prefix="lsdae-probe-")
        try:
            if self._extract(tmp):
                self.outcome.run.update(r.code for r in self.rules if r.name in RUNNER_RULES)
                _Driver(self, tmp, probes).drive()
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return self.outcome

    def _extract(self, tmp: str) -> bool:
        target = os.path.join(tmp, "fmu")
        os.mkdir(target, 0o700)
        prefixes = (f"binaries/{self.tuple}/", "resources/")
        wanted = [n for n in self.ctx.names if n.startswith(prefixes)]
        for v in self.source.extract_to(Path(target), names=wanted):
            self.emit(v.rule or "archive-unreadable", v)  # the engine resolves the rule
        if not os.path.isfile(os.path.join(target, *self.binary.split("/"))):
            reason = f"the binary {self.binary} could not be extracted"
            self.skip(self.rules, reason)
            self.outcome.info["probes"] = f"not run: {reason}"
            return False
        return True


@dataclass
class _Death:
    kind: str  # "end", "died", "timeout", "fmu-timeout", "load-failed", "fatal", "worker-error"
    probe: str = ""


class _Driver:
    """Starts workers until every probe has run or cannot run; turns deaths into findings."""

    def __init__(self, run: _Run, tmp: str, probes: list[RuleSpec]):
        self.run, self.tmp, self.remaining = run, tmp, probes
        self.limits = run.limits
        self.call_file = os.path.join(tmp, "call")
        self.stderr_file = os.path.join(tmp, "worker.log")
        self.fmu_deadline = time.monotonic() + self.limits.fmu_seconds
        self.blocked: list[str] = []   # FMI functions that hung: not called again

    def drive(self) -> None:
        restarts = 0
        while True:
            result = self._one_worker()
            done = {c for c, _ in self.run.outcome.skipped} | self.run.outcome.run
            self.remaining = [r for r in self.remaining if r.code not in done]
            if result.kind == "end":
                self.run.skip(self.remaining, "not run: the worker ended early")
                return
            if result.kind == "load-failed":
                self.run.skip(self.remaining, "the binary cannot be loaded (binary-not-loadable)")
                return
            if result.kind == "fatal" and not self.remaining:
                return
            if result.kind == "fmu-timeout":
                self.run.skip(self.remaining, f"the per-FMU time limit of "
                              f"{self.limits.fmu_seconds:g} s was reached")
                return
            if result.probe in ("setup", ""):
                self.run.skip(self.remaining, "the worker failed before the probes could run "
                              "(see the findings)")
                return
            if not self.remaining:
                return
            restarts += 1
            if restarts > self.limits.max_restarts:
                self.run.skip(self.remaining, f"not run: the worker was restarted "
                              f"{self.limits.max_restarts} times")
                return

    # -- one worker process --------------------------------------------------------------

    def _start(self) -> subprocess.Popen[bytes]:
        ctx = self.run.ctx
        job = Job(directory=os.path.join(self.tmp, "fmu"), call_file=self.call_file,
                  model=ctx.model, manifest=ctx.manifest, draft=ctx.draft, seed=self.run.seed,
                  probes=[(r.code, r.name, r.option_values) for r in self.remaining],
                  blocked=list(self.blocked))
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
                [sys.executable, "-m", "conformance.probes.worker", job_file, str(limit)],
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=err, cwd=self.tmp,
                env=env, start_new_session=True)

    def _one_worker(self) -> _Death:
        proc = self._start()
        watch = WorkerProcess(proc)
        current = "setup"
        step_deadline = time.monotonic() + self.limits.probe_seconds
        try:
            while True:
                now = time.monotonic()
                if now >= self.fmu_deadline or now >= step_deadline:
                    per_fmu = now >= self.fmu_deadline
                    watch.kill()
                    probe = self._timed_out(current, per_fmu)
                    return _Death("fmu-timeout" if per_fmu else "timeout", probe)
                events, eof = watch.read(min(step_deadline, self.fmu_deadline) - now)
                for event in events:
                    kind = event.get("event")
                    if kind == "start":
                        current = str(event.get("code", ""))
                        step_deadline = time.monotonic() + self.limits.probe_seconds
                    elif kind == "done":
                        self._done(event)
                        current = ""
                        step_deadline = time.monotonic() + self.limits.probe_seconds
                    elif kind == "ready":
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
                    elif kind == "fatal":
                        watch.finish()
                        return _Death("fatal", str(event.get("code", "")))
                    elif kind == "end":
                        watch.finish()
                        return _Death("end")
                if eof:  # the channel closed before "end": whatever the exit status, a death
                    watch.finish()
                    return _Death("died", self._died(current, watch))
        finally:
            watch.kill()

    def _done(self, event: dict[str, Any]) -> None:
        code = str(event.get("code"))
        outcome = self.run.outcome
        violations = [violation_from_json(v) for v in event.get("violations") or []]
        outcome.violations.extend((code, v) for v in violations)
        skipped = event.get("skipped")
        if skipped and not violations:
            outcome.skipped.add((code, str(skipped)))
        else:
            outcome.run.add(code)
        for key, value in (event.get("info") or {}).items():
            if key not in ("points", "seed"):
                outcome.info[key] = value

    # -- findings --------------------------------------------------------------------------

    def _record(self) -> tuple[str, str, bool]:
        try:
            with open(self.call_file, "rb") as fh:
                return CallRecord.parse(fh.read(CallRecord.SIZE))
        except OSError:
            return "", "", False

    def _stderr(self) -> str:
        try:
            with open(self.stderr_file, "rb") as fh:
                fh.seek(max(0, os.path.getsize(self.stderr_file) - STDERR_TAIL))
                text = fh.read().decode("utf-8", "replace").strip()
        except OSError:
            return ""
        # paths of the temporary directory would make two reports of one FMU differ
        return text.replace(os.path.join(self.tmp, "fmu") + os.sep, "").replace(self.tmp, "<tmp>")

    def _stderr_evidence(self) -> dict[str, str]:
        text = self._stderr()
        return {"stderr": text} if text else {}

    def _context(self, current: str) -> tuple[str, str, str, dict[str, Any]]:
        probe, call, in_progress = self._record()
        probe = probe or current
        if not call:
            where = "before any FMI call"
        elif in_progress:
            where = f"during {call}"
        else:
            where = f"after {call} had returned"
        facts = {"probe": probe, "call": call or None, "call_in_progress": in_progress}
        if probe in self.run.by_name or any(r.code == probe for r in self.run.rules):
            self.run.outcome.run.add(probe)
        return probe, call, where, facts

    def _timed_out(self, current: str, per_fmu: bool) -> str:
        probe, call, where, facts = self._context(current)
        if call and facts["call_in_progress"]:
            self.blocked.append(call)
        limit = self.limits.fmu_seconds if per_fmu else self.limits.probe_seconds
        scope = "per FMU" if per_fmu else "per probe"
        self.run.emit(TIMED_OUT, Violation(
            f"the binary did not respond within the {limit:g} s limit {scope}: stopped "
            f"{where}, in {self.run.names(probe)}", Location(file=self.run.binary),
            evidence(facts, limit_seconds=limit, limit=scope, **self._stderr_evidence()),
            subject=call or probe))
        return probe

    def _died(self, current: str, watch: WorkerProcess) -> str:
        probe, call, where, facts = self._context(current)
        how = watch.how()
        if probe == "setup" and not call:  # died before touching the binary: our defect
            self.run.emit("internal-error", Violation(
                f"the probe worker failed before loading the binary ({how}): "
                f"{(self._stderr().splitlines() or ['no message'])[-1]}",
                evidence=evidence(exit=how, **self._stderr_evidence())))
            return probe
        ev = evidence(facts, exit=how, **self._stderr_evidence())
        limit_mib = int(self.limits.address_space_mib)
        if watch.memory_error or watch.peak() >= MEMORY_FRACTION * (limit_mib << 20):
            self.run.emit(MEMORY, Violation(
                f"the binary exhausted the {limit_mib} MiB address-space limit {where}, in "
                f"{self.run.names(probe)} ({how})", Location(file=self.run.binary),
                ev + evidence(limit_mib=limit_mib), subject=call or probe))
        else:
            self.run.emit(CRASHED, Violation(
                f"the binary crashed ({how}) {where}, in {self.run.names(probe)}",
                Location(file=self.run.binary), ev, subject=call or probe))
        return probe
