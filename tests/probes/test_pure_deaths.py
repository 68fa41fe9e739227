"""What a worker's death or a limit means (conformance/probes/machinery/deaths.py), decided in
this process from what the worker left behind: a call file written with the real CallRecord,
a stderr file, and a fake of the supervisor's WorkerProcess. No worker is started.

The runner's bookkeeping is the real one (``runner._Run``): the findings it emits, the rules it
counts as run and the names it gives the probes are what lsdae reports.
"""
from __future__ import annotations

import ctypes
import os
from dataclasses import dataclass, field
from types import SimpleNamespace

import pytest

from conformance.probes.machinery import deaths as D
from conformance.probes.machinery.runner import Limits, _Run
from conformance.report import causes
from conformance.report.catalogue import default_catalogue
from conformance.report.findings import Location, thaw
from conformance.runtime.callrecord import CallRecord

MIB = 1 << 20
CATALOGUE = default_catalogue()
LIMITS = Limits(probe_seconds=20.0, fmu_seconds=300.0, address_space_mib=1000, max_restarts=3)
PROBE, ENDURANCE = "DAE740", "DAE760"   # a point probe, an endurance probe (counted)
BINARY = "binaries/x86_64-linux/m.so"


@dataclass
class _Watch:
    how_text: str = "killed by SIGSEGV"
    memory_error: bool = False
    peak_bytes: int = 0

    def how(self) -> str:
        return self.how_text

    def peak(self) -> int:
        return self.peak_bytes


@dataclass
class _Driver:
    run: object
    limits: Limits
    call_file: str
    stderr_file: str
    tmp: str
    narrowed: set = field(default_factory=set)
    to_narrow: dict = field(default_factory=dict)
    died: list = field(default_factory=list)
    blocked: list = field(default_factory=list)


def _model(**names):
    return SimpleNamespace(by_vr={vr: SimpleNamespace(name=name)
                                  for name, vr in names.items()})


def _setup(tmp_path, *, probe: str = PROBE, call: str = "", in_progress: bool = True,
           refs: tuple[int, ...] = (), n: int | None = None, started: int = 0,
           probe_start: int = 0, grown: int = 0, grew: str = "", stderr: str | None = None,
           model=None, limits: Limits = LIMITS):
    rec = CallRecord()
    if started or probe_start:
        rec.enter("fmi3X", count=probe_start)
        rec.leave()
    rec.set_probe(probe)
    if call:
        arr = (ctypes.c_uint32 * len(refs))(*refs) if refs else None
        rec.enter(call, count=started or None, refs=arr,
                  n=len(refs) if n is None else n)
        if not in_progress:
            rec.leave()
    if grown or grew:
        rec.grew(grew, grown)
    call_file = tmp_path / "calls"
    call_file.write_bytes(bytes(rec.buffer))
    stderr_file = tmp_path / "stderr"
    if stderr is not None:
        stderr_file.write_text(stderr)
    rules = [CATALOGUE[PROBE], CATALOGUE[ENDURANCE], CATALOGUE["DAE739"]]
    run = _Run(None, SimpleNamespace(model=model), rules, 0)
    run.binary = BINARY
    driver = _Driver(run, limits, str(call_file), str(stderr_file), str(tmp_path))
    return D.Diagnosis(driver), driver, run


def _only(run):
    (code, v), = run.outcome.violations
    return code, v


# ------------------------------------------------------------------------ small readers

def test_read_counts_of_a_missing_file_are_zero(tmp_path):
    assert D.read_counts(str(tmp_path / "none")) == (0, 0)
    _, driver, _ = _setup(tmp_path, call="fmi3GetFloat64", started=12, probe_start=5)
    assert D.read_counts(driver.call_file) == (12, 5)


def test_a_library_that_does_not_load_names_the_error_without_the_temporary_path():
    v = D.not_loadable(OSError(os.path.join("/tmp/x", "binaries", "m.so") + ": bad ELF"),
                       "/tmp/x")
    assert v.message == "the binary cannot be loaded: binaries/m.so: bad ELF"
    assert thaw(v.evidence) == {"error": "binaries/m.so: bad ELF", "exception": "OSError"}
    assert v.part is None and v.location == Location()
    missing = D.not_loadable(AttributeError("function fmi3Reset not found"), "/tmp/x")
    assert missing.part == "missing-function"
    assert thaw(missing.evidence)["exception"] == "AttributeError"


def test_the_call_clock_restarts_when_another_call_started(tmp_path, monkeypatch):
    _, driver, _ = _setup(tmp_path, call="fmi3GetFloat64", started=3)
    now = [100.0]
    monkeypatch.setattr(D.time, "monotonic", lambda: now[0])
    clock = D.CallClock(driver.call_file)
    assert (clock.started, clock.since) == (-1, 100.0)
    now[0] = 101.0
    clock.tick()
    assert (clock.started, clock.since) == (3, 101.0)
    now[0] = 104.0
    clock.tick()                                   # the same call still: the clock runs on
    assert clock.since == 101.0 and clock.running() == 3.0


def test_stderr_is_its_tail_without_temporary_paths(tmp_path):
    tmp = str(tmp_path)
    text = "x" * 2000 + f"\nerror in {os.path.join(tmp, 'fmu')}{os.sep}binaries/m.so and {tmp}/w  \n"
    diag, _, _ = _setup(tmp_path, stderr=text)
    tail = diag.stderr()
    assert tail.endswith("error in binaries/m.so and <tmp>/w")
    assert len(tail) <= D.STDERR_TAIL and tail.startswith("x")
    assert diag._stderr_evidence() == {"stderr": tail}
    quiet, _, _ = _setup(tmp_path / "q" if (tmp_path / "q").mkdir() is None else tmp_path)
    assert quiet.stderr() == "" and quiet._stderr_evidence() == {}


def test_a_missing_call_file_reads_as_nothing_recorded(tmp_path):
    diag, driver, _ = _setup(tmp_path)
    driver.call_file = str(tmp_path / "gone")
    assert diag._record() == ("", "", False)
    assert diag._refs() == (0, ())
    assert diag._growth() == (0, "")


# ------------------------------------------------------------------------ time limits

def test_a_time_limit_with_no_call_in_progress_is_lsdaes_own(tmp_path):
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", in_progress=False)
    probe, reason = diag.timed_out(PROBE, per_fmu=False, call_seconds=50.0, probe_seconds=50.0)
    assert probe == PROBE and run.outcome.violations == []
    assert reason == (
        f"time limit: lsdae's own computation in {run.names(PROBE)} took longer than the 20 s "
        "limit per probe (probe_seconds of binary-timed-out) while no FMI call was in progress "
        "(after fmi3GetFloat64 had returned); not the binary's fault")
    assert driver.died == [PROBE] and driver.blocked == []


def test_a_per_fmu_time_limit_before_any_call_names_that_limit(tmp_path):
    diag, _, run = _setup(tmp_path, probe="")
    probe, reason = diag.timed_out("setup", per_fmu=True, call_seconds=0.0, probe_seconds=1.0)
    assert probe == "setup"
    assert reason == (
        f"time limit: lsdae's own computation in {run.names('setup')} took longer than the "
        "300 s limit per FMU (fmu_seconds of binary-timed-out) while no FMI call was in "
        "progress (before any FMI call); not the binary's fault")


@pytest.mark.parametrize("call_seconds, probe_seconds, hung", [
    (9.99, 20.0, False), (10.0, 20.0, True),     # half the probe's time
    (5.0, 10.0, True), (4.99, 10.0, False),      # the probe ran 10 s only: half of that
    (10.0, 60.0, True), (9.9, 60.0, False),      # capped at the per-probe limit (20 s)
])
def test_a_call_is_hung_when_it_ran_half_the_probes_time(tmp_path, call_seconds,
                                                         probe_seconds, hung):
    diag, driver, run = _setup(tmp_path, call="fmi3DoStep")
    probe, reason = diag.timed_out(PROBE, per_fmu=False, call_seconds=call_seconds,
                                   probe_seconds=probe_seconds)
    assert probe == PROBE
    assert (reason == "") is hung
    assert (run.outcome.violations != []) is hung
    if not hung:
        assert reason == (
            f"time limit: {run.names(PROBE)} took longer than the 20 s limit per probe "
            "(probe_seconds of binary-timed-out) in many FMI calls and lsdae's own work "
            "between them; no single call ran for half of that time, so no call hung "
            "(lsdae's budget, not the binary's fault)")


def test_a_hung_call_is_binary_timed_out_naming_the_call(tmp_path):
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", stderr="stuck\n")
    probe, reason = diag.timed_out(PROBE, per_fmu=True, call_seconds=200.0, probe_seconds=250.0)
    assert (probe, reason) == (PROBE, "")
    code, v = _only(run)
    assert (code, v.rule) == ("DAE702", "binary-timed-out") or v.rule == "binary-timed-out"
    assert v.message == (f"the binary did not respond within the 300 s limit per FMU: stopped "
                         f"during fmi3GetFloat64, in {run.names(PROBE)}")
    assert v.location == Location(file=BINARY) and v.subject == "fmi3GetFloat64"
    assert thaw(v.evidence) == {"probe": PROBE, "call": "fmi3GetFloat64",
                                "call_in_progress": True, "limit_seconds": 300.0,
                                "limit": "per FMU", "stderr": "stuck"}
    assert run.outcome.run == {PROBE} and driver.blocked == ["fmi3GetFloat64"]


def test_a_hang_outside_a_rule_is_not_counted_as_a_rule_run(tmp_path):
    diag, driver, run = _setup(tmp_path, probe="setup", call="fmi3Instantiate")
    assert diag.timed_out("x", per_fmu=False, call_seconds=30.0, probe_seconds=30.0) == (
        "setup", "")
    assert run.outcome.run == set() and driver.blocked == ["fmi3Instantiate"]
    assert _only(run)[1].subject == "fmi3Instantiate"


def test_an_endurance_probe_counts_the_calls_made(tmp_path):
    diag, _, run = _setup(tmp_path, probe=ENDURANCE, call="fmi3GetFloat64", started=1501,
                          probe_start=300)
    diag.timed_out(ENDURANCE, per_fmu=False, call_seconds=20.0, probe_seconds=20.0)
    v = _only(run)[1]
    assert v.message.endswith(
        f"stopped during fmi3GetFloat64, after 1,200 FMI calls in this probe (1,500 in this "
        f"worker), in {run.names(ENDURANCE)}")
    ev = thaw(v.evidence)
    assert (ev["call_count"], ev["calls_in_probe"]) == (1500, 1200)


def test_an_endurance_probe_after_a_call_returned_counts_it(tmp_path):
    diag, _, run = _setup(tmp_path, probe=ENDURANCE, call="fmi3GetFloat64", started=1501,
                          probe_start=300, in_progress=False)
    _, reason = diag.timed_out(ENDURANCE, per_fmu=False, call_seconds=20.0, probe_seconds=20.0)
    assert ("(after fmi3GetFloat64 had returned, after 1,201 FMI calls in this probe (1,501 in "
            "this worker))") in reason


def test_the_recorded_probe_wins_over_the_current_one_and_none_falls_back(tmp_path):
    diag, driver, _ = _setup(tmp_path, probe="", call="fmi3GetReal")
    assert diag.timed_out("DAE739", per_fmu=False, call_seconds=1.0,
                          probe_seconds=1.0)[0] == "DAE739"
    assert driver.died == ["DAE739"]
    empty, driver2, _ = _setup(tmp_path, probe="")
    empty.timed_out("", per_fmu=False, call_seconds=1.0, probe_seconds=1.0)
    assert driver2.died == []


# ------------------------------------------------------------------------ deaths

def test_a_crash_during_a_call_of_one_variable_names_it_and_joins_its_cause(tmp_path):
    model = _model(x=7)
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", refs=(7,), model=model,
                               stderr="Segmentation fault\n")
    assert diag.died(PROBE, _Watch()) == (PROBE, "")
    code, v = _only(run)
    assert v.rule == "binary-crashed"
    assert v.message == (f"the binary crashed (killed by SIGSEGV) during fmi3GetFloat64 of 'x' "
                         f"(valueReference 7), in {run.names(PROBE)}")
    assert v.location == Location(file=BINARY) and v.subject == "fmi3GetFloat64"
    assert v.part is None
    assert v.cause == (D.CRASH_CAUSE, causes.through("x"))
    assert thaw(v.evidence) == {
        "probe": PROBE, "call": "fmi3GetFloat64", "call_in_progress": True,
        "exit": "killed by SIGSEGV", "stderr": "Segmentation fault",
        "value_references": [7], "variables": ["x"], "value_reference_count": 1,
        "place": run.names(PROBE)}
    assert run.outcome.run == {PROBE}
    assert driver.narrowed == {"fmi3GetFloat64"} and driver.to_narrow == {}


def test_a_crash_in_a_getter_of_several_variables_is_noted_for_narrowing(tmp_path):
    model = _model(x=7, y=8)
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", refs=(7, 8, 9), model=model)
    diag.died(PROBE, _Watch("killed by SIGABRT"))
    v = _only(run)[1]
    assert v.message == ("the binary crashed (killed by SIGABRT) during fmi3GetFloat64 of 3 "
                         "variables ('x', 'y', 'valueReference 9'), in " + run.names(PROBE))
    assert v.cause == (D.CRASH_CAUSE,)
    assert thaw(v.evidence)["variables"] == ["x", "y", "valueReference 9"]
    assert driver.to_narrow == {("fmi3GetFloat64", "killed by SIGABRT"): (7, 8, 9)}
    assert driver.narrowed == set()


def test_more_variables_than_kept_are_shown_with_an_ellipsis_and_not_narrowed(tmp_path):
    refs = tuple(range(1, 11))
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", refs=refs, model=_model())
    diag.died(PROBE, _Watch())
    v = _only(run)[1]
    assert ("during fmi3GetFloat64 of 10 variables ('valueReference 1', 'valueReference 2', "
            "'valueReference 3', 'valueReference 4', 'valueReference 5', 'valueReference 6', "
            "'valueReference 7', 'valueReference 8', …), in") in v.message
    assert thaw(v.evidence)["value_reference_count"] == 10
    assert driver.to_narrow == {} and driver.narrowed == set()


def test_one_unknown_variable_and_no_model_are_named_by_reference(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3SetFloat64", refs=(5,), model=None)
    diag.died(PROBE, _Watch())
    v = _only(run)[1]
    assert "during fmi3SetFloat64 of valueReference 5, in" in v.message
    assert v.cause == (D.CRASH_CAUSE, causes.through("valueReference 5"))
    unnamed, _, run2 = _setup(tmp_path, call="fmi3GetFloat64", refs=(5,),
                              model=SimpleNamespace(by_vr={5: SimpleNamespace(name="")}))
    unnamed.died(PROBE, _Watch())
    # known but unnamed: the reference stands for the name, quoted as a name is
    assert ("during fmi3GetFloat64 of 'valueReference 5' (valueReference 5), in"
            in _only(run2)[1].message)


def test_a_setter_crash_is_not_narrowed(tmp_path):
    diag, driver, _ = _setup(tmp_path, call="fmi3SetFloat64", refs=(1, 2), model=_model())
    diag.died(PROBE, _Watch())
    assert driver.to_narrow == {} and driver.narrowed == set()


def test_a_crash_after_a_call_returned_names_no_variable(tmp_path):
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", refs=(7,), in_progress=False,
                               model=_model(x=7))
    diag.died(PROBE, _Watch())
    v = _only(run)[1]
    assert v.message == (f"the binary crashed (killed by SIGSEGV) after fmi3GetFloat64 had "
                         f"returned, in {run.names(PROBE)}")
    assert v.cause == (D.CRASH_CAUSE,) and v.subject == "fmi3GetFloat64"
    assert "variables" not in thaw(v.evidence) and driver.narrowed == set()


def test_a_crash_before_any_call_has_the_probe_as_subject(tmp_path):
    diag, _, run = _setup(tmp_path)
    diag.died(PROBE, _Watch())
    v = _only(run)[1]
    assert v.subject == PROBE and v.message.endswith(f"before any FMI call, in {run.names(PROBE)}")


def test_a_crash_in_an_illegal_call_of_its_probe_is_its_part(tmp_path):
    diag, _, run = _setup(tmp_path, probe="DAE739", call="fmi3SetBoolean")
    diag.died("DAE739", _Watch())
    assert _only(run)[1].part == "crash-on-illegal-call"
    other, _, run2 = _setup(tmp_path, probe="DAE739", call="fmi3GetFloat64")
    other.died("DAE739", _Watch())
    assert _only(run2)[1].part is None
    after, _, run3 = _setup(tmp_path, probe="DAE739", call="fmi3SetBoolean", in_progress=False)
    after.died("DAE739", _Watch())
    assert _only(run3)[1].part is None
    elsewhere, _, run4 = _setup(tmp_path, call="fmi3SetBoolean")
    elsewhere.died(PROBE, _Watch())
    assert _only(run4)[1].part is None


def test_a_death_in_setup_before_loading_is_lsdaes_internal_error(tmp_path):
    diag, _, run = _setup(tmp_path, probe="setup", stderr="Traceback\nImportError: numpy\n")
    assert diag.died("setup", _Watch("the process exited with status 1")) == ("setup", "")
    code, v = _only(run)
    assert v.rule == "internal-error"
    assert v.message == ("the probe worker failed before loading the binary (the process "
                         "exited with status 1): ImportError: numpy")
    assert thaw(v.evidence) == {"exit": "the process exited with status 1",
                                "stderr": "Traceback\nImportError: numpy"}
    assert run.outcome.run == set()
    quiet, _, run2 = _setup(tmp_path / "q" if (tmp_path / "q").mkdir() is None else tmp_path,
                            probe="setup")
    quiet.died("setup", _Watch("ended"))
    assert _only(run2)[1].message.endswith("(ended): no message")


def test_a_death_in_setup_during_a_call_is_the_binarys(tmp_path):
    diag, _, run = _setup(tmp_path, probe="setup", call="fmi3InstantiateModelExchange")
    diag.died("setup", _Watch())
    assert _only(run)[1].rule == "binary-crashed"


# ------------------------------------------------------------------------ memory

LIMIT = LIMITS.address_space_mib * MIB


@pytest.mark.parametrize("peak, memory", [(int(0.8 * LIMIT), True), (int(0.8 * LIMIT) - 1, False)])
def test_a_death_near_the_address_space_limit_is_memory(tmp_path, peak, memory):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64")
    diag.died(PROBE, _Watch(peak_bytes=peak))
    assert _only(run)[1].rule == ("binary-memory-limit" if memory else "binary-crashed")


def test_a_memory_error_during_a_call_is_the_binarys(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", stderr="")
    diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    v = _only(run)[1]
    assert v.rule == "binary-memory-limit"
    assert v.message == (f"the binary exhausted the 1000 MiB address-space limit during "
                         f"fmi3GetFloat64, in {run.names(PROBE)} (MemoryError)")
    assert v.subject == "fmi3GetFloat64" and v.location == Location(file=BINARY)
    assert thaw(v.evidence) == {"probe": PROBE, "call": "fmi3GetFloat64",
                                "call_in_progress": True, "exit": "MemoryError",
                                "limit_mib": 1000, "place": run.names(PROBE)}
    assert v.cause == D.MEMORY_CAUSE   # every probe's death at the limit is one finding
    assert run.outcome.run == {PROBE}


def test_memory_the_calls_took_names_the_call_that_grew_it(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", grown=600 * MIB,
                          grew="fmi3DoStep")
    diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    v = _only(run)[1]
    assert v.message == (f"the binary exhausted the 1000 MiB address-space limit during "
                         f"fmi3GetFloat64, in {run.names(PROBE)} (MemoryError); its FMI calls "
                         "grew the address space by 600 MiB, the last of them fmi3DoStep")
    assert v.subject == "fmi3DoStep"
    ev = thaw(v.evidence)
    assert (ev["grown_in_fmi_calls_mib"], ev["last_growing_call"]) == (600, "fmi3DoStep")


def test_memory_grown_by_the_call_that_died_is_not_named_twice(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", grown=500 * MIB,
                          grew="fmi3GetFloat64")
    diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    v = _only(run)[1]
    assert v.message.endswith("(MemoryError)") and v.subject == "fmi3GetFloat64"
    assert thaw(v.evidence)["grown_in_fmi_calls_mib"] == 500


def test_memory_grown_below_the_share_is_not_blamed_on_the_growing_call(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", grown=500 * MIB - 1,
                          grew="fmi3DoStep")
    diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    v = _only(run)[1]
    assert v.subject == "fmi3GetFloat64" and v.message.endswith("(MemoryError)")
    assert "last_growing_call" not in thaw(v.evidence)


def test_memory_exhausted_while_idle_after_calls_grew_it_is_the_binarys(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", in_progress=False,
                          grown=500 * MIB, grew="fmi3DoStep", stderr="oom\n")
    assert diag.died(PROBE, _Watch("MemoryError", memory_error=True)) == (PROBE, "")
    v = _only(run)[1]
    assert v.rule == "binary-memory-limit" and v.part == "grown-across-calls"
    assert v.message == ("the binary's FMI calls grew the worker's address space by 500 MiB "
                         "(the last of them fmi3DoStep) until the 1000 MiB address-space limit "
                         "was exhausted after fmi3GetFloat64 had returned, in "
                         f"{run.names(PROBE)} (MemoryError)")
    assert v.subject == "fmi3DoStep" and v.location == Location(file=BINARY)
    assert thaw(v.evidence) == {
        "probe": PROBE, "call": "fmi3GetFloat64", "call_in_progress": False,
        "exit": "MemoryError", "grown_in_fmi_calls_mib": 500, "last_growing_call": "fmi3DoStep",
        "limit_mib": 1000, "stderr": "oom", "place": run.names(PROBE)}
    assert v.cause == D.MEMORY_CAUSE
    assert run.outcome.run == {PROBE}


def test_memory_exhausted_while_idle_without_that_growth_is_lsdaes_own(tmp_path):
    diag, driver, run = _setup(tmp_path, call="fmi3GetFloat64", in_progress=False,
                               grown=500 * MIB - 1, grew="fmi3DoStep")
    probe, reason = diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    assert probe == PROBE and run.outcome.violations == [] and run.outcome.run == set()
    assert reason == (
        f"memory limit: lsdae's own computation in {run.names(PROBE)} exhausted the worker's "
        "1000 MiB address-space limit (address_space_mib of binary-memory-limit) while no FMI "
        "call was in progress (after fmi3GetFloat64 had returned, MemoryError); not the "
        "binary's fault")


def test_grown_memory_is_not_the_binarys_while_a_call_is_in_progress_alone(tmp_path):
    # a call in progress: the memory is that call's (the general memory finding), not "grown"
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", grown=800 * MIB, grew="fmi3DoStep")
    diag.died(PROBE, _Watch("MemoryError", memory_error=True))
    assert _only(run)[1].part is None


def test_a_death_not_near_the_limit_with_growth_is_a_crash(tmp_path):
    diag, _, run = _setup(tmp_path, call="fmi3GetFloat64", in_progress=False, grown=900 * MIB,
                          grew="fmi3DoStep")
    diag.died(PROBE, _Watch())
    assert _only(run)[1].rule == "binary-crashed"


def test_is_rule_knows_rules_by_name_and_by_code(tmp_path):
    diag, _, run = _setup(tmp_path)
    assert diag.is_rule(PROBE) and diag.is_rule(CATALOGUE[PROBE].name)
    assert not diag.is_rule("setup") and not diag.is_rule("")


def test_a_crash_in_a_call_without_value_references(tmp_path):
    diag, driver, run = _setup(tmp_path, call="fmi3EnterEventMode", model=_model(x=7))
    diag.died(PROBE, _Watch())
    v = _only(run)[1]
    assert v.message == (f"the binary crashed (killed by SIGSEGV) during fmi3EnterEventMode, "
                         f"in {run.names(PROBE)}")
    assert v.cause == (D.CRASH_CAUSE,)
    assert "variables" not in thaw(v.evidence) and driver.to_narrow == {}


def test_a_death_the_record_names_no_probe_of_is_the_current_probes(tmp_path):
    diag, driver, run = _setup(tmp_path, probe="", call="fmi3GetFloat64")
    assert diag.died(PROBE, _Watch()) == (PROBE, "")
    v = _only(run)[1]
    assert v.message.endswith(f"during fmi3GetFloat64, in {run.names(PROBE)}")
    assert thaw(v.evidence)["probe"] == PROBE and driver.died == [PROBE]


def test_stderr_that_is_not_utf8_is_read_with_replacement_characters(tmp_path):
    diag, driver, _ = _setup(tmp_path)
    with open(driver.stderr_file, "wb") as fh:
        fh.write(b"bad \xff\xfe byte\n")
    assert diag.stderr() == "bad \ufffd\ufffd byte"
