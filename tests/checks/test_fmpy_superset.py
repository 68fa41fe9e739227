"""lsdae reports every problem class that ``fmpy validate`` reports on an FMI 3.0 modelDescription.

Each case below breaks the HelloWorldDAE scene in one way (one problem class of
``fmpy.validation.validate_fmu`` and the reader it calls), zips it, and runs both tools. Every
message fmpy gives is mapped, explicitly, to the lsdae rule(s) that cover its class
(:data:`FMPY_CLASSES`); the test fails when fmpy reports a problem that no mapped lsdae rule
reports, and when fmpy says something this table does not know (a new fmpy class to map). A
second test keeps the table honest: every class is exercised by some case.

Some fmpy problems are bare exceptions from its reader (a ``KeyError`` prints as the missing
value reference, ``None`` for a display unit without a unit, the quoted unit for a display unit
of an undefined unit, a ``TypeError`` for a dimension without a size); what they stand for
depends on the case, so the case names the class.

Out of scope here: fmpy's "Unsupported FMI version" (an FMI 2.0 or 1.0 FMU, which lsdae reports
as out of scope by its own rule, not as a modelDescription problem). Deliberately not followed:
fmpy expects an output <Clock> among the InitialUnknowns, but a Clock has no ``initial``
attribute (fmi3Clock is not an initializable variable in the XSD), so MS-05 (a) does not ask for
it and model-structure-initial-unknown-mismatch does not either.
"""
from __future__ import annotations

import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from fmpy.validation import validate_fmu

from conformance.run.engine import EngineOptions, check_fmu
from conformance.model.manifest import MANIFEST
from conformance.model.description import MODEL_DESCRIPTION
from tests.fixturekit import scene_xml

# fmpy's message pattern -> the lsdae rules that cover that problem class (any one suffices).
FMPY_CLASSES: dict[str, tuple[str, tuple[str, ...]]] = {
    "schema": (r"^ERROR \(line \d+, column \d+\)", ("DAE020",)),
    "zip-backslash": (r"^The file path .* contains a backslash\.$", ("DAE002",)),
    "declared-type": (r"has declaredType=\".*\" which has not been defined\.$", ("DAE530",)),
    "read-combination": (r"has an illegal combination of causality=", ("DAE504",)),
    "derivative-vr": (r"^The derivative attribute of model variable .* which does not exist\.$",
                      ("DAE509",)),
    "name-unique": (r"^The variable name \".*\" \(line \d+\) is not unique\.$", ("DAE503",)),
    "continuous-non-float": (r"must have variability != \"continuous\"\.$", ("DAE504",)),
    "start-missing": (r"^Variable \".*\" \(line \d+\) has no start value\.$", ("DAE506",)),
    "combination": ((r"^The combination causality=\".*\" and variability=\".*\" in variable "
                     r".* is not allowed\.$"), ("DAE504", "DAE505", "DAE508")),
    "calculated-start": (r"has initial=\"calculated\" but provides a start value\.$", ("DAE507",)),
    "independent-start": (r"has causality=\"independent\" but provides a start value\.$",
                          ("DAE508",)),
    "unit": (r"^The unit \".*\" of variable .* is not defined\.$", ("DAE531",)),
    "display-unit": (r"^The display unit \".*\" of (the )?variable .* is not defined\.$",
                     ("DAE532",)),
    "name-character": (r"contains an illegal (carriage return|line feed|tab) character",
                       ("DAE533",)),
    "name-structured": (r"is not a legal variable name for naming convention \"structured\"",
                        ("DAE534",)),
    # the same fmpy message for a name with CR, LF or TAB: lsdae names that cause instead
    "name-structured-character": (r"", ("DAE533",)),
    "kind-without-dependencies": ((r"^(If dependenciesKind exists dependencies must also exist|"
                                   r"Either both or none of the dependencies and "
                                   r"dependenciesKind)"), ("DAE535",)),
    "kind-length": (r"^The number of elements in the dependencies and dependenciesKind",
                    ("DAE535",)),
    "outputs": (r"^ModelStructure/Outputs must have exactly one entry", ("DAE511",)),
    "derivative-attribute": ((r"referenced by the continuous state derivative \d+ .* must have "
                              r"the attribute \"derivative\"\.$"), ("DAE509",)),
    "initial-unknowns": (r"^ModelStructure/InitialUnknowns does not contain the expected set",
                         ("DAE513",)),
    "independent-count": (r"^Exactly one independent variable must be defined\.$", ("DAE508",)),
    "vr-unique": (r"has the same value reference as variable", ("DAE502",)),
    "build-description": ((r"^(Failed to validate buildDescription\.xml|"
                           r"Unsupported fmiBuildDescription version)"), ("DAE538",)),
    # bare exceptions of fmpy's reader: the case says which class they stand for
    "structure-vr": (r"", ("DAE510",)),
    "dimension": (r"", ("DAE536",)),
    "dimension-size-without-start": (r"", ("DAE506",)),
    "clocks-vr": (r"", ("DAE537",)),
    "display-unit-without-unit": (r"", ("DAE532",)),
}
_BARE = re.compile(r"^(\d+|None|'[^']*'|int\(\) argument must be .*)$")

X = ('<Float64 name="x" valueReference="2" causality="local" variability="continuous" '
     'initial="exact" start="1" nominal="1"/>')
G2 = ('<Float64 name="g2" valueReference="7" causality="local" variability="continuous" '
      'description="residual y - 3z - 2x"/>')
TIME = '<Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>'
DE = '<DefaultExperiment startTime="0" stopTime="1"/>'
CSD = '<ContinuousStateDerivative valueReference="3" dependencies="2" dependenciesKind="constant"/>'
IU = '<InitialUnknown valueReference="3" dependencies="2" dependenciesKind="constant"/>'
UNITS = '<UnitDefinitions><Unit name="m"><DisplayUnit name="mm" factor="1000"/></Unit></UnitDefinitions>'
BUILD = ('<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">'
         '<BuildConfiguration modelIdentifier="HelloWorldDAE"><SourceFileSet>'
         '<SourceFile name="model.c"/></SourceFileSet></BuildConfiguration></fmiBuildDescription>')


def after(anchor: str, text: str) -> tuple[str, str]:
    return anchor, anchor + "\n    " + text


def on_x(attributes: str) -> tuple[str, str]:
    return X, X.replace('name="x"', 'name="x" ' + attributes)


@dataclass(frozen=True)
class Case:
    id: str
    edits: tuple[tuple[str, str], ...] = ()
    extra: dict[str, str] = field(default_factory=dict)
    bare: str | None = None          # the class fmpy's bare exception messages stand for


CASES = [
    Case("schema", ((G2, G2.replace('causality="local"', 'causality="bogus"')),)),
    Case("zip-backslash", extra={"sources\\model.c": "/* */\n"}),
    Case("declared-type", (on_x('declaredType="Length"'),)),
    Case("read-combination", (after(G2, '<Float64 name="o" valueReference="8" causality="output" '
                                        'variability="fixed"/>'),)),
    Case("derivative-vr", ((X, X.replace('name="x"', 'name="x" derivative="99"')),)),
    Case("name-unique", ((G2, G2.replace('name="g2"', 'name="g1"')),)),
    Case("name-unique-alias", ((X, X.replace('nominal="1"/>', 'nominal="1"><Alias name="y"/>'
                                             '</Float64>')),)),
    Case("continuous-non-float", (after(G2, '<Int32 name="n" valueReference="8" '
                                            'variability="continuous"/>'),)),
    Case("start-missing", (after(G2, '<Float64 name="u" valueReference="8" causality="input"/>'),)),
    Case("combination-initial", (after(G2, '<Float64 name="p" valueReference="8" '
                                           'causality="local" variability="fixed" '
                                           'initial="exact" start="1"/>'),)),
    Case("calculated-start", ((G2, G2.replace('/>', ' initial="calculated" start="0"/>')),)),
    Case("independent-start", ((TIME, TIME.replace('/>', ' start="0"/>')),)),
    Case("independent-count", ((TIME, TIME.replace('causality="independent"',
                                                   'causality="local"')),)),
    Case("vr-unique", ((G2, G2.replace('valueReference="7"', 'valueReference="6"')),)),
    Case("unit", (on_x('unit="m"'),)),
    Case("unit-of-type", (on_x('declaredType="T"'),
                          (DE, '<TypeDefinitions><Float64Type name="T" unit="K"/>'
                               '</TypeDefinitions>' + DE))),
    Case("display-unit", (on_x('unit="m" displayUnit="km"'), (DE, UNITS + DE))),
    Case("display-unit-alias", ((X, X.replace('nominal="1"/>', 'nominal="1" unit="m"><Alias '
                                              'name="xa" displayUnit="km"/></Float64>')),
                                (DE, UNITS + DE))),
    Case("display-unit-without-unit", (on_x('displayUnit="mm"'), (DE, UNITS + DE)),
         bare="display-unit-without-unit"),
    # fmpy's KeyError on the display unit hides its own "unit not defined"; the cause is the unit
    Case("display-unit-of-undefined-unit", (on_x('unit="km" displayUnit="mm"'), (DE, UNITS + DE)),
         bare="unit"),
    Case("name-tab-flat", (('variableNamingConvention="structured"',
                            'variableNamingConvention="flat"'),
                           (G2, G2.replace('name="g2"', 'name="g&#9;2"')))),
    Case("name-lf-cr-flat", (('variableNamingConvention="structured"',
                              'variableNamingConvention="flat"'),
                             (G2, G2.replace('name="g2"', 'name="g&#10;2&#13;"')))),
    Case("name-tab-structured", ((G2, G2.replace('name="g2"', 'name="g&#9;2"')),)),
    Case("name-structured", ((G2, G2.replace('name="g2"', 'name="2g"')),)),
    Case("name-structured-alias", ((X, X.replace('nominal="1"/>', 'nominal="1"><Alias '
                                                 'name="x[]"/></Float64>')),)),
    Case("kind-without-dependencies", ((CSD, CSD.replace(' dependencies="2"', '')),)),
    Case("kind-length", ((IU, IU.replace('"constant"', '"constant constant"')),)),
    Case("outputs", (after(G2, '<Float64 name="v" valueReference="8" causality="output"/>'),
                     (IU, IU + '<InitialUnknown valueReference="8"/>'))),
    Case("derivative-attribute", ((CSD, CSD.replace('valueReference="3"',
                                                    'valueReference="6"')),)),
    Case("initial-unknowns", ((IU, ''),)),
    Case("structure-vr", ((IU, IU.replace('valueReference="3"', 'valueReference="99"')),),
         bare="structure-vr"),
    Case("dependency-vr", ((CSD, CSD.replace('dependencies="2"', 'dependencies="99"')),),
         bare="structure-vr"),
    Case("dimension-vr", (after(G2, '<Float64 name="a" valueReference="8"><Dimension '
                                    'valueReference="99"/></Float64>'),), bare="dimension"),
    Case("dimension-target", (after(G2, '<UInt64 name="n" valueReference="9" '
                                        'variability="discrete"/><Float64 name="a" '
                                        'valueReference="8"><Dimension valueReference="9"/>'
                                        '</Float64>'),), bare="dimension"),
    Case("dimension-no-start", (after(G2, '<UInt64 name="n" valueReference="9" '
                                          'causality="structuralParameter" variability="fixed"/>'
                                          '<Float64 name="a" valueReference="8"><Dimension '
                                          'valueReference="9"/></Float64>'),),
         bare="dimension-size-without-start"),
    Case("clocks-vr", (after(G2, '<Float64 name="s" valueReference="8" variability="discrete" '
                                 'clocks="99"/>'),), bare="clocks-vr"),
    Case("build-description", extra={"sources/buildDescription.xml":
                                     BUILD.replace('<SourceFile name="model.c"/>', '<Bogus/>')}),
    Case("build-description-version", extra={"sources/buildDescription.xml":
                                             BUILD.replace('"3.0"', '"2.0"')}),
]


def build(case: Case, dest: Path) -> Path:
    texts = {name: path.read_text(encoding="utf-8") for name, path in scene_xml("HelloWorldDAE").items()}
    md = texts[MODEL_DESCRIPTION]
    for old, new in case.edits:
        assert md.count(old) == 1, f"{case.id}: {old!r} occurs {md.count(old)} times"
        md = md.replace(old, new)
    fmu = dest / f"{case.id}.fmu"
    with zipfile.ZipFile(fmu, "w") as zf:
        zf.writestr(MODEL_DESCRIPTION, md)
        zf.writestr(MANIFEST, texts[MANIFEST])
        for name, text in case.extra.items():
            zf.writestr(name, text)
    return fmu


def classify(message: str, case: Case) -> str | None:
    """The fmpy problem class of one message (None: a message this table does not know)."""
    if _BARE.match(message):
        return case.bare
    for key, (pattern, _) in FMPY_CLASSES.items():
        if pattern and re.search(pattern, message, re.DOTALL):
            if key == "name-structured" and re.match(r'^"[^"]*[\t\r\n]', message):
                return "name-structured-character"
            return key
    return None


def lsdae_codes(fmu: Path) -> set[str]:
    report = check_fmu(fmu, options=EngineOptions(probes=False))
    return {f.code for f in report.findings if f.severity.name.lower() in ("warning", "error")}


def test_the_clean_scene_is_clean_for_both(tmp_path):
    fmu = build(Case("clean"), tmp_path)
    assert validate_fmu(str(fmu)) == []
    assert lsdae_codes(fmu) == set()


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_lsdae_reports_what_fmpy_reports(case, tmp_path):
    fmu = build(case, tmp_path)
    problems = validate_fmu(str(fmu))
    assert problems, f"{case.id}: fmpy finds nothing wrong, so this case tests nothing"
    found = lsdae_codes(fmu)
    unknown = [p for p in problems if classify(p, case) is None]
    assert not unknown, f"fmpy messages this test does not map to an lsdae rule: {unknown}"
    missed = []
    for problem in problems:
        key = classify(problem, case)
        covering = FMPY_CLASSES[key][1]
        if not found & set(covering):
            missed.append(f"{key} ({' or '.join(covering)}): {problem}")
    assert not missed, ("fmpy reports problems that lsdae does not:\n  " + "\n  ".join(missed)
                        + f"\nlsdae found: {sorted(found)}")


def test_every_fmpy_class_has_a_case(tmp_path):
    seen = set()
    for case in CASES:
        fmu = build(case, tmp_path)
        seen.update(classify(p, case) for p in validate_fmu(str(fmu)))
    assert set(FMPY_CLASSES) - seen == set()
