"""What a worker's death or a limit means: the binary's ``binary-*`` finding, or lsdae's own limit.

The driver (:mod:`.driver`) asks :class:`Diagnosis` once a worker died or was stopped. The shared
:class:`~conformance.runtime.callrecord.CallRecord` says which probe ran and which FMI call was
in progress; the driver's :class:`CallClock` says how long that call had been running.

* A limit reached while **no FMI call** was in progress is lsdae's own: the binary was idle.
* A time limit reached while a call was in progress is the binary's only when **that call**
  had been running for at least half of the probe's time (half the per-probe limit when that
  ran out): a probe whose many short calls, with lsdae's work
  between them, add up to the limit ran out of lsdae's budget, not into a hang (a slow or
  loaded machine must not make one).
* A memory limit reached during a call is the binary's; a crash always is (the binary may have
  corrupted memory earlier), except before it was loaded at all (``internal-error``).
* A memory limit reached while no FMI call was in progress is the binary's all the same when
  FMI calls had grown the address space by at least ``FMU_SHARE`` of the limit (the
  CallRecord counts it once the library watches its calls): the FMU took the memory, and
  lsdae's next allocation only found it gone. The finding names the call that grew it last.

For lsdae's own limits the reason is returned (the driver lists the probe as not run with
it); the binary's findings are emitted here, naming the probe and the call.
"""
from __future__ import annotations

import logging
import os
import time
from typing import Any

from ...report import causes
from ...report.findings import Location, Violation, evidence
from ...runtime.callrecord import GETTER_CALLS, CallCounts, CallRecord
from ...runtime.supervisor import WorkerProcess
from .registry import ENDURANCE as COUNTED

CRASHED, TIMED_OUT, MEMORY, NOT_LOADABLE = (
    "binary-crashed", "binary-timed-out", "binary-memory-limit", "binary-not-loadable")
MEMORY_FRACTION = 0.8        # a death at this share of the address-space limit is "memory"
HANG_SHARE = 0.5             # a call running this share of its probe's time is a hang
FMU_SHARE = 0.5              # FMI calls that grew the address space by this share: the FMU's
STDERR_TAIL = 1500
#: The probe that makes calls the importer must not make (it tests robustness), and those calls:
#: a crash during one of them is no verdict of the text (FMI requires no detection of an
#: illegal call). illegal-call-accepted (DAE739, readback/rare_calls.py) makes them as
#: fmi3SetBoolean on a Float64 variable in Configuration Mode and the partial-derivative calls
#: with wrong arguments. The record names the function only: the legal fmi3SetBoolean on the
#: switch that starts a DAE-mode instance in that probe (one every earlier probe made alike) is
#: counted with them.
ILLEGAL_CALLS: dict[str, frozenset[str]] = {
    "DAE739": frozenset({"fmi3SetBoolean", "fmi3GetDirectionalDerivative",
                         "fmi3GetAdjointDerivative"})}

#: The cause every crash of the binary names (``Violation.cause``): one finding for them all.
CRASH_CAUSE = "the binary crashed"
#: All deaths at the memory limit that the binary's calls caused are one defect (its memory
#: grows in every probe that calls the function): one finding, the probes listed in its evidence.
MEMORY_CAUSE = causes.FAULT.format("exhausts the address-space limit")

log = logging.getLogger(__name__)


def read_counts(call_file: str) -> CallCounts:
    try:
        with open(call_file, "rb") as fh:
            return CallRecord.counts(fh.read(CallRecord.SIZE))
    except OSError:
        return CallCounts(0, 0)


def not_loadable(exc: Exception, directory: str) -> Violation:
    """``binary-not-loadable`` for the library the worker could not load from the FMU unpacked
    at ``directory`` (:mod:`.stage` sends it). fmpy loads the library, then resolves every fmi3*
    function of fmi3Functions.h in it: a missing one raises AttributeError (ctypes: "undefined
    symbol", "function ... not found"), a library that does not load at all another exception."""
    error = str(exc).replace(directory + os.sep, "")  # the path in the FMU
    return Violation(f"the binary cannot be loaded: {error}", Location(),
                     evidence(error=error, exception=type(exc).__name__),
                     part="missing-function" if isinstance(exc, AttributeError) else None)


class CallClock:
    """When the FMI call now in progress started, as the parent saw the call counter move
    (:meth:`tick` in the driver's loop, about every 50 ms)."""

    def __init__(self, call_file: str):
        self.call_file = call_file
        self.started, self.since = -1, time.monotonic()

    def tick(self) -> None:
        started = read_counts(self.call_file).started
        if started != self.started:
            self.started, self.since = started, time.monotonic()

    def running(self) -> float:
        """Seconds since the last call started (the call in progress, if any)."""
        return time.monotonic() - self.since


class Diagnosis:
    """Deaths and limits of one FMU's workers; ``driver`` gives the run, the limits, the
    temporary directory, and the lists of blocked calls and probes that died."""

    def __init__(self, driver: Any):
        self.driver = driver
        self.run, self.limits = driver.run, driver.limits

    # -- what the worker left behind ---------------------------------------------------------

    def _record(self) -> tuple[str, str, bool]:
        try:
            with open(self.driver.call_file, "rb") as fh:
                return CallRecord.parse(fh.read(CallRecord.SIZE))
        except OSError:
            return "", "", False

    def _refs(self) -> tuple[int, tuple[int, ...]]:
        """(how many value references the last call passed, the first of them)."""
        try:
            with open(self.driver.call_file, "rb") as fh:
                return CallRecord.refs(fh.read(CallRecord.SIZE))
        except OSError:
            return 0, ()

    def _variables(self) -> tuple[str, dict[str, Any], tuple[str, ...]]:
        """The variables the call in progress read or set, as the message names them (' of
        'time' (valueReference 4294967295)'), as evidence, and as causes (one variable: the
        crash is that variable's, and the same crash in a call that read it with others is
        the same defect)."""
        n, refs = self._refs()
        if not n:
            return "", {}, ()
        model = getattr(self.run.ctx, "model", None)
        by_vr = model.by_vr if model is not None else {}
        names = [by_vr[vr].name if vr in by_vr and by_vr[vr].name else f"valueReference {vr}"
                 for vr in refs]
        if n == 1:
            text = (f" of '{names[0]}' (valueReference {refs[0]})" if refs[0] in by_vr
                    else f" of {names[0]}")
        else:
            shown = ", ".join(f"'{name}'" for name in names) + (", …" if n > len(names) else "")
            text = f" of {n} variables ({shown})"
        return (text, {"value_references": list(refs), "variables": names,
                       "value_reference_count": n},
                (causes.through(names[0]),) if n == 1 else ())

    def _to_narrow(self, call: str, how: str) -> None:
        """Note a crash during a getter of several variables, all of them kept in the record,
        for the driver to narrow to one (:mod:`.narrowing`); a getter's crash that names one
        variable needs no narrowing."""
        n, refs = self._refs()
        if call not in GETTER_CALLS:
            return
        if n == 1:
            self.driver.narrowed.add(call)
        elif n == len(refs):
            self.driver.to_narrow.setdefault((call, how), refs)

    def _growth(self) -> tuple[int, str]:
        """(bytes by which FMI calls grew the worker's address space, the call last)."""
        try:
            with open(self.driver.call_file, "rb") as fh:
                return CallRecord.growth(fh.read(CallRecord.SIZE))
        except OSError:
            return 0, ""

    def stderr(self) -> str:
        path, tmp = self.driver.stderr_file, self.driver.tmp
        try:
            with open(path, "rb") as fh:
                fh.seek(max(0, os.path.getsize(path) - STDERR_TAIL))
                text = fh.read().decode("utf-8", "replace").strip()
        except OSError:
            return ""
        # paths of the temporary directory would make two reports of one FMU differ
        return text.replace(os.path.join(tmp, "fmu") + os.sep, "").replace(tmp, "<tmp>")

    def _stderr_evidence(self) -> dict[str, str]:
        text = self.stderr()
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
        facts: dict[str, Any] = {"probe": probe, "call": call or None,
                                 "call_in_progress": in_progress}
        if call and probe in COUNTED:
            counts = read_counts(self.driver.call_file)
            total, in_probe = counts.completed(in_progress), counts.completed_in_probe(in_progress)
            where += f", after {in_probe:,} FMI calls in this probe ({total:,} in this worker)"
            facts.update(call_count=total, calls_in_probe=in_probe)
        if probe:
            self.driver.died.append(probe)
        return probe, call, where, facts

    def is_rule(self, probe: str) -> bool:
        return probe in self.run.by_name or any(r.code == probe for r in self.run.rules)

    def _own(self, probe: str, reason: str) -> str:
        log.debug("lsdae's own limit in %s: %s", self.run.names(probe), reason)
        return reason

    # -- a limit of time -----------------------------------------------------------------------

    def timed_out(self, current: str, per_fmu: bool, call_seconds: float,
                  probe_seconds: float) -> tuple[str, str]:
        """The probe that was stopped, and the reason when the limit was lsdae's own;
        ``call_seconds``: how long the last FMI call had been running, ``probe_seconds`` the
        probe (or setup)."""
        probe, call, where, facts = self._context(current)
        limit = self.limits.fmu_seconds if per_fmu else self.limits.probe_seconds
        scope = "per FMU" if per_fmu else "per probe"
        option = "fmu_seconds" if per_fmu else "probe_seconds"
        hang = HANG_SHARE * min(probe_seconds, self.limits.probe_seconds)
        if not (call and facts["call_in_progress"]):  # the binary was not running: ours
            return probe, self._own(
                probe, f"time limit: lsdae's own computation in {self.run.names(probe)} took "
                f"longer than the {limit:g} s limit {scope} ({option} of {TIMED_OUT}) while no "
                f"FMI call was in progress ({where}); not the binary's fault")
        if call_seconds < hang:  # many short calls and our work between them: our budget
            return probe, self._own(
                probe, f"time limit: {self.run.names(probe)} took longer than the {limit:g} s "
                f"limit {scope} ({option} of {TIMED_OUT}) in many FMI calls and lsdae's own "
                "work between them; no single call ran for half of that time, so no call hung "
                "(lsdae's budget, not the binary's fault)")
        if self.is_rule(probe):
            self.run.outcome.run.add(probe)
        self.driver.blocked.append(call)
        self.run.emit(TIMED_OUT, Violation(
            f"the binary did not respond within the {limit:g} s limit {scope}: stopped "
            f"{where}, in {self.run.names(probe)}", Location(file=self.run.binary),
            evidence(facts, limit_seconds=limit, limit=scope, **self._stderr_evidence()),
            subject=call or probe))
        return probe, ""

    # -- a death -------------------------------------------------------------------------------

    def died(self, current: str, watch: WorkerProcess) -> tuple[str, str]:
        """The probe during which the worker died, and the reason when the limit it reached
        was lsdae's own."""
        probe, call, where, facts = self._context(current)
        how = watch.how()
        limit_mib = int(self.limits.address_space_mib)
        memory = watch.memory_error or watch.peak() >= MEMORY_FRACTION * (limit_mib << 20)
        grown, grew = self._growth()
        if memory and grown >= FMU_SHARE * (limit_mib << 20) and not facts["call_in_progress"]:
            if self.is_rule(probe):
                self.run.outcome.run.add(probe)
            self.run.emit(MEMORY, Violation(
                f"the binary's FMI calls grew the worker's address space by "
                f"{grown / (1 << 20):,.0f} MiB (the last of them {grew}) until the "
                f"{limit_mib} MiB address-space limit was exhausted {where}, in "
                f"{self.run.names(probe)} ({how})", Location(file=self.run.binary),
                evidence(facts, exit=how, grown_in_fmi_calls_mib=round(grown / (1 << 20)),
                         last_growing_call=grew, limit_mib=limit_mib,
                         place=self.run.names(probe), **self._stderr_evidence()),
                subject=grew, part="grown-across-calls", cause=MEMORY_CAUSE))
            return probe, ""
        if memory and not (call and facts["call_in_progress"]):  # ours: the binary was idle
            return probe, self._own(
                probe, f"memory limit: lsdae's own computation in {self.run.names(probe)} "
                f"exhausted the worker's {limit_mib} MiB address-space limit "
                f"(address_space_mib of {MEMORY}) while no FMI call was in progress ({where}, "
                f"{how}); not the binary's fault")
        if probe == "setup" and not call:  # died before touching the binary: our defect
            self.run.emit("internal-error", Violation(
                f"the probe worker failed before loading the binary ({how}): "
                f"{(self.stderr().splitlines() or ['no message'])[-1]}",
                evidence=evidence(exit=how, **self._stderr_evidence())))
            return probe, ""
        if self.is_rule(probe):
            self.run.outcome.run.add(probe)
        ev = evidence(facts, exit=how, **self._stderr_evidence())
        if memory:
            # the FMI calls took the memory and another call's allocation found it gone: the
            # finding names the call that took it (the last that grew the address space)
            took = grew if grew and grown >= FMU_SHARE * (limit_mib << 20) else ""
            self.run.emit(MEMORY, Violation(
                f"the binary exhausted the {limit_mib} MiB address-space limit {where}, in "
                f"{self.run.names(probe)} ({how})" + (
                    f"; its FMI calls grew the address space by {grown / (1 << 20):,.0f} MiB, "
                    f"the last of them {took}" if took and took != call else ""),
                Location(file=self.run.binary),
                ev + evidence(limit_mib=limit_mib, **({"grown_in_fmi_calls_mib": round(
                    grown / (1 << 20)), "last_growing_call": took} if took else {}),
                    place=self.run.names(probe)),
                subject=took or call or probe, cause=MEMORY_CAUSE))
        else:
            illegal = facts["call_in_progress"] and call in ILLEGAL_CALLS.get(probe, ())
            # crashes reached by several probes or calls are one defect (a binary that
            # corrupted its memory crashes wherever it next touches it, during a call or after
            # one, by a signal or an abort): one finding, the probes listed in its evidence; a
            # call of one variable names it, and joins the crashes of calls that read it
            of, refs, keys = "", {}, ()
            if call and facts["call_in_progress"]:
                of, refs, keys = self._variables()
                self._to_narrow(call, how)
            same = (CRASH_CAUSE, *keys)
            self.run.emit(CRASHED, Violation(
                f"the binary crashed ({how}) {where.replace(f'during {call}', f'during {call}{of}', 1)}"
                f", in {self.run.names(probe)}", Location(file=self.run.binary),
                ev + evidence(refs, place=self.run.names(probe)), subject=call or probe,
                part="crash-on-illegal-call" if illegal else None, cause=same or None))
        return probe, ""
