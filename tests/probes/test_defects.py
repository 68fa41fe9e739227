"""Every defect variant is caught by its rule and nothing else, every probe rule has one, and
each probe rule's finding on its variant is exactly the one expected (test_exact_*)."""
from __future__ import annotations

import math
import re

import pytest

from conformance.report.catalogue import default_catalogue, with_options
from conformance.run.engine import EngineOptions, check_fmu
from conformance.model.manifest import MANIFEST
from conformance.report.findings import FmuReport, Severity
from conformance.runtime.host import host_platform_tuple
from tests.checkkit import checked
from tests.exactkit import assert_exact
from tests.fixtures import DEFECTS, Defect, FIXTURES, SCENES_DIR, build_defect
from tests.reportkit import raw_placeholders

PROBE_RULES = [r for r in default_catalogue() if r.stage == "probe"]

_WITH_OPTIONS: dict[str, FmuReport] = {}


def _checked(defect: Defect) -> FmuReport:
    """The defect's report, once per session: through checkkit, or, for a variant with a rule
    option of its own (checkkit asks with the default catalogue), once per process here."""
    if not defect.options:
        return checked(build_defect(defect), options=EngineOptions(probes=True))
    if defect.id not in _WITH_OPTIONS:
        _WITH_OPTIONS[defect.id] = check_fmu(
            build_defect(defect), options=EngineOptions(probes=True),
            catalogue=with_options(default_catalogue(), defect.options))
    return _WITH_OPTIONS[defect.id]


def _report(defect_id: str) -> FmuReport:
    """The report of the defect variant of this id (tests/fixtures/defects/)."""
    (defect,) = [d for d in DEFECTS if d.id == defect_id]
    return _checked(defect)


@pytest.mark.parametrize("defect", DEFECTS, ids=[d.id for d in DEFECTS])
def test_defect_is_caught_by_its_rule_only(defect: Defect):
    report = _checked(defect)
    expected = {defect.code, *defect.also}
    found = {f.code for f in report.findings
             if f.severity >= Severity.WARNING or f.code in expected}
    detail = "\n".join(f"  {f.severity} {f.code} {f.name}: {f.message}" for f in report.findings)
    assert found == expected, (f"{defect.id}: extra {sorted(found - expected)}, "
                               f"missing {sorted(expected - found)}\n{detail}")
    assert raw_placeholders(report) == []


@pytest.mark.parametrize("rule", PROBE_RULES, ids=[r.code for r in PROBE_RULES])
def test_every_probe_rule_has_a_defect_variant(rule):
    assert any(d.code == rule.code for d in DEFECTS), (
        f"{rule.code} {rule.name} has no defect variant in tests/fixtures/defects/")


def _c_switches() -> set[str]:
    """The macros the scenes' C sources test with #if/#ifdef/#ifndef/#elif."""
    found = set()
    for path in [*SCENES_DIR.rglob("*.c"), *SCENES_DIR.rglob("*.h")]:
        for line in path.read_text(encoding="utf-8").splitlines():
            if re.match(r"\s*#\s*(if|ifdef|ifndef|elif)\b", line):
                found.update(re.findall(r"\b[A-Z][A-Z0-9_]*\b", line))
    return found


def test_every_defect_switch_is_documented_and_every_table_define_exists():
    switches = _c_switches()
    readme = (FIXTURES / "README.md").read_text(encoding="utf-8")
    undocumented = sorted(s for s in switches
                          if s.startswith("DEFECT_") and f"`{s}`" not in readme)
    assert undocumented == [], f"add these switches to tests/fixtures/README.md: {undocumented}"
    unknown = sorted({d.split("=")[0] for defect in DEFECTS for d in defect.defines} - switches)
    assert unknown == [], f"defines of tests/fixtures/defects/ that no C source tests: {unknown}"


# The exact finding of each probe rule on its defect variant (issue: "assert on the exact
# finding, not only that something fired"): severity, subject, file and line, and the evidence
# numbers that prove it. The reports are the ones test_defect_is_caught_by_its_rule_only makes
# (checkkit: once per session). Each expectation was checked against the variant's C source
# (scenes/common/fmi3_framework.c, scenes/<scene>/model.c) and XML: the subject is the variable
# the defect makes wrong, the line is that variable's element. Evidence that varies from run to
# run (timings, memory, counts of calls that depend on which worker ran what) is left out;
# values of the FMU's own arithmetic at the seed-0 sampling points are compared within 1e-6,
# the integrators' within 1e-4.

MD = "modelDescription.xml"
MAN = MANIFEST


def _binary(scene: str) -> str:
    return f"binaries/{host_platform_tuple()}/{scene}.so"


def _also(found) -> list[tuple[str, str]]:
    """The (rule, place) of each finding folded into ``found`` as the same defect."""
    return [(dict(a)["rule"], dict(a)["where"]) for a in found.evidence_dict().get("also", ())]


def test_exact_binary_crashed():
    # every residual read crashes in Continuous-Time Mode; the narrowing reads each variable of
    # the call alone and names the first, g1 (valueReference 6); four more probes met it
    report = _report("DAE701-HelloWorldDAE-DEFECT_SEGFAULT_GETFLOAT64")
    found = assert_exact(report, code="DAE701", severity="error", subject="fmi3GetFloat64",
                         file=_binary("HelloWorldDAE"), line=None, part=None,
                         evidence={"probe": "narrow dae", "call": "fmi3GetFloat64",
                                   "call_in_progress": True, "exit": "killed by SIGSEGV",
                                   "value_references": [6], "variables": ["g1"],
                                   "value_reference_count": 1})
    assert sorted(_also(found)) == [("DAE701", "probe DAE717 stale-values-read"),
                                    ("DAE701", "probe DAE720 algebraic-not-settable"),
                                    ("DAE701", "probe DAE721 initial-residual-nonzero"),
                                    ("DAE701", "probe DAE722 evaluation-not-repeatable")]


def test_exact_binary_crashed_late():
    # the 5001st FMI call on one instance dereferences NULL: in the endurance path run, after
    # 5,000 calls on its instance (the probe's count adds the calls on its other instances;
    # the worker's count depends on which probes that worker ran before, left out)
    report = _report("DAE701-SimpleDAE-DEFECT_LATE_CRASH")
    found = assert_exact(report, code="DAE701", severity="error",
                         subject="fmi3GetContinuousStates", file=_binary("SimpleDAE"),
                         line=None, part=None,
                         evidence={"probe": "DAE760", "call": "fmi3GetContinuousStates",
                                   "call_in_progress": True, "exit": "killed by SIGSEGV",
                                   "place": "probe DAE760 evaluation-fails-late"})
    assert found.evidence_dict()["calls_in_probe"] > 5000


def test_exact_binary_timed_out():
    # fmi3GetDirectionalDerivative spins for ever: stopped at the 5 s per-probe limit (which
    # probe calls it first depends on how the probes are spread over the workers: left out)
    report = _report("DAE702-SimpleDAE-DEFECT_HANG_DIRECTIONAL")
    assert_exact(report, code="DAE702", severity="warning",
                 subject="fmi3GetDirectionalDerivative", file=_binary("SimpleDAE"), line=None,
                 part=None, evidence={"call": "fmi3GetDirectionalDerivative",
                                      "call_in_progress": True, "limit_seconds": 5.0,
                                      "limit": "per probe"})


def test_exact_binary_memory_limit():
    # fmi3GetContinuousStateDerivatives allocates 64 MiB blocks until malloc fails, then
    # aborts: under the default 2048 MiB limit, in each probe that calls it; one defect, one
    # finding (the handshake's), the other probes in its evidence
    report = _report("DAE703-HelloWorldDAE-DEFECT_MEMORY_BLOWUP")
    found = assert_exact(report, code="DAE703", severity="error",
                         subject="fmi3GetContinuousStateDerivatives",
                         file=_binary("HelloWorldDAE"), line=None, part=None,
                         evidence={"probe": "DAE710",
                                   "call": "fmi3GetContinuousStateDerivatives",
                                   "call_in_progress": True, "exit": "killed by SIGABRT",
                                   "limit_mib": 2048, "place": "probe DAE710 enable-handshake"})
    assert [f.code for f in report.findings].count("DAE703") == 1
    assert _also(found) == [("DAE703", "probe DAE714 state-vectors-inconsistent"),
                            ("DAE703", "probe DAE724 evaluation-failed"),
                            ("DAE703", "probe DAE730 state-set-ignored")]


def test_exact_binary_not_loadable():
    report = _report("DAE704-Robertson-DEFECT_MISSING_EXPORT")
    binary = _binary("Robertson")
    assert_exact(report, code="DAE704", severity="error", subject=None, file=binary, line=None,
                 part="missing-function",
                 evidence={"error": f"{binary}: undefined symbol: fmi3GetClock",
                           "exception": "AttributeError"})


def test_exact_enable_handshake():
    # the switch ODE_DAE_Switch is tunable (line 6 of the manifest names it), but
    # fmi3EnterConfigurationMode fails: Reconfiguration Mode is refused
    report = _report("DAE710-SimpleDAE-DEFECT_NO_RECONFIGURATION")
    assert_exact(report, code="DAE710", severity="error", subject="ODE_DAE_Switch", file=MAN,
                 line=6, part="reconfiguration-refused",
                 evidence={"call": "fmi3EnterConfigurationMode", "status": "fmi3Error",
                           "mode": "dae",
                           "sequence": ["fmi3InstantiateModelExchange",
                                        "fmi3EnterConfigurationMode", "fmi3SetBoolean(true)",
                                        "fmi3ExitConfigurationMode",
                                        "fmi3EnterInitializationMode", "fmi3GetBoolean",
                                        "fmi3ExitInitializationMode",
                                        "fmi3UpdateDiscreteStates"]})
    # the switch false: ODE mode's derivatives fail (HelloWorldDAE's switch 'dae', vr 1)
    report = _report("DAE710-HelloWorldDAE-DEFECT_ODE_DERIVATIVES_FAIL")
    assert_exact(report, code="DAE710", severity="error", subject="dae", file=MAN, line=6,
                 part="ode-run-fails",
                 evidence={"call": "fmi3GetContinuousStateDerivatives", "status": "fmi3Error",
                           "mode": "ode", "point": "start"})


def test_exact_dae_initialization_refused():
    report = _report("DAE711-HelloWorldDAE-DEFECT_DAE_INIT_REFUSED")
    assert_exact(report, code="DAE711", severity="info", subject="fmi3ExitInitializationMode",
                 file=MAN, line=6, part=None,
                 evidence={"call": "fmi3ExitInitializationMode", "status": "fmi3Error",
                           "dae_mode_probed": None})


def test_exact_reset_incomplete():
    # fmi3Reset keeps the switch and x1 (SimpleDAE line 20) as set at near-1
    report = _report("DAE712-SimpleDAE-DEFECT_RESET_KEEPS_SWITCH")
    assert_exact(report, code="DAE712", severity="error", subject="ODE_DAE_Switch", file=MAN,
                 line=6, part="switch-kept",
                 evidence={"after_reset": True, "start": False, "point": "near-1",
                           "consequences": []})
    assert_exact(report, code="DAE712", severity="error", subject="x1", file=MD, line=20,
                 part=None, rel=1e-6,
                 evidence={"after_reset": 0.4867895136708698, "start": 0.5,
                           "set_before": 0.4867895136708698, "instantiated": 0.5,
                           "point": "near-1", "scale": 1.0})


def test_exact_start_value_not_applied():
    # the XML edited after the build: x1 (line 20) says 0.6, the binary starts it at 0.5
    report = _report("DAE713-SimpleDAE-state-start")
    assert_exact(report, code="DAE713", severity="error", subject="x1", file=MD, line=20,
                 part=None,
                 evidence={"value_reference": 1, "type": "Float64", "initial": "exact",
                           "start": 0.6, "held": 0.5, "element": None,
                           "elements_differing": 1, "elements": 1, "modes": "ODE and DAE",
                           "held_by_mode": [["ODE", 0.5], ["DAE", 0.5]], "rtol": 1e-12})
    # DAE mode only: the switch moves w (EventDAE line 22) to its start + 0.5
    report = _report("DAE713-EventDAE-dae-mode-start")
    assert_exact(report, code="DAE713", severity="error", subject="w", file=MD, line=22,
                 part=None,
                 evidence={"value_reference": 3, "initial": "approx", "start": 1.0,
                           "held": 1.5, "modes": "DAE", "held_by_mode": [["DAE", 1.5]]})


def test_exact_algebraic_not_settable():
    # Robertson's algebraic variable y3 (vr 6, manifest line 8)
    report = _report("DAE720-Robertson-DEFECT_W_NOT_SETTABLE")
    assert_exact(report, code="DAE720", severity="error", subject="y3", file=MAN, line=8,
                 part=None, evidence={"call": "fmi3SetFloat64", "status": "fmi3Error",
                                      "point": "start", "value": 0.0})


def test_exact_initial_residual_nonzero():
    # w reset to its guess (y = z = 0) with x = 1: g1 = y + 2z - x = -1, g2 = y - 3z - 2x = -2
    report = _report("DAE721-HelloWorldDAE-DEFECT_INCONSISTENT_INIT")
    for subject, line, value in (("g1", 16, -1.0), ("g2", 17, -2.0)):
        assert_exact(report, code="DAE721", severity="info", subject=subject, file=MAN,
                     line=line, part=None,
                     evidence={"point": "start", "value": value, "scale": 1.0,
                               "tolerance": 1.0001e-06, "rtol": 1e-06, "atol": 1e-10,
                               "started": "configuration"})


def test_exact_evaluation_not_repeatable():
    # each jump to a distant point adds 1e-9 to the residual massBalance (line 16): start,
    # near-1, start again is two jumps (the offsets themselves count the earlier probes' jumps)
    report = _report("DAE722-Robertson-DEFECT_HIDDEN_STATE")
    assert_exact(report, code="DAE722", severity="error", subject="massBalance", file=MAN,
                 line=16, part=None, rel=1e-6,
                 evidence={"point": "start", "difference": 2e-9, "tolerance": 1.0001e-10,
                           "rtol": 1e-10, "atol": 1e-14,
                           "sequence": ["start", "near-1", "start"]})


def test_exact_nan_or_inf():
    # der(x) (line 22) is NaN for t > 0: at every near point, none at start
    report = _report("DAE723-HelloWorldDAE-DEFECT_NAN_DERIVATIVE")
    assert_exact(report, code="DAE723", severity="info", subject="der(x)", file=MD, line=22,
                 part=None, rel=1e-6,
                 evidence={"points": ["near-1", "near-2", "near-3"], "value": "nan",
                           "mode": "dae",
                           "first_point": [["label", "near-1"], ["t", 0.01257302210933933]]})


def test_exact_evaluation_failed():
    # the residual read fails in DAE mode for t > 0: first at near-1, then near-2 and near-3
    report = _report("DAE724-Robertson-DEFECT_EVAL_ERROR_AFTER_START")
    found = assert_exact(report, code="DAE724", severity="error", subject="fmi3GetFloat64",
                         file=MAN, line=2, part=None, rel=1e-6,
                         evidence={"call": "fmi3GetFloat64", "status": "fmi3Error",
                                   "point": "near-1", "t": 0.01257302210933933,
                                   "unknowns": ["massBalance", "der(y1)", "der(y2)"]})
    assert _also(found) == [("DAE724", "'fmi3GetFloat64'")] * 2   # near-2, near-3


def test_exact_input_not_settable():
    # both inputs are refused; u1 (vr 7, line 26) and u2 (vr 8, line 27)
    report = _report("DAE725-SimpleDAE-DEFECT_INPUT_NOT_SETTABLE")
    for subject, line, vr in (("u1", 26, 7), ("u2", 27, 8)):
        assert_exact(report, code="DAE725", severity="error", subject=subject, file=MD,
                     line=line, part=None,
                     evidence={"call": "fmi3SetFloat64", "status": "fmi3Error",
                               "value_reference": vr, "value": 0.0, "mode": "DAE mode",
                               "state": "Continuous-Time Mode", "point": "start"})


def test_exact_state_set_ignored():
    # x1, x2 set to near-1's states read back their start 0.5
    report = _report("DAE730-SimpleDAE-DEFECT_STATE_SET_IGNORED")
    assert_exact(report, code="DAE730", severity="error", subject="x1", file=MD, line=20,
                 part=None, rel=1e-6,
                 evidence={"point": "near-1", "t": 0.01257302210933933,
                           "read_with": "fmi3GetFloat64", "rtol": 1e-06,
                           "states": [["x1", [["set", 0.4867895136708698], ["read_back", 0.5]]],
                                      ["x2", [["set", 0.5640422650443282],
                                              ["read_back", 0.5]]]]})


def test_exact_state_not_settable_by_value():
    report = _report("DAE731-HelloWorldDAE-DEFECT_STATE_SET_REFUSED")
    assert_exact(report, code="DAE731", severity="warning", subject="x", file=MD, line=21,
                 part=None, rel=1e-6,
                 evidence={"call": "fmi3SetFloat64", "status": "fmi3Error", "point": "near-1",
                           "t": 0.01257302210933933, "states": ["x"],
                           "accepted_path": "fmi3SetContinuousStates"})


def test_exact_event_indicators_failed():
    # one more indicator than the manifest's <EventIndicator> (line 16) lists
    report = _report("DAE732-EventDAE-DEFECT_INDICATOR_COUNT")
    assert_exact(report, code="DAE732", severity="error",
                 subject="fmi3GetNumberOfEventIndicators", file=MAN, line=16, part=None,
                 evidence={"reported": 2, "declared": 1, "declared_in": "the manifest",
                           "indicators": ["z"]})


def test_exact_event_indicators_inconsistent():
    # the indicator z (line 25) computed from the previous evaluation's w
    report = _report("DAE733-EventDAE-DEFECT_INDICATORS_STALE")
    assert_exact(report, code="DAE733", severity="error", subject="z", file=MD, line=25,
                 part=None, rel=1e-6,
                 evidence={"point": "start", "t": 0.0, "index": 0,
                           "first": 0.42962647641930074, "second": 0.5,
                           "tolerance": 1.0001e-10, "rtol": 1e-10, "atol": 1e-14})


def test_exact_state_vectors_inconsistent():
    # the last element of fmi3GetContinuousStateDerivatives, der(x2) (line 23), is
    # 1e-6 * (1 + |der(x2)|) off fmi3GetFloat64's
    report = _report("DAE714-SimpleDAE-DEFECT_VECTOR_DERIVATIVES")
    found = assert_exact(report, code="DAE714", severity="error", subject="der(x2)", file=MD,
                         line=23, part="dae-mode-order", rel=1e-6,
                         evidence={"getter": "fmi3GetContinuousStateDerivatives", "index": 1,
                                   "vector": 0.2474052066584822,
                                   "get_float64": 0.24740395925452294, "point": "start",
                                   "t": 0.0, "mode": "DAE mode", "tolerance": 1.0001e-10})
    ev = found.evidence_dict()
    assert ev["vector"] - ev["get_float64"] == pytest.approx(1e-6 * (1 + ev["get_float64"]),
                                                             rel=1e-6)
    # ODE mode: the last state, x2 (line 22), is 0.5 + 1e-6 * 1.5
    report = _report("DAE714-SimpleDAE-states-ode")
    assert_exact(report, code="DAE714", severity="error", subject="x2", file=MD, line=22,
                 part=None, rel=1e-12,
                 evidence={"getter": "fmi3GetContinuousStates", "index": 1,
                           "vector": 0.5000015, "get_float64": 0.5, "point": "start",
                           "mode": "ODE mode"})


def test_exact_state_nominals_invalid():
    # x1's nominal (element 0, line 20) is 0 whatever the buffer held, in both modes: one
    # finding, the other mode in its evidence
    report = _report("DAE715-SimpleDAE-DEFECT_NOMINAL_INVALID")
    found = assert_exact(report, code="DAE715", severity="error",
                         subject="x1", file=MD, line=20, part=None,
                         evidence={"index": 0, "into_nan": 0.0, "into_1e300": 0.0,
                                   "fills": ["nan", 1e300], "mode": "DAE mode",
                                   "state": "Continuous-Time Mode", "place": "DAE mode"})
    assert _also(found) == [("DAE715", "ODE mode")]
    # left unwritten: the element reads back what the caller's buffer held
    report = _report("DAE715-SimpleDAE-DEFECT_NOMINAL_UNWRITTEN")
    found = assert_exact(report, code="DAE715", severity="error",
                         subject="x1", file=MD, line=20, part="unwritten",
                         evidence={"index": 0, "into_nan": float("nan"), "into_1e300": 1e300,
                                   "mode": "DAE mode"})
    assert _also(found) == [("DAE715", "ODE mode")]


def test_exact_state_nominal_not_xml():
    # 1.1 times x1's XML nominal 1 (line 20)
    report = _report("DAE716-SimpleDAE-DEFECT_NOMINAL_NOT_XML")
    found = assert_exact(report, code="DAE716", severity="info",
                         subject="x1", file=MD, line=20, part=None, rel=1e-12,
                         evidence={"index": 0, "nominal": 1.1, "xml_nominal": 1.0,
                                   "mode": "DAE mode", "rtol": 1e-12,
                                   "state": "Continuous-Time Mode"})
    assert _also(found) == [("DAE716", "ODE mode")]


def test_exact_stale_values_read():
    # the output y1 (line 28) read on its own keeps start's 0 at near-1's values
    report = _report("DAE717-SimpleDAE-outputs-stale")
    found = assert_exact(report, code="DAE717", severity="error", subject="y1", file=MD,
                         line=28, part=None, rel=1e-6,
                         evidence={"group": "outputs", "alone": 0.0,
                                   "at_new_point": 0.13022041828868072,
                                   "previous_point": 0.0,
                                   "points": ["start", "start with the values of near-1"],
                                   "changed_by": ["fmi3SetFloat64",
                                                  "setting the whole point"],
                                   "mode": "DAE mode"})
    assert _also(found) == [("DAE717", "'y1'")]   # the same in ODE mode


def test_exact_reset_incomplete_keeps_the_guess():
    # z2 (line 25) keeps the value solved at start; z1's solved value is its start 0
    report = _report("DAE712-SimpleDAE-DEFECT_RESET_KEEPS_GUESS")
    assert_exact(report, code="DAE712", severity="error", subject="z2", file=MD, line=25,
                 part=None, rel=1e-6,
                 evidence={"after_reset": 0.6796738189082439, "instantiated": 0.0,
                           "type": "Float64", "causality": "local", "point": "near-1"})


def test_exact_evaluation_failed_read_back():
    # the independent variable time (line 19) refused in every state and mode
    report = _report("DAE724-SimpleDAE-time-refused")
    where = ["Initialization Mode, DAE mode", "Event Mode, DAE mode",
             "Continuous-Time Mode, DAE mode", "Initialization Mode, ODE mode",
             "Event Mode, ODE mode", "Continuous-Time Mode, ODE mode"]
    assert_exact(report, code="DAE724", severity="error", subject="time", file=MD, line=19,
                 part="refused-after-initialization",
                 evidence={"call": "fmi3GetFloat64", "status": "fmi3Error",
                           "problem": "refused", "state": "Initialization Mode",
                           "mode": "DAE mode", "where": where, "value_reference": 0,
                           "causality": "independent", "variability": "continuous"})
    # NaN: the info sub-check
    report = _report("DAE724-SimpleDAE-time-nan")
    assert_exact(report, code="DAE724", severity="info", subject="time", file=MD, line=19,
                 part="nan-read-back",
                 evidence={"call": "fmi3GetFloat64", "status": "fmi3OK", "problem": "nan",
                           "where": where, "value_reference": 0})
    # the inputs unwritten in Initialization Mode: u1 (line 26), u2 folded into it
    report = _report("DAE724-SimpleDAE-inputs-unwritten")
    found = assert_exact(report, code="DAE724", severity="error", subject="u1", file=MD,
                         line=26, part="unwritten",
                         evidence={"status": "fmi3OK", "problem": "unwritten",
                                   "state": "Initialization Mode",
                                   "where": ["Initialization Mode, DAE mode",
                                             "Initialization Mode, ODE mode"],
                                   "value_reference": 7, "causality": "input"})
    assert _also(found) == [("DAE724", "'u2'")]


def test_exact_event_update_invalid():
    # the first event iteration at EventDAE's first event (t = 0.25) leaves every output
    # argument as the caller preset it, in both modes: one finding, the ODE mode's in it
    report = _report("DAE734-EventDAE-DEFECT_EVENT_OUTPUTS_UNWRITTEN")
    found = assert_exact(report, code="DAE734", severity="error",
                         subject="discreteStatesNeedUpdate", file=MD, line=None, part=None,
                         evidence={"mode": "dae", "t": 0.25, "call": 1,
                                   "place": "DAE mode, t = 0.25",
                                   "unwritten": ["discreteStatesNeedUpdate",
                                                 "terminateSimulation",
                                                 "nominalsOfContinuousStatesChanged",
                                                 "valuesOfContinuousStatesChanged",
                                                 "nextEventTimeDefined"]})
    assert _also(found) == [("DAE734", "ODE mode, t = 0.25")]


def test_exact_next_event_time_not_ahead():
    # at the time event t = 0.75 the FMU announces t - 0.1
    report = _report("DAE735-EventDAE-DEFECT_NEXT_EVENT_PAST=0.1")
    found = assert_exact(report, code="DAE735", severity="error",
                         subject="nextEventTime", file=MD, line=None, part=None, rel=1e-12,
                         evidence={"mode": "dae", "t": 0.75, "next_event_time": 0.65,
                                   "behind": 0.1})
    assert _also(found) == [("DAE735", "ODE mode, t = 0.75")]


def test_exact_values_stale_after_event():
    # b goes 0 -> 0.5 at t = 0.75 unnoticed: der(x) (line 21) = -(k x + b) reads -1, not -1.5;
    # in DAE mode the residual g (line 24) = w - k x - b reads 0, not -0.5 (the info part)
    report = _report("DAE736-EventDAE-DEFECT_EVENT_STALE")
    assert_exact(report, code="DAE736", severity="error", subject="der(x)", file=MD, line=21,
                 part=None, rel=1e-9,
                 evidence={"mode": "ode", "t": 0.75, "at_event": -1.0, "fresh": -1.5,
                           "tolerance": 1.5001e-06, "rtol": 1e-06, "atol": 1e-10})
    assert_exact(report, code="DAE736", severity="info", subject="g", file=MD, line=24,
                 part="dae-mode", rel=1e-9,
                 evidence={"mode": "dae", "t": 0.75, "at_event": 0.0, "fresh": -0.5,
                           "tolerance": 1.0001e-06})


def test_exact_states_changed_flag_spurious():
    # at the first event, t = 0.25, x still holds 1
    report = _report("DAE737-EventDAE-DEFECT_STATES_CHANGED_SPURIOUS")
    found = assert_exact(report, code="DAE737", severity="error",
                         subject="valuesOfContinuousStatesChanged", file=MD, line=None,
                         part=None, evidence={"mode": "dae", "t": 0.25, "states": [1.0]})
    assert _also(found) == [("DAE737", "ODE mode, t = 0.25")]


def test_exact_stop_time_refused():
    # SimpleDAE's DefaultExperiment: start 0, stop 1, the default tolerance 1e-6
    report = _report("DAE738-SimpleDAE-DEFECT_STOP_TIME_REFUSED")
    found = assert_exact(report, code="DAE738", severity="warning",
                         subject="fmi3EnterInitializationMode", file=MD, line=None, part=None,
                         evidence={"call": "fmi3EnterInitializationMode",
                                   "status": "fmi3Error", "mode": "dae", "start_time": 0.0,
                                   "stop_time": 1.0, "tolerance_defined": True,
                                   "tolerance": 1e-06})
    assert _also(found) == [("DAE738", "ODE mode")]


def test_exact_illegal_call_accepted():
    # fmi3SetBoolean on x1's value reference (1, the Float64 at line 20)
    report = _report("DAE739-SimpleDAE-DEFECT_SETBOOLEAN_ANY_VR")
    assert_exact(report, code="DAE739", severity="info", subject="x1", file=MD, line=20,
                 part=None,
                 evidence={"mode": "ode", "spec": "SG-09", "call": "fmi3SetBoolean",
                           "place": "fmi3SetBoolean, ODE mode"})


def test_exact_directional_derivative_mismatch():
    # d der(x1)/d x1 = cos(x1) = 0.87758 at x1 = 0.5 (start), given with the wrong sign; the
    # same wrong partial in ODE mode, the adjoint and Initialization Mode folded into it
    report = _report("DAE740-SimpleDAE-DEFECT_WRONG_JACOBIAN")
    found = assert_exact(report, code="DAE740", severity="error", subject="d(der(x1))/d(x1)",
                         file=MAN, line=14, part="dae-mode", rel=1e-6,
                         evidence={"mode": "DAE mode", "entry": "d(der(x1))/d(x1)",
                                   "unknown": "der(x1)", "known": "x1",
                                   "fmu": -0.8775825618903728,
                                   "finite_difference": 0.8775825618836229, "declared": True,
                                   "place": "fmi3GetDirectionalDerivative, DAE mode"})
    assert sorted(_also(found)) == [
        ("DAE740", "fmi3GetDirectionalDerivative, ODE mode"),
        ("DAE741", "fmi3GetAdjointDerivative, DAE mode"),
        ("DAE741", "fmi3GetAdjointDerivative, ODE mode"),
        ("DAE752", "fmi3GetDirectionalDerivative, Initialization Mode, DAE mode"),
        ("DAE752", "fmi3GetDirectionalDerivative, Initialization Mode, ODE mode")]
    # ODE mode only: 10 % too large, against modelDescription's der(x1) (line 38)
    report = _report("DAE740-SimpleDAE-DEFECT_ODE_DIRECTIONAL_OFF")
    assert_exact(report, code="DAE740", severity="error", subject="d(der(x1))/d(x1)", file=MD,
                 line=38, part=None, rel=1e-6,
                 evidence={"mode": "ODE mode", "declared_in": MD, "fmu": 0.9653408180794101,
                           "finite_difference": 0.8775825618836229,
                           "place": "fmi3GetDirectionalDerivative, ODE mode"})


def test_exact_adjoint_derivative_mismatch():
    # d(__residual0)/d(z1) (the residual at manifest line 22) doubled by the adjoint alone
    report = _report("DAE741-SimpleDAE-DEFECT_WRONG_ADJOINT")
    found = assert_exact(report, code="DAE741", severity="error",
                         subject="d(__residual0)/d(z1)", file=MAN, line=22, part=None,
                         rel=1e-6,
                         evidence={"mode": "DAE mode", "entry": "d(__residual0)/d(z1)",
                                   "unknown": "__residual0", "known": "z1",
                                   "fmu": 5.968034606330188,
                                   "finite_difference": 2.9840173028458157,
                                   "place": "fmi3GetAdjointDerivative, DAE mode"})
    ev = found.evidence_dict()
    assert ev["fmu"] == pytest.approx(2 * ev["finite_difference"], rel=1e-6)


def test_exact_dependency_undeclared():
    # der(x1) = sin(x1) + sin(z1*z2*u1) (manifest line 14) with z2 (vr 6) left out
    report = _report("DAE742-SimpleDAE-xml")
    assert_exact(report, code="DAE742", severity="error", subject="d(der(x1))/d(z2)", file=MAN,
                 line=14, part=None, rel=1e-6,
                 evidence={"mode": "DAE mode", "declared_in": MAN, "entry": "d(der(x1))/d(z2)",
                           "unknown": "der(x1)", "known": "z2", "known_value_reference": 6,
                           "finite_difference": 0.01449061159528383})
    # fmi3GetVariableDependencies says y (Output, line 14) depends on x (vr 2): its part's
    # basis is info
    report = _report("DAE742-Chain-DEFECT_EXTRA_DEPENDENCY")
    assert_exact(report, code="DAE742", severity="info", subject="d(y)/d(x)", file=MAN,
                 line=14, part="reported-dependencies-dae-mode",
                 evidence={"mode": "DAE mode", "entry": "d(y)/d(x)",
                           "known_value_reference": 2,
                           "source": "fmi3GetVariableDependencies"})


def test_exact_dependency_never_observed():
    # y1 = u1*x1*z1 + sin(u2) (manifest line 12) listed as depending on x2
    report = _report("DAE743-SimpleDAE-xml")
    assert_exact(report, code="DAE743", severity="info", subject="d(y1)/d(x2)", file=MAN,
                 line=12, part=None,
                 evidence={"mode": "DAE mode", "declared_in": MAN, "entry": "d(y1)/d(x2)",
                           "points": 4})


def test_exact_dependencies_kind_violated():
    # __residual0 = z1*u1^2 + tanh(3*z1) + u2*x1^3 (line 22) declared constant in z1:
    # d/dz1 = u1^2 + 3 (1 - tanh(3 z1)^2) is 3 at start (z1 = u1 = 0) and less at near-2
    report = _report("DAE744-SimpleDAE-xml")
    assert_exact(report, code="DAE744", severity="error", subject="d(__residual0)/d(z1)",
                 file=MAN, line=22, part=None, rel=1e-6,
                 evidence={"mode": "DAE mode", "entry": "d(__residual0)/d(z1)",
                           "kind": "constant", "known_value_reference": 5,
                           "smallest": 2.9515676658907113, "largest": 2.9999999996699835})


def test_exact_algebraic_jacobian_ill_conditioned_and_singular():
    # Chain's last residual rebuilt from the one before it: plus 1e-10*w[3] (cond ~ 1e11), or
    # twice it (singular); the finding is dg/dw's, at the first residual (line 22), no subject
    report = _report("DAE745-Chain-DEFECT_ILL_CONDITIONED")
    assert_exact(report, code="DAE745", severity="info", subject=None, file=MAN, line=22,
                 part=None, rel=1e-3,
                 evidence={"condition_number": 112829399512.6589, "size": 4,
                           "source": "fmi3GetDirectionalDerivative",
                           "involved": ["w[3]", "w[2]", "w[1]", "w[0]"],
                           "threshold": 1e8})
    report = _report("DAE746-Chain-DEFECT_SINGULAR_GW")
    assert_exact(report, code="DAE746", severity="error", subject=None, file=MAN, line=22,
                 part=None,
                 evidence={"size": 4, "source": "fmi3GetDirectionalDerivative",
                           "involved": ["w[3]", "w[2]", "w[1]", "w[0]"],
                           "threshold": "smallest singular value <= 4 * eps * largest"})


def test_exact_ode_dae_inconsistent():
    # ODE mode solves g = 0.05: at ODE mode's algebraic variables both residuals are 0.05
    report = _report("DAE747-SimpleDAE-DEFECT_ODE_DAE_INCONSISTENT")
    assert_exact(report, code="DAE747", severity="error", subject=None, file=MAN, line=22,
                 part=None, rel=1e-6,
                 evidence={"worst": "y2",
                           "residual_at_ode_algebraic": [["__residual0", 0.05],
                                                         ["__residual1", 0.05]],
                           "ode": [["der(x1)", 0.4135101808850224],
                                   ["der(x2)", 0.21353324736090387],
                                   ["y1", -0.023570958120995786],
                                   ["y2", -0.001175298826265366]],
                           "dae": [["der(x1)", 0.4164110737081649],
                                   ["der(x2)", 0.2138062296246579],
                                   ["y1", -0.021934168359143278],
                                   ["y2", -0.0023474671290940156]],
                           "newton_converged": True})


def test_exact_initial_dependency_undeclared():
    # in Initialization Mode y1 (the manifest's InitialUnknown at line 20) also gets
    # 0.25 * x2 (vr 3): d(y1)/d(x2) = 0.25 exactly; the ODE mode's twin folded into it
    report = _report("DAE750-SimpleDAE-DEFECT_INITIAL_UNDECLARED")
    found = assert_exact(report, code="DAE750", severity="error", subject="d(y1)/d(x2)",
                         file=MAN, line=20, part="dae-mode", rel=1e-6,
                         evidence={"element": "InitialUnknown", "file": MAN,
                                   "mode": "DAE mode", "entry": "d(y1)/d(x2)", "unknown": "y1",
                                   "known": "x2", "known_value_reference": 3,
                                   "known_role": "state", "finite_difference": 0.25,
                                   "confirmed_finite_difference": 0.25})
    assert _also(found) == [("DAE750", "'d(y1)/d(x2)'")]   # ODE mode's
    # ODE mode: modelDescription's InitialUnknown der(x1) (line 40) without x2
    report = _report("DAE750-SimpleDAE-ode-initial-without-state")
    assert_exact(report, code="DAE750", severity="error", subject="d(der(x1))/d(x2)", file=MD,
                 line=40, part=None, rel=1e-6,
                 evidence={"file": MD, "mode": "ODE mode", "known_value_reference": 3,
                           "known_role": "state",
                           "finite_difference": -0.0004624002481386027})


def test_exact_initial_dependencies_kind_violated():
    # der(x2) = ... + u1^2 (InitialUnknown, line 17) declared constant in u1 (vr 7)
    report = _report("DAE751-SimpleDAE-xml")
    assert_exact(report, code="DAE751", severity="error", subject="d(der(x2))/d(u1)",
                 file=MAN, line=17, part=None, rel=1e-6,
                 evidence={"element": "InitialUnknown", "mode": "DAE mode",
                           "entry": "d(der(x2))/d(u1)", "kind": "constant",
                           "known_value_reference": 7, "smallest": -0.1283112725925884,
                           "largest": 0.2058436161368666})


def test_exact_initial_directional_derivative_mismatch():
    # the implicit derivative of z1 and z2 (lines 18, 19) with the wrong sign: 7 entries in
    # one finding, no single subject
    report = _report("DAE752-SimpleDAE-DEFECT_INITIAL_DIRECTIONAL")
    found = assert_exact(report, code="DAE752", severity="error", subject=None, file=MAN,
                         line=18, part=None, rel=1e-6,
                         evidence={"mode": "DAE mode", "entry": "d(z1)/d(x1)", "count": 7,
                                   "subjects": ["d(z1)/d(x1)", "d(z1)/d(u1)", "d(z1)/d(u2)",
                                                "d(z2)/d(x1)", "d(z2)/d(x2)", "d(z2)/d(u1)",
                                                "d(z2)/d(u2)"],
                                   "lines": [18, 18, 18, 19, 19, 19, 19],
                                   "fmu": 0.02723233795521288,
                                   "finite_difference": -0.027232337955898373})
    ev = found.evidence_dict()
    assert ev["fmu"] == pytest.approx(-ev["finite_difference"], rel=1e-9)


def test_exact_evaluation_fails_late():
    # every FMI call after the 5000th on one instance returns fmi3Error
    report = _report("DAE760-HelloWorldDAE-DEFECT_LATE_ERROR")
    assert_exact(report, code="DAE760", severity="info", subject="fmi3GetContinuousStates",
                 file=MAN, line=2, part=None,
                 evidence={"call": "fmi3GetContinuousStates", "status": "fmi3Error",
                           "calls_before": 5001, "fresh_instance": "ok", "level": "quick",
                           "budget_calls": 50000})


def test_exact_memory_grows():
    # 1 KiB kept per fmi3GetFloat64 (the bytes measured, with malloc's overhead, vary: a range)
    report = _report("DAE761-Robertson-DEFECT_LEAK")
    found = assert_exact(report, code="DAE761", severity="info", subject="fmi3GetFloat64",
                         file=MAN, line=2, part=None,
                         evidence={"function": "fmi3GetFloat64",
                                   "measured": "C heap in use (mallinfo2)",
                                   "threshold_bytes_per_call": 64.0, "stopped": "budget",
                                   "level": "quick"})
    assert 1024 <= found.evidence_dict()["bytes_per_call"] < 1200


def test_exact_instances_not_independent():
    # the states in one C global: the first instance, read again after a second one was set
    # to near-1, gives near-1's derivatives
    report = _report("DAE762-SimpleDAE-DEFECT_GLOBAL_STATE")
    assert_exact(report, code="DAE762", severity="error", subject="shared-derivatives",
                 file=MAN, line=2, part=None, rel=1e-6,
                 evidence={"compared": "derivatives", "point": "start", "count": 5,
                           "level": "quick"})
    # a new instance starts from the states the last one freed left: x = 1 at start becomes
    # near-1's 0.98679
    report = _report("DAE762-HelloWorldDAE-DEFECT_STALE_STATES")
    assert_exact(report, code="DAE762", severity="error", subject="cycle", file=MAN, line=2,
                 part=None, rel=1e-6,
                 evidence={"kind": "cycle", "cycle": 1, "count": 4, "cycles_run": 1,
                           "compared": "values after initialisation",
                           "differences": [
                               [["variable", "x"], ["expected", 1.0],
                                ["actual", 0.9867895136708698],
                                ["difference", 0.013210486329130244]],
                               [["variable", "y"], ["expected", 1.4],
                                ["actual", 1.3815053191392177],
                                ["difference", 0.01849468086078221]],
                               [["variable", "z"], ["expected", -0.19999999999999998],
                                ["actual", -0.19735790273417395],
                                ["difference", 0.0026420972658260378]],
                               [["variable", "der(x)"], ["expected", 1.4],
                                ["actual", 1.3815053191392177],
                                ["difference", 0.01849468086078221]]]})


def test_exact_simulation_failed():
    # g1 jumps by 1 at t = 0.5 with no event indicator: IDA stalls there
    report = _report("DAE801-HelloWorldDAE-DEFECT_LATE_JUMP")
    found = assert_exact(report, code="DAE801", severity="info", subject="dae:solver",
                         file=MAN, line=2, part=None, rel=1e-4,
                         evidence={"mode": "dae", "t_start": 0.0, "t_reached": 0.5,
                                   "stop_time": 1.0, "rtol": 1e-06})
    event = dict(found.evidence_dict()["event"])
    assert (event["limit"], event["value"]) == ("stall_steps", 200)
    assert event["t"] == pytest.approx(0.5, rel=1e-9)


def test_exact_algebraic_jacobian_singular_along_trajectory():
    # dg/dy2 = 1 - y1^2 vanishes at t* = 1.5 - ln 2 (y2, the algebraic variable at line 8)
    report = _report("DAE802-VanDerPolDAE-xml")
    found = assert_exact(report, code="DAE802", severity="error", subject="y2", file=MAN,
                         line=8, part=None,
                         evidence={"mode": "dae", "t_start": 0.0, "stop_time": 1.0,
                                   "threshold": 1e12})
    assert found.evidence_dict()["t"] == pytest.approx(1.5 - math.log(2), abs=1e-5)


def test_exact_evaluation_failed_during_simulation():
    # Akzo without its CO2 feed: y2 used up near t = 0.184, sqrt() of a negative: fmi3Discard
    report = _report("DAE803-Akzo-AKZO_NO_CO2_FEED")
    found = assert_exact(report, code="DAE803", severity="info",
                         subject="dae:fmi3GetContinuousStateDerivatives", file=MAN, line=2,
                         part=None, rel=1e-4,
                         evidence={"mode": "dae", "t_start": 0.0,
                                   "t_reached": 0.18419613145756095, "stop_time": 180.0})
    event = dict(found.evidence_dict()["event"])
    assert (event["call"], event["status"], event["limit"]) == (
        "fmi3GetContinuousStateDerivatives", "fmi3Discard", "stall_steps")


def test_exact_simulation_budget_exceeded():
    # der(x) gains 1e5*cos(1e5*t) from t = 0.5: the 20000 steps end near t = 0.53
    report = _report("DAE804-HelloWorldDAE-DEFECT_LATE_FAST")
    assert_exact(report, code="DAE804", severity="warning", subject="dae:max_steps", file=MAN,
                 line=2, part=None, rel=1e-3,
                 evidence={"mode": "dae", "t_reached": 0.5262501190485054, "stop_time": 1.0,
                           "steps": 20000,
                           "event": [["t", 0.5262501190485054], ["limit", "max_steps"],
                                     ["value", 20000],
                                     ["last_step_t", 0.5262501190485054]]})


def test_exact_ode_dae_trajectory_mismatch():
    # from t = 0.5 ODE mode solves g = 0.05: y drifts furthest, by 0.1007 at t = 1, and not
    # less at 100 and 10000 times tighter tolerances
    report = _report("DAE805-HelloWorldDAE-DEFECT_LATE_ODE_DRIFT")
    # located at y's <AlgebraicVariable> (manifest line 8), where the reader acts
    found = assert_exact(report, code="DAE805", severity="error", subject="y", file=MAN,
                         line=8, part=None, rel=1e-3,
                         evidence={"limit": 100.0, "rtol": 1e-06, "compared_times": 101,
                                   "dae_status": "ok", "ode_status": "ok",
                                   "worst": [["variable", "y"], ["t", 1.0],
                                             ["dae", 5.6773194451291324],
                                             ["ode", 5.777984110651099],
                                             ["difference", 0.10066466552196651],
                                             ["tolerance_unit", 6.7779841106510985e-06],
                                             ["gap", 14851.711641486363]]})
    tighter = [dict(c) for c in found.evidence_dict()["confirmation"]]
    assert [c["rtol"] for c in tighter] == [1e-8, 1e-10]
    assert all(c["difference"] == pytest.approx(0.1007, rel=1e-3) for c in tighter)


def test_exact_invariant_drift():
    # der(p) = 1.05 v: the energy (the <Invariant> at line 19, vr 8) falls from 4 to 3.81
    # in both modes' runs: one finding, the ODE run's in it
    report = _report("DAE806-MassSpringDAE-DEFECT_ENERGY_DRIFT")
    found = assert_exact(report, code="DAE806", severity="info",
                         subject="energy", file=MAN, line=19, part=None, rel=1e-4,
                         evidence={"mode": "DAE mode", "value_reference": 8, "initial": 4.0,
                                   "worst": 3.8095150369891932, "t_worst": 2.31,
                                   "tolerance": 4e-4, "rtol": 1e-06, "times": 101})
    assert _also(found) == [("DAE806", "ODE mode trajectory")]


def test_exact_next_event_time_behind_during_simulation():
    # after the state event (x falls to 0.5 at t = ln 2) every event announces t - 0.05
    # in both modes' runs: one finding, the ODE run's in it
    report = _report("DAE807-EventDAE-DEFECT_STALE_TIME_EVENT")
    found = assert_exact(report, code="DAE807", severity="error",
                         subject="dae:nextEventTime", file=MAN, line=2, part=None, rel=1e-9,
                         evidence={"mode": "dae", "t_reached": 1.0, "stop_time": 1.0,
                                   "behind": 0.05, "count": 1})
    ev = found.evidence_dict()
    assert ev["t"] == pytest.approx(math.log(2), abs=1e-5)
    assert ev["next_event_time"] == pytest.approx(ev["t"] - 0.05, rel=1e-12)
    (other,) = [dict(a) for a in ev["also"]]
    assert other["rule"] == "DAE807" and other["where"].startswith(
        "'ode:nextEventTime', ODE-mode simulation, t = 0.69314")
