"""Everything an importer reads must read back right (issue 20, point 7): the families.

* evaluation-failed's read-back (DAE724): a variable fmi3GetFloat64 refuses, leaves unwritten or
  gives as NaN, varied by the kind of variable (time, an input, a discrete variable, an event
  indicator), the state (Instantiated, Initialization, Event, Continuous-Time Mode) and the mode;
  the finding names the variable, the first state and the mode, and no other state or mode.
* state-vectors-inconsistent (DAE714): the getter (derivatives, states) and the mode.
* state-nominals-invalid (DAE715) and state-nominal-not-xml (DAE716): the value (0, negative,
  NaN, infinite), an unwritten element, another nominal than the XML's; each mode.
* stale-values-read (DAE717): the group read alone (outputs, derivatives, residuals, algebraic
  variables, event indicators), the setter that moved the point (fmi3SetContinuousStates,
  fmi3SetFloat64, all of them) and the mode.
* reset-incomplete (DAE712): what fmi3Reset keeps (time and the cache, the algebraic variables,
  the switch and a state).

The defect switches are in scenes/common/fmi3_framework.c (tests/fixtures/README.md); the clean
scenes and the corpus stay clean (tests/probes/test_clean_scenes.py, tests/scenes/test_corpus.py).
"""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.model.description import read_model_description
from conformance.probes.evaluation.readable import STATES, readable
from conformance.report.findings import Finding, thaw
from conformance.run.engine import EngineOptions, check_fmu
from tests.checkkit import checked
from tests.fixtures import SCENES_DIR, build_scene, variant


def _findings(scene: str, defines: tuple[str, ...], code: str,
              also: tuple[str, ...] = ()) -> list[Finding]:
    """The findings of ``code``, each violation its own (not folded by cause: the tests here
    look at each variable's evidence). Each test here looks at its rule's findings alone, so
    only the probes of ``code`` and ``also`` run (test_defects.py checks one member of each
    family with every probe); the report is kept for the next test that asks the same."""
    report = checked(build_scene(scene, defines=list(defines)),
                     options=EngineOptions(probes=True, select=tuple(sorted({code, *also})),
                                           fold=False))
    return [f for f in report.findings if f.code == code]


READS = [  # (scene, defines, variable, first state, mode(s) it shows in); time is not read in
    # Instantiated, where it has no value before fmi3EnterInitializationMode (FMI 3.0.2 §2.2.6)
    ("SimpleDAE", ("DEFECT_GET_REFUSED",), "time", "Initialization Mode", {"DAE", "ODE"}),
    ("SimpleDAE", ("DEFECT_GET_REFUSED", "READ_STATES=EventMode", "READ_DAE=0"), "time",
     "Event Mode", {"ODE"}),
    ("SimpleDAE", ("DEFECT_GET_REFUSED", "READ_KIND=K_U", "READ_STATES=Instantiated",
                   "READ_DAE=1"), "u1", "Instantiated", {"DAE"}),
    ("EventDAE", ("DEFECT_GET_REFUSED", "READ_KIND=K_D"), "k", "Initialization Mode",
     {"DAE", "ODE"}),
    ("EventDAE", ("DEFECT_GET_REFUSED", "READ_KIND=K_Z", "READ_STATES=InitializationMode"), "z",
     "Initialization Mode", {"DAE", "ODE"}),
    ("SimpleDAE", ("DEFECT_GET_NAN", "READ_STATES=ContinuousTimeMode"), "time",
     "Continuous-Time Mode", {"DAE", "ODE"}),
    ("SimpleDAE", ("DEFECT_GET_UNWRITTEN", "READ_KIND=K_U", "READ_STATES=EventMode",
                   "READ_DAE=0"), "u2", "Event Mode", {"ODE"}),
]


@pytest.mark.parametrize("scene,defines,variable,state,modes", READS,
                         ids=["-".join(r[1]) for r in READS])
def test_every_readable_variable_reads_back_in_every_state_and_mode(scene, defines, variable,
                                                                    state, modes):
    findings = _findings(scene, defines, "DAE724")
    by_subject = {f.subject: f.evidence_dict() for f in findings}
    assert variable in by_subject, [f.subject for f in findings]
    ev = by_subject[variable]
    assert ev["state"] == state
    assert {w.split(", ")[1].split()[0] for w in ev["where"]} == modes
    aimed = state if "READ_STATES" in " ".join(defines) else None
    if aimed:  # the defect is in one state: no other state is named
        assert {w.split(", ")[0] for w in ev["where"]} == {state}
    problem = {"DEFECT_GET_REFUSED": "refused", "DEFECT_GET_NAN": "nan",
               "DEFECT_GET_UNWRITTEN": "unwritten"}[defines[0]]
    assert ev["problem"] == problem
    part = {"refused": "refused-in-instantiated" if state == "Instantiated" else
            "refused-after-initialization", "nan": "nan-read-back", "unwritten": "unwritten"}
    assert {f.part for f in findings if f.subject == variable} == {part[problem]}


def test_reads_refused_in_one_state_are_one_finding():
    """EventDAE refuses every discrete variable in Initialization Mode: one getter defect, one
    finding (issue 29), its first variable's, with each other variable in its evidence."""
    report = checked(build_scene("EventDAE", defines=["DEFECT_GET_REFUSED", "READ_KIND=K_D"]),
                     options=EngineOptions(probes=True, select=("DAE724",)))
    (finding,) = [f for f in report.findings if f.code == "DAE724"]
    unfolded = _findings("EventDAE", ("DEFECT_GET_REFUSED", "READ_KIND=K_D"), "DAE724")
    assert len(unfolded) > 1
    also = thaw(finding.evidence_dict()["also"])
    assert {finding.subject, *(a["where"].strip("'") for a in also)} == {
        f.subject for f in unfolded}
    assert {a["rule"] for a in also} == {"DAE724"}
    assert f"the same defect in {len(unfolded) - 1} more place" in finding.message


def test_a_refused_event_indicator_variable_is_a_finding_not_a_rule_not_run():
    # the read-back (DAE724) runs before event-indicators-inconsistent (DAE733), whose probe
    # must then still run
    report = check_fmu(build_scene("EventDAE", defines=["DEFECT_GET_REFUSED", "READ_KIND=K_Z"]),
                       options=EngineOptions(probes=True, select=("DAE724", "DAE733")))
    assert "z" in {f.subject for f in report.findings if f.code == "DAE724"}
    assert "DAE733" not in dict(report.rules_not_run)
    # with the read-back deselected, event-indicators-inconsistent says it itself
    alone = check_fmu(build_scene("EventDAE", defines=["DEFECT_GET_REFUSED", "READ_KIND=K_Z"]),
                      options=EngineOptions(probes=True, endurance="off", select=("DAE733",)))
    assert [f.code for f in alone.findings if f.code.startswith("DAE7")] == ["DAE733"]


VECTORS = [  # (defines, getter, mode)
    (("DEFECT_VECTOR_DERIVATIVES", "READ_DAE=1"), "fmi3GetContinuousStateDerivatives", "DAE"),
    (("DEFECT_VECTOR_DERIVATIVES", "READ_DAE=0"), "fmi3GetContinuousStateDerivatives", "ODE"),
    (("DEFECT_VECTOR_STATES", "READ_DAE=1"), "fmi3GetContinuousStates", "DAE"),
    (("DEFECT_VECTOR_STATES", "READ_DAE=0"), "fmi3GetContinuousStates", "ODE"),
]


@pytest.mark.parametrize("defines,getter,mode", VECTORS, ids=["-".join(v[0]) for v in VECTORS])
def test_vector_getters_agree_with_their_variables(defines, getter, mode):
    findings = _findings("SimpleDAE", defines, "DAE714")
    assert {(f.evidence_dict()["getter"], f.evidence_dict()["mode"]) for f in findings} == {
        (getter, f"{mode} mode")}
    assert {f.subject for f in findings} == {"der(x2)" if "Derivatives" in getter else "x2"}
    # in DAE mode the manifest's <ContinuousStateDerivative> list orders the vectors
    assert {f.part for f in findings} == {"dae-mode-order" if mode == "DAE" else None}


NOMINALS = [  # (defines, code, modes)
    (("DEFECT_NOMINAL_INVALID", "NOMINAL_VALUE=0.0"), "DAE715", {"DAE", "ODE"}),
    (("DEFECT_NOMINAL_INVALID", "NOMINAL_VALUE=-1.0", "READ_DAE=0"), "DAE715", {"ODE"}),
    (("DEFECT_NOMINAL_INVALID", "NOMINAL_VALUE=NAN", "READ_DAE=1"), "DAE715", {"DAE"}),
    (("DEFECT_NOMINAL_INVALID", "NOMINAL_VALUE=INFINITY"), "DAE715", {"DAE", "ODE"}),
    (("DEFECT_NOMINAL_UNWRITTEN",), "DAE715", {"DAE", "ODE"}),
    (("DEFECT_NOMINAL_NOT_XML", "READ_DAE=1"), "DAE716", {"DAE"}),
    (("DEFECT_NOMINAL_NOT_XML", "READ_DAE=0"), "DAE716", {"ODE"}),
]


@pytest.mark.parametrize("defines,code,modes", NOMINALS, ids=["-".join(n[0]) for n in NOMINALS])
def test_state_nominals(defines, code, modes):
    other = "DAE716" if code == "DAE715" else "DAE715"
    findings = _findings("SimpleDAE", defines, code, also=(other,))
    assert {f.subject for f in findings} == {"x1"}
    assert {f.evidence_dict()["mode"].split()[0] for f in findings} == modes
    assert _findings("SimpleDAE", defines, other, also=(code,)) == []  # one fault, one finding
    if code == "DAE715":  # +Inf is > 0.0 (all FMI requires); an unwritten element is fmi3OK's
        part = ("unwritten" if "DEFECT_NOMINAL_UNWRITTEN" in defines else
                "infinite" if "NOMINAL_VALUE=INFINITY" in defines else None)
        assert {f.part for f in findings} == {part}


STALE = [  # (scene, kind, group, modes)
    ("SimpleDAE", "K_Y", "outputs", {"DAE", "ODE"}),
    ("SimpleDAE", "K_DER", "derivatives", {"DAE", "ODE"}),
    ("SimpleDAE", "K_RES", "residuals", {"DAE"}),
    ("SimpleDAE", "K_W", "algebraic variables", {"ODE"}),
    ("EventDAE", "K_Z", "event indicators", {"DAE", "ODE"}),
]


@pytest.mark.parametrize("scene,kind,group,modes", STALE, ids=[s[1] for s in STALE])
def test_each_group_read_alone_after_a_change_of_point(scene, kind, group, modes):
    findings = _findings(scene, ("DEFECT_STALE_READ", f"READ_KIND={kind}"), "DAE717")
    assert {f.evidence_dict()["group"] for f in findings} == {group}
    assert {f.evidence_dict()["mode"].split()[0] for f in findings} == modes


SETTERS = [  # (KEEPS_CACHE_ON, the setter, modes); fmi3SetTime (1) is left out: no small
    # scene's equations depend on time, so a cache kept across fmi3SetTime changes no value
    ("2", "fmi3SetContinuousStates", "-1", {"DAE", "ODE"}),
    ("3", "fmi3SetFloat64", "1", {"DAE"}),
    ("3", "fmi3SetFloat64", "0", {"ODE"}),
]


@pytest.mark.parametrize("on,setter,mode,modes", SETTERS, ids=[f"{s[1]}-{s[2]}" for s in SETTERS])
def test_a_setter_that_keeps_the_cache(on, setter, mode, modes):
    findings = _findings("SimpleDAE", ("DEFECT_SET_KEEPS_CACHE", f"KEEPS_CACHE_ON={on}",
                                       f"READ_DAE={mode}"), "DAE717")
    assert findings and {f.evidence_dict()["mode"].split()[0] for f in findings} == modes
    assert all(f.evidence_dict()["changed_by"][0] == setter for f in findings)


def test_stale_reads_in_one_mode_only():
    findings = _findings("SimpleDAE", ("DEFECT_STALE_READ", "READ_KIND=K_Y", "READ_DAE=0"),
                         "DAE717")
    assert {f.evidence_dict()["mode"] for f in findings} == {"ODE mode"}


RESETS = [  # (defines, the variables named)
    # time is not read in Instantiated (no value there before fmi3EnterInitializationMode), so
    # a reset that keeps it shows nowhere the probe may look
    (("DEFECT_RESET_KEEPS_TIME",), set()),
    (("DEFECT_RESET_KEEPS_GUESS",), {"z2"}),
    (("DEFECT_RESET_KEEPS_SWITCH",), {"ODE_DAE_Switch", "x1"}),
    # issue 30.3: the reset keeps the switch, and the algebraic variables too: compared with a
    # fresh instance in DAE mode (the mode the reset left it in), z2 is still a defect of its own
    (("DEFECT_RESET_KEEPS_SWITCH", "DEFECT_RESET_KEEPS_GUESS"), {"ODE_DAE_Switch", "x1", "z2"}),
    # the reset keeps the switch, and DAE mode holds z1 at 0.5 (its start is 0): z1 reads as a
    # fresh DAE-mode instance reads it, a consequence of the switch, listed in its finding
    (("DEFECT_RESET_KEEPS_SWITCH", "DEFECT_W_START_DAE"), {"ODE_DAE_Switch", "x1"}),
    # the reset keeps the algebraic variables for DAE mode only: read again after the switch is
    # set true in Configuration Mode, z2 is not what a fresh DAE-mode instance reads
    (("DEFECT_RESET_KEEPS_GUESS_DAE",), {"z2"}),
]


@pytest.mark.parametrize("defines,named", RESETS, ids=["+".join(r[0]) for r in RESETS])
def test_reset_against_a_fresh_instance(defines, named):
    findings = _findings("SimpleDAE", defines, "DAE712")
    assert {f.subject for f in findings} == named
    assert {f.subject for f in findings if f.part == "switch-kept"} == named & {"ODE_DAE_Switch"}


def test_a_value_the_reset_keeps_for_dae_mode_only_is_found_in_dae_mode():
    """Issue 30.1: after fmi3Reset the switch reads false and every start value holds in ODE
    mode; with the switch set true again in Configuration Mode, z2 is the value of before the
    reset, where a fresh DAE-mode instance reads 0."""
    (f,) = _findings("SimpleDAE", ("DEFECT_RESET_KEEPS_GUESS_DAE",), "DAE712")
    ev = f.evidence_dict()
    assert (f.subject, ev["mode"], ev["instantiated_dae_mode"]) == ("z2", "DAE mode", 0.0)
    assert ev["after_reset"] != 0.0
    assert f.message == (
        "after fmi3Reset and the enable parameter set true again in Configuration Mode, 'z2' "
        "reads a value set or computed before the reset, not what a fresh instance reads in "
        "DAE mode (MV-23)")


def test_what_only_the_kept_switch_explains_is_listed_in_its_finding():
    """Issue 30.3, the first cause decided from evidence: after fmi3Reset the switch is still
    true, and z1 reads 0.5 where a fresh instance reads 0 (ODE mode) and a fresh instance with
    the switch set reads 0.5 (DAE mode): a consequence of the switch, in its finding's evidence
    and message; x1, which no fresh instance holds, stays a finding of its own."""
    findings = _findings("SimpleDAE", ("DEFECT_RESET_KEEPS_SWITCH", "DEFECT_W_START_DAE"),
                         "DAE712")
    (switch,) = [f for f in findings if f.part == "switch-kept"]
    ev = switch.evidence_dict()
    assert thaw(ev["consequences"]) == [{"variable": "z1", "after_reset": 0.5,
                                         "instantiated": 0.0, "instantiated_dae_mode": 0.5}]
    assert switch.message.endswith("; 1 variable(s) read after the reset as in DAE mode, which "
                                   "the switch explains: 'z1'")
    assert ev["compared_with"].startswith("a fresh instance in DAE mode")
    assert {f.subject for f in findings} == {"ODE_DAE_Switch", "x1"}


def test_which_variables_are_readable_in_which_state():
    tree = etree.parse(str(SCENES_DIR / "corpus" / "TypesAndArrays" / "modelDescription.xml"))
    model = read_model_description(tree)
    by_state = {state: {i.var.name: i.size for i in readable(model, state)} for state in STATES}
    instantiated = by_state["Instantiated"]
    # a start value (not the independent variable: no start, no value before
    # fmi3EnterInitializationMode); arrays with their element counts
    assert {"x", "scale", "i8", "enabled", "label", "mode"} <= set(instantiated)
    assert "time" not in instantiated and "time" in by_state["Initialization Mode"]
    assert instantiated["gains"] == 3 and instantiated["matrix"] == 4
    assert not {"der(x)", "y", "total", "disabled", "status"} & set(instantiated)
    for state in STATES[1:]:
        assert {"der(x)", "y", "total", "disabled", "status"} <= set(by_state[state])
    for names in by_state.values():  # no getter for Binary and Clock; clocked: clock not active
        assert not {"blob", "tick", "ticks"} & set(names)


def test_the_independent_variable_is_not_read_in_instantiated_even_with_a_start():
    text = (SCENES_DIR / "corpus" / "TypesAndArrays" / "modelDescription.xml").read_text(
        encoding="utf-8").replace('causality="independent" variability="continuous"/>',
                                  'causality="independent" variability="continuous" start="0"/>')
    model = read_model_description(etree.ElementTree(etree.fromstring(text.encode())))
    assert model.by_vr[0].start == "0"
    assert "time" not in {i.var.name for i in readable(model, "Instantiated")}
    assert "time" in {i.var.name for i in readable(model, "Initialization Mode")}


@pytest.mark.parametrize("type_,attributes", [
    ("Int32", 'variability="discrete"'), ("Boolean", 'variability="discrete"'),
    ("Float64", ""), ("UInt8", 'causality="parameter" variability="fixed" start="3"'),
])
def test_a_variable_the_binary_does_not_know_is_a_finding_in_an_fmu_without_the_layer(
        type_, attributes):
    # the XML declares a variable the binary has no value reference for: a plain Model
    # Exchange FMU, each type, read in ODE mode (a parameter already in Instantiated)
    ghost = f'<{type_} name="ghost" valueReference="99" {attributes}/>\n    '
    fmu = variant("TypesAndArrays", md_edits=((
        '<Float64 name="x" valueReference="1"', ghost + '<Float64 name="x" valueReference="1"'),))
    report = check_fmu(fmu, options=EngineOptions(probes=True, select=("DAE724",)))
    found = {f.subject: f.evidence_dict() for f in report.findings if f.code == "DAE724"}
    assert set(found) == {"ghost"}
    ev = found["ghost"]
    assert ev["state"] == ("Instantiated" if "start" in attributes else "Initialization Mode")
    assert ev["mode"] == "ODE mode" and ev["problem"] == "refused"
