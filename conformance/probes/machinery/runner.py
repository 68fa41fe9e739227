"""Parent side of the probe stage: extract, start the worker, enforce the limits, collect.

:func:`run_probes` decides whether anything can be probed (a modelDescription, a manifest, a
Model Exchange binary for this platform), extracts ``binaries/<tuple>/`` and ``resources/`` into
a private temporary directory, and starts ``python -m conformance.runtime.child`` there: the
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
:class:`~conformance.runtime.callrecord.CallRecord` file the worker writes before every FMI call
(during an endurance probe also after how many FMI calls).
Violations of probes that completed are kept, and a fresh worker runs the remaining probes (at
most ``max_restarts`` times, option of ``binary-crashed``). A death during setup ends probing of
that FMU: a new worker would only die again.

The endurance probes (``conformance.probes.endurance.sustained``) run after the other probes,
at the level the engine passes (``endurance``: "quick" or "long", handed to the worker in the
job); at "off" the runner skips them with that reason and they cost nothing.

Once every worker has ended, :func:`fold_consequences` makes one defect one finding: what
vanishes with every instance alone is instances-not-independent's. Violations that name the
same cause (``Violation.cause``) are folded by the engine's collector
(``conformance.run.causes``), for probes and static checks alike.
"""
from __future__ import annotations

import copy
import logging
import os
import shutil
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Sequence

from ...report.catalogue import RuleSpec, default_catalogue
from ...report.findings import Violation, evidence
from ...model.layer import describe_fmu
from ...runtime.host import host_platform_tuple, library_extension
from .driver import RUNNER_RULES, Driver
from .job import NARROW
from .lanes import Lanes, split, workers_for
from .registry import ENDURANCE, FAMILY_OF, FIRST, FIRST_CAUSE, LAST

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Limits:
    """The catalogue options of the runner rules (their defaults live in the catalogue only)."""

    probe_seconds: float
    fmu_seconds: float
    address_space_mib: int
    max_restarts: int

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
    not_run: set[tuple[str, str]] = field(default_factory=set)   # the failed part of skipped
    info: dict[str, Any] = field(default_factory=dict)
    # violations that vanish with every instance alone (stage._first_cause): folded into
    # instances-not-independent's finding by fold_consequences
    consequences: list[tuple[str, Violation]] = field(default_factory=list)
    # what each step of the workers cost: {"probe", "seconds", "calls", "fmi_seconds",
    # "peak_rss", "lane"}; logged, never part of the report (it differs from run to run)
    stats: list[dict[str, Any]] = field(default_factory=list)


def run_probes(source: Any, ctx: Any, rules: Sequence[RuleSpec], *, seed: int = 0,
               endurance: str = "quick", workers: int = 0) -> ProbeOutcome:
    """Run the enabled probe-stage ``rules`` on one FMU; never raises for a bad FMU.
    ``endurance`` is the level of the endurance probes: "off", "quick" or "long"; ``workers``
    the workers at once, 1 or 2 (0: by the model's size, :func:`.lanes.workers_for`)."""
    return _Run(source, ctx, rules, seed, endurance, workers).run()


class _Run:
    def __init__(self, source: Any, ctx: Any, rules: Sequence[RuleSpec], seed: int,
                 endurance: str = "quick", workers: int = 0):
        self.source, self.ctx, self.seed, self.endurance = source, ctx, seed, endurance
        self.workers = workers
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

    def skip(self, rules: Iterable[RuleSpec], reason: str, *, failed: bool = False) -> None:
        """Rules that do not run, and why; ``failed``: they should have run on this FMU but
        could not (an earlier failure, a missing capability, a budget), which every report
        lists, rather than not applying to it."""
        pairs = [(r.code, reason) for r in rules]
        self.outcome.skipped.update(pairs)
        if failed:
            self.outcome.not_run.update(pairs)

    def names(self, code: str) -> str:
        if code == "setup":
            return "setup (loading the binary, entering Continuous-Time Mode)"
        if code == "teardown":
            return "teardown (fmi3Terminate, fmi3FreeInstance)"
        if code.startswith(NARROW):
            mode = code.split()[-1].upper() if " " in code else ""
            return ("lsdae's narrowing of the crash (each variable of the call read alone, "
                    f"Continuous-Time Mode{', ' + mode + ' mode' if mode else ''})")
        rule = next((r for r in self.rules if r.code == code), None)
        return f"probe {code} {rule.name}" if rule else f"probe {code or '?'}"

    # -- preconditions -------------------------------------------------------------------

    def _not_probeable(self) -> str | None:
        """Why the binary cannot be probed at all, or None. An FMU without a readable manifest
        (an ordinary Model Exchange FMU, or a DAE FMU whose manifest cannot be read) is probed
        in ODE mode, by the rules that do not need the manifest (the engine leaves the others
        out); a Co-Simulation or Scheduled Execution FMU is not probed: the probes drive the
        Model Exchange interface."""
        ctx = self.ctx
        if ctx.model is None:
            return "no modelDescription.xml could be read"
        me = ctx.model.model_exchange
        if me is None:
            return (f"{describe_fmu(ctx.model)}, not Model Exchange: the probes drive the Model "
                    "Exchange interface only")
        if not me.model_identifier:
            return "the <ModelExchange> element has no modelIdentifier: no binary to load"
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
            if rule.code not in FAMILY_OF:
                self.skip([rule], "not implemented")
            elif rule.code in ENDURANCE and self.endurance == "off":
                self.skip([rule], "the endurance stage is off (--endurance off)")
            elif not rule.applies_to(self.ctx.draft):
                self.skip([rule], f"does not apply to draft {self.ctx.draft}")
            else:
                probes.append(rule)
        # the start values first, before any instance was freed; the endurance probes last:
        # what sustained use does to the FMU (a late crash, state in C globals) must not change
        # the other probes' verdicts
        probes.sort(key=lambda rule: (rule.code in ENDURANCE, rule.code in LAST,
                                      rule.code not in FIRST))
        tmp = tempfile.mkdtemp(prefix="lsdae-probe-")
        try:
            if self._extract(tmp):
                self.outcome.run.update(r.code for r in self.rules if r.name in RUNNER_RULES)
                self._drive(tmp, probes)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        fold_consequences(self.outcome)
        return self.outcome

    def _drive(self, tmp: str, probes: list[RuleSpec]) -> None:
        """One worker after another for the probes; for a large FMU two lanes of them at once
        (:mod:`.lanes`), each with an outcome of its own, merged in lane order."""
        lanes = split(probes, workers_for(self.ctx.model, self.workers))
        if len(lanes) == 1:
            Driver(self, tmp, probes).drive()
            return
        blocked: list[str] = []    # an FMI function one lane must not call, neither may the other
        narrowed: set[str] = set()  # a getter whose crash one lane named a variable of
        runs, drivers = [], []
        for number, lane in enumerate(lanes):
            run = copy.copy(self)
            run.outcome = ProbeOutcome()
            folder = tmp if number == 0 else os.path.join(tmp, f"lane-{number}")
            if number:
                os.mkdir(folder, 0o700)
                shutil.copytree(os.path.join(tmp, "fmu"), os.path.join(folder, "fmu"))
            others = [p for other in lanes if other is not lane for p in other]
            runs.append(run)
            drivers.append(Driver(run, folder, lane, others=others, blocked=blocked,
                                  lane=number, narrowed=narrowed))
        log.debug("%d probe workers at once: %s", len(lanes),
                  " | ".join(" ".join(r.code for r in lane) for lane in lanes))
        Lanes(drivers).drive()
        for run in runs:
            merge(self.outcome, run.outcome)

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




def merge(into: ProbeOutcome, lane: ProbeOutcome) -> None:
    """``lane``'s outcome added to ``into``'s (info: what ``into`` has not yet)."""
    into.violations.extend(lane.violations)
    into.consequences.extend(lane.consequences)
    into.run.update(lane.run)
    into.skipped.update(lane.skipped)
    into.not_run.update(lane.not_run)
    into.stats.extend(lane.stats)
    for key, value in lane.info.items():
        into.info.setdefault(key, value)


def fold_consequences(outcome: ProbeOutcome) -> None:
    """The first cause: the findings that vanished with every instance alone are folded into
    the finding of instances-not-independent (its evidence lists them, its message counts
    them); when that rule reported nothing (not run, not selected, a death), nothing explains
    them and they are reported as the findings of their own rules."""
    if not outcome.consequences:
        return
    at = next((k for k, (code, _) in enumerate(outcome.violations) if code == FIRST_CAUSE),
              None)
    if at is None:
        outcome.violations.extend(outcome.consequences)
        outcome.consequences.clear()
        return
    code, cause = outcome.violations[at]
    listed: dict[str, list[str]] = {}
    for rule, v in outcome.consequences:
        listed.setdefault(rule, []).append(v.subject or "")
    count = len(outcome.consequences)
    outcome.violations[at] = (code, replace(
        cause, message=cause.message + (
            f"; {count} finding{'s' if count > 1 else ''} of "
            f"{', '.join(sorted(listed))} vanish with every instance alone (a copy of the "
            "binary of its own): consequences of this one, listed in its evidence"),
        evidence=cause.evidence + evidence(consequences=[
            {"rule": rule, "subject": v.subject, "message": v.text}
            for rule, v in outcome.consequences])))

