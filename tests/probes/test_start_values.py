"""start-value-not-applied (DAE713, issue 21.3): after instantiation, before any set, every
variable with initial exact or approx holds its XML start, whatever its type, size or place.

The family: every type fmi3Get* reads (Float64, Float32, the integer types, Enumeration,
Boolean, String), scalars and arrays (an element of a parameter array, a constant array), in a
DAE FMU (a state, an algebraic variable: tests/fixtures/defects/basic.py) and in FMUs without
the layer (the corpus, PythonFMU3's in tests/probes/test_pythonfmu3.py). The XML is edited
after the binary was built, so the binary holds the old value. The clean scenes and corpus
stay clean (tests/probes/test_clean_scenes.py, tests/scenes/test_corpus.py).
"""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.model.description import read_model_description
from conformance.probes.instruments.instantiation import Held, expected_starts, read_held
from conformance.runtime.errors import FmiError
from conformance.probes.readback.start_values import differs
from conformance.report.findings import Severity
from conformance.run.engine import EngineOptions, check_fmu
from tests.fixtures import variant

EDITS = {   # TypesAndArrays: (old, new) -> the variable named
    "scale": ('name="scale" valueReference="6" causality="input" start="1.5"',
              'name="scale" valueReference="6" causality="input" start="2.5"'),      # Float32
    "x": ('name="x" valueReference="1" declaredType="Length" initial="exact" start="1"',
          'name="x" valueReference="1" declaredType="Length" initial="exact" start="2"'),
    "i8": ('start="-8"', 'start="-9"'),
    "u64": ('start="64"', 'start="65"'),
    "enabled": ('start="true"', 'start="false"'),
    "label": ('"hello, corpus"', '"hello"'),
    "mode": ('variability="fixed" start="2"/>', 'variability="fixed" start="1"/>'),
    "gains": ('start="1 2 3"', 'start="1 2 4"'),                                   # element 2
    "offsets": ('start="10 20"', 'start="10 21"'),                          # a constant array
}


@pytest.mark.parametrize("variable", sorted(EDITS))
def test_each_type_and_shape_is_read_and_compared(variable):
    fmu = variant("TypesAndArrays", md_edits=(EDITS[variable],))
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    bad = [(f.name, f.subject) for f in report.findings if f.severity >= Severity.WARNING]
    assert bad == [("start-value-not-applied", variable)]
    (finding,) = [f for f in report.findings if f.name == "start-value-not-applied"]
    ev = finding.evidence_dict()
    assert ev["state"].startswith("Instantiated") and ev["start"] != ev["held"]


def test_several_edits_give_one_finding_per_variable():
    fmu = variant("TypesAndArrays", md_edits=tuple(EDITS.values()))
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    found = sorted(f.subject for f in report.findings if f.name == "start-value-not-applied")
    assert found == sorted(EDITS)


MD = """<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">
<ModelExchange modelIdentifier="M"/>
<ModelVariables>
  <Float64 name="time" valueReference="0" causality="independent" initial="exact" start="0"/>
  <UInt64 name="n" valueReference="1" causality="structuralParameter" variability="fixed" start="3"/>
  <Float64 name="a" valueReference="2" causality="parameter" variability="fixed" start="0.5"><Dimension valueReference="1"/></Float64>
  <Float64 name="b" valueReference="3" causality="parameter" variability="fixed" start="1 2"><Dimension start="2"/></Float64>
  <Float64 name="c" valueReference="4" causality="parameter" variability="fixed" start="1 2"><Dimension start="3"/></Float64>
  <Float64 name="d" valueReference="5" causality="output"/>
  <Float64 name="e" valueReference="6" initial="approx" start="NaN"/>
  <Boolean name="f" valueReference="7" causality="parameter" variability="fixed" start="1"/>
  <Int32 name="g" valueReference="8" causality="parameter" variability="fixed" start="x"/>
  <String name="h" valueReference="9" causality="parameter" variability="fixed"><Start value="a b"/></String>
  <Clock name="tick" valueReference="10" causality="input" intervalVariability="triggered"/>
  <Int32 name="i" valueReference="11" causality="input" variability="discrete" start="4" clocks="10"/>
  <Float64 name="j" valueReference="12" variability="discrete" initial="exact" start="5" clocks="10"/>
</ModelVariables>
<ModelStructure><Output valueReference="5"/></ModelStructure>
</fmiModelDescription>"""


def test_what_the_xml_says_each_variable_must_hold():
    model = read_model_description(etree.ElementTree(etree.fromstring(MD.encode())))
    got = {v.name: expected_starts(model, v) for v in model.variables}
    assert got == {
        "time": None,                 # independent: no value before initialisation (even
                                      # with a start the XML should not give it)
        "n": [3],
        "a": [0.5, 0.5, 0.5],         # one value broadcast to the size the parameter gives
        "b": [1.0, 2.0],
        "c": None,                    # two values for three elements: the static rules' case
        "d": None,                    # calculated: nothing to hold
        "e": None,                    # NaN: float-attribute-not-finite, not the binary's fault
        "f": [True],
        "g": None,                    # not a number: the schema stage reports it
        "h": ["a b"],                 # one <Start> child, spaces and all
        "tick": None,                 # no getter for a Clock
        "i": None,                    # clocked: read only in Event Mode while the clock
        "j": None,                    # ticks, or in Initialization Mode (FMI 3.0.2 §2.2.7.2)
    }


class _RefusesFirst:
    """An instance whose first fmi3Get<type> returns ``status``; ``calls``: the types read."""

    def __init__(self, status: str):
        self.status, self.calls = status, []

    def get_typed(self, type_, vrs, n, *, fill=None):
        self.calls.append(type_)
        if len(self.calls) == 1:
            raise FmiError(f"fmi3Get{type_}", self.status, ["refused"])
        return [0] * n


def _items() -> list[Held]:
    model = read_model_description(etree.ElementTree(etree.fromstring(MD.encode())))
    return [Held(v, start) for v in model.variables
            if (start := expected_starts(model, v)) is not None]


def test_nothing_is_read_on_an_instance_an_error_terminated():
    # FMI 3.0.2 §2.3.8: values of an instance in Terminated serve debugging only
    items, inst = _items(), _RefusesFirst("fmi3Error")
    read_held(inst, items)
    assert inst.calls == ["Float64"]                  # the array a, read first, refused
    first = items[[h.var.name for h in items].index("a")].error
    assert first is not None and first.after is None
    assert all(h.held is None for h in items)
    others = [h.error for h in items if h.var.name != "a"]
    assert others and all(e is not None and e.after is first and e.status == "not called"
                          for e in others)


def test_a_discarded_read_does_not_stop_the_others():
    items, inst = _items(), _RefusesFirst("fmi3Discard")
    read_held(inst, items)
    assert len(inst.calls) == 5                       # a, b, then n, f and h by type
    assert [h.var.name for h in items if h.held is None] == ["a"]


@pytest.mark.parametrize("type_, held, start, expected", [
    ("Float64", 0.1, 0.1, False),
    ("Float64", 0.1 + 1e-17, 0.1, False),
    ("Float64", 0.5, 0.6, True),
    ("Float64", float("nan"), 0.6, True),
    ("Float32", 0.10000000149011612, 0.1, False),   # single precision of the XML's 0.1
    ("Float32", 0.2, 0.1, True),
    ("Int8", -8, -8, False),
    ("UInt64", 2**63, 2**63 + 1, True),
    ("Boolean", 1, True, False),
    ("String", "ball", "balloon", True),
])
def test_how_a_value_is_compared(type_, held, start, expected):
    assert differs(type_, held, start, rtol=1e-12, float32_rtol=2e-7) is expected


def test_a_start_that_only_dae_mode_misses_is_found_and_says_so():
    """Issue 30.1: SimpleDAE holds z1's XML start (0) in ODE mode; once the switch is set true in
    Configuration Mode it holds 0.5. The DAE-mode snapshot (a fresh instance, the switch set,
    read in Instantiated) shows it: one finding, naming DAE mode as the only mode that does."""
    from tests.fixtures import build_scene
    report = check_fmu(build_scene("SimpleDAE", defines=["DEFECT_W_START_DAE"]),
                       options=EngineOptions(probes=True, select=("DAE713",)))
    (f,) = report.findings
    ev = f.evidence_dict()
    assert (f.code, f.severity, f.subject, f.location.file, f.location.line) == (
        "DAE713", Severity.ERROR, "z1", "modelDescription.xml", 24)
    assert (ev["modes"], ev["start"], ev["held"], dict(ev["held_by_mode"])) == (
        "DAE", 0.0, 0.5, {"DAE": 0.5})
    assert f.message == (
        "after fmi3InstantiateModelExchange and the enable parameter set true in Configuration "
        "Mode, before any other fmi3Set*, fmi3GetFloat64 returns 0.5 for 'z1', whose XML start "
        "is 0.0 (initial=\"approx\"), in DAE mode only (ODE mode holds it): an importer that "
        "trusts the XML starts from another point than the binary")


def test_a_start_both_modes_miss_is_one_finding_naming_both():
    """The XML says z1 starts at -1, the binary holds 0 in either mode: one finding."""
    report = check_fmu(variant("SimpleDAE", md_edits=((
        'name="z1" valueReference="5" causality="local" variability="continuous" '
        'initial="approx" start="0.0"',
        'name="z1" valueReference="5" causality="local" variability="continuous" '
        'initial="approx" start="-1"'),)), options=EngineOptions(probes=True, select=("DAE713",)))
    (f,) = report.findings
    ev = f.evidence_dict()
    assert (f.subject, ev["modes"], dict(ev["held_by_mode"])) == (
        "z1", "ODE and DAE", {"ODE": 0.0, "DAE": 0.0})
    assert f.message.startswith("after fmi3InstantiateModelExchange, before any fmi3Set*, "
                                "fmi3GetFloat64 returns 0.0 for 'z1', whose XML start is -1.0")
    assert "in ODE and DAE mode:" in f.message
