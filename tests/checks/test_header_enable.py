"""Unit tests of the manifest-header and enable-parameter checks (DAE1xx, DAE2xx)."""
from __future__ import annotations

import pytest
from lxml import etree

from conformance.checks import enable, header
from conformance.checks.context import CheckContext
from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import read_model_description

NS = 'xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"'
NAME = 'fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"'
VERSION = 'fmi-ls:fmi-ls-version="1.0.0-alpha.1"'
DESCRIPTION = 'fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI."'
ENABLE = '<EnableDAEParameter valueReference="1"/>'
BODY = """
  <AlgebraicVariables><AlgebraicVariable valueReference="4"/></AlgebraicVariables>
  <ModelStructure>
    <Residual valueReference="6" dependencies="2 4" dependenciesKind="constant constant"/>
  </ModelStructure>"""

DAE_VAR = ('<Boolean name="dae" valueReference="1" causality="structuralParameter" '
           'variability="fixed" start="false"/>')


def alpha1(*, name: str = NAME, version: str = VERSION, description: str = DESCRIPTION,
           enable_xml: str = ENABLE, root_attrs: str = "") -> str:
    return (f"<fmiDAEManifest {NS} {name} {version} {description} {root_attrs}>\n"
            f"  {enable_xml}{BODY}\n</fmiDAEManifest>")


def formulation(*, version: str = 'fmi-ls:fmi-ls-version="0.1"', enable_xml: str = "",
                root_attrs: str = "") -> str:
    return (f'<fmiLayeredStandardManifest xmlns="http://fmi-standard.org/fmi-ls-manifest" {NS} '
            f"{NAME} {version} {DESCRIPTION} {root_attrs}>\n  {enable_xml}\n"
            "  <AlgebraicVariables><AlgebraicVariable valueReference=\"4\"/></AlgebraicVariables>"
            "\n  <ModelStructure><Residual><Formulation index=\"1\" valueReference=\"6\"/>"
            "</Residual></ModelStructure>\n</fmiLayeredStandardManifest>")


def model(dae_var: str = DAE_VAR, extra: str = "") -> str:
    return f"""<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="t">
  <ModelExchange modelIdentifier="M"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    {dae_var}
    <Float64 name="x" valueReference="2" start="1"/>
    <Float64 name="der(x)" valueReference="3" derivative="2"/>
    <Float64 name="y" valueReference="4"/>
    <Float64 name="g1" valueReference="6"/>
    {extra}
  </ModelVariables>
</fmiModelDescription>"""


def ctx(manifest: str | None = None, md: str | None = None, *, draft: str = "alpha1",
        names: tuple[str, ...] = ()) -> CheckContext:
    man = None
    if manifest is not None:
        man = read_manifest(etree.ElementTree(etree.fromstring(manifest)), draft=draft)
    mdl = read_model_description(etree.ElementTree(etree.fromstring(md or model())))
    return CheckContext(model=mdl, manifest=man, draft=draft, names=names)


def run(check, context: CheckContext) -> list:
    return list(check(context))


# ---------------------------------------------------------------------------- catalogue
def test_codes_are_in_our_ranges():
    assert set(header.CHECKS) == {"DAE101", "DAE102", "DAE103", "DAE104"}
    assert set(enable.CHECKS) == {f"DAE20{i}" for i in range(1, 9)}


def test_catalogue_names_match_functions():
    from conformance.report.catalogue import load_catalogue
    cat = load_catalogue()
    for code, fn in {**header.CHECKS, **enable.CHECKS}.items():
        assert cat[code].name.replace("-", "_") == fn.__name__
        assert cat[code].stage == "static"


def test_a_clean_alpha1_manifest_passes_every_rule():
    context = ctx(alpha1(), names=("modelDescription.xml", MANIFEST))
    for check in (*header.CHECKS.values(), *enable.CHECKS.values()):
        assert run(check, context) == [], check.__name__


def test_a_clean_formulation_manifest_passes_the_header_rules():
    context = ctx(formulation(enable_xml='<EnableDAE valueReference="1"/>'), draft="formulation")
    for check in (*header.CHECKS.values(), *enable.CHECKS.values()):
        assert run(check, context) == [], check.__name__


# ---------------------------------------------------------------------------- DAE101
@pytest.mark.parametrize("name", [
    "extra/fmi-ls-dae/fmi-ls-manifest.xml",
    "fmi-ls-manifest.xml",
    "extra/DAE/fmi-ls-manifest.xml",
    "extra/org.fmi-standard.fmi-ls-dae/FMI-LS-MANIFEST.xml",
    "Extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml",
    "extra/com.vendor.FmiLsDae/fmi-ls-manifest.xml",
])
def test_manifest_location_fires_on_misplaced_dae_manifest(name):
    context = CheckContext(model=None, manifest=None, draft=None,
                           names=("modelDescription.xml", name))
    found = run(header.manifest_location, context)
    assert len(found) == 1
    assert found[0].subject == name and found[0].location.file == name
    assert dict(found[0].evidence)["expected"] == MANIFEST


@pytest.mark.parametrize("names", [
    ("modelDescription.xml", MANIFEST),
    ("modelDescription.xml", MANIFEST, "extra/fmi-ls-dae/fmi-ls-manifest.xml"),
    ("modelDescription.xml", "extra/org.fmi-standard.fmi-ls-struct/fmi-ls-manifest.xml"),
    ("modelDescription.xml", "extra/com.vendor.daemon/fmi-ls-manifest.xml"),
    ("modelDescription.xml", "X/fmi-ls-manifest.xml"),   # a folder of one letter, not ours
    ("modelDescription.xml", "extra/fmi-ls-dae/readme.txt"),
    ("modelDescription.xml",),
])
def test_manifest_location_is_silent(names):
    context = CheckContext(model=None, manifest=None, draft=None, names=names)
    assert run(header.manifest_location, context) == []


# ---------------------------------------------------------------------------- DAE102
@pytest.mark.parametrize("attr,actual", [
    ('fmi-ls:fmi-ls-name="fmi-ls-dae"', "fmi-ls-dae"),
    ('fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae "', "org.fmi-standard.fmi-ls-dae "),
    ('fmi-ls:fmi-ls-name=""', ""),
])
def test_ls_name_wrong_value(attr, actual):
    found = run(header.ls_name_mismatch, ctx(alpha1(name=attr)))
    assert len(found) == 1
    ev = dict(found[0].evidence)
    assert ev["actual"] == actual and ev["expected"] == "org.fmi-standard.fmi-ls-dae"
    assert found[0].location.line == 1 and found[0].location.file == MANIFEST
    assert found[0].location.path == "/fmiDAEManifest/@fmi-ls:fmi-ls-name"


def test_ls_name_missing_and_unqualified():
    missing = run(header.ls_name_mismatch, ctx(alpha1(name="")))
    assert len(missing) == 1 and missing[0].subject == "fmi-ls-name"
    assert "qualified" not in dict(missing[0].evidence)
    unq = run(header.ls_name_mismatch,
              ctx(alpha1(name='fmi-ls-name="org.fmi-standard.fmi-ls-dae"')))
    assert len(unq) == 1 and dict(unq[0].evidence)["qualified"] is False


def test_header_rules_leave_other_attributes_alone():
    context = ctx(alpha1(name='fmi-ls-name="org.fmi-standard.fmi-ls-dae"'))
    assert run(header.ls_version_invalid, context) == []
    assert run(header.ls_description_mismatch, context) == []


# ---------------------------------------------------------------------------- DAE103
@pytest.mark.parametrize("version", ["1.0.0-alpha.1", "1.0.0-alpha.2", "1.0.0", "1.2.3+build.4",
                                     "1.0.0-beta"])
def test_ls_version_accepted_on_alpha1(version):
    context = ctx(alpha1(version=f'fmi-ls:fmi-ls-version="{version}"'))
    assert run(header.ls_version_invalid, context) == []


@pytest.mark.parametrize("version,reason", [
    ("0.1", "older than shape"), ("1.0", "not semver"), ("v1.0.0", "not semver"),
    ("0.1-beta", "older than shape"), ("1.0.0 alpha.1", "not semver"),
    ("0.1.0", "older than shape"), ("0.0.1", "older than shape"),
    ("1.0.0-alpha", "older than shape"), ("1.0.0-alpha.0", "older than shape"),
])
def test_ls_version_rejected_on_alpha1(version, reason):
    found = run(header.ls_version_invalid,
                ctx(alpha1(version=f'fmi-ls:fmi-ls-version="{version}"')))
    assert len(found) == 1
    ev = dict(found[0].evidence)
    assert ev["reason"] == reason and ev["actual"] == version


@pytest.mark.parametrize("version", ["0.1", "0.0.1", "0.1.0", "1.0.0-alpha.1"])
def test_ls_version_accepted_on_legacy(version):
    context = ctx(formulation(version=f'fmi-ls:fmi-ls-version="{version}"'), draft="formulation")
    assert run(header.ls_version_invalid, context) == []


@pytest.mark.parametrize("version", ["", "  ", "draft", "1.0.0.0", "one"])
def test_ls_version_rejected_on_legacy(version):
    context = ctx(formulation(version=f'fmi-ls:fmi-ls-version="{version}"'), draft="formulation")
    assert len(run(header.ls_version_invalid, context)) == 1


def test_ls_version_missing_and_unqualified():
    assert len(run(header.ls_version_invalid, ctx(alpha1(version="")))) == 1
    unq = run(header.ls_version_invalid, ctx(alpha1(version='fmi-ls-version="1.0.0-alpha.1"')))
    assert len(unq) == 1 and dict(unq[0].evidence)["qualified"] is False


# ---------------------------------------------------------------------------- DAE104
@pytest.mark.parametrize("text,difference", [
    ("Layered standard for DAE support in FMI", "the final period is missing"),
    ("Layered standard for DAE support in FMU", 'says "FMU" where the text says "FMI"'),
    ("layered standard for DAE support in FMI.", "different letter case"),
    ("Layered standard for DAE support in FMI. ", "leading or trailing whitespace"),
    ("Layered standard for  DAE support in FMI.", "different whitespace"),
    ("", "empty"),
    ("DAE", "different text"),
])
def test_ls_description_mismatch(text, difference):
    found = run(header.ls_description_mismatch,
                ctx(alpha1(description=f'fmi-ls:fmi-ls-description="{text}"')))
    assert len(found) == 1
    ev = dict(found[0].evidence)
    assert ev["difference"] == difference and ev["actual"] == text
    assert found[0].subject == "fmi-ls-description"
    assert (found[0].location.line, found[0].location.path) == (
        1, "/fmiDAEManifest/@fmi-ls:fmi-ls-description")


def test_ls_description_missing_and_unqualified():
    [missing] = run(header.ls_description_mismatch, ctx(alpha1(description="")))
    assert (missing.subject, missing.part) == ("fmi-ls-description", "missing-or-unqualified")
    assert (missing.location.file, missing.location.line, missing.location.path) == (
        MANIFEST, 1, "/fmiDAEManifest/@fmi-ls:fmi-ls-description")
    assert dict(missing.evidence) == {"attribute": "fmi-ls-description",
                                      "expected": "Layered standard for DAE support in FMI."}
    unq = run(header.ls_description_mismatch, ctx(alpha1(
        description='fmi-ls-description="Layered standard for DAE support in FMI."')))
    assert len(unq) == 1 and dict(unq[0].evidence)["qualified"] is False


# ---------------------------------------------------------------------------- enable rules
ENABLE_RULES = tuple(enable.CHECKS.values())


def fired(context: CheckContext) -> dict[str, list]:
    out = {}
    for code, check in enable.CHECKS.items():
        found = run(check, context)
        if found:
            out[code] = found
    return out


def test_missing_enable_fires_only_missing():
    result = fired(ctx(alpha1(enable_xml="")))
    assert set(result) == {"DAE201"}
    assert result["DAE201"][0].location.line == 1


def test_missing_enable_on_legacy_drafts():
    assert set(fired(ctx(formulation(), draft="formulation"))) == {"DAE201"}


@pytest.mark.parametrize("enable_xml,root_attrs,subject,evidence", [
    ('<EnableDAEParameter valueReference="99"/>', "", "99",
     {"element": "EnableDAEParameter", "value_reference": 99}),
    ('<EnableDAEParameter valueReference="x1"/>', "", "x1",
     {"element": "EnableDAEParameter", "value_reference": "x1"}),
    ('<EnableDAEParameter valueReference="-1"/>', "", "-1",
     {"element": "EnableDAEParameter", "value_reference": "-1"}),
    ("<EnableDAEParameter/>", "", "EnableDAEParameter", {"element": "EnableDAEParameter"}),
])
def test_unknown_vr(enable_xml, root_attrs, subject, evidence):
    result = fired(ctx(alpha1(enable_xml=enable_xml, root_attrs=root_attrs)))
    assert set(result) == {"DAE202"}
    assert result["DAE202"][0].subject == subject
    assert result["DAE202"][0].location.line == 2
    assert dict(result["DAE202"][0].evidence) == evidence


def test_enable_by_name_resolves_or_not():
    good = ctx(formulation(root_attrs='enableDAEModeVariable="dae"'), draft="formulation")
    assert fired(good) == {}
    bad = ctx(formulation(root_attrs='enableDAEModeVariable="ODE_DAE_Switch"'),
              draft="formulation")
    result = fired(bad)
    assert set(result) == {"DAE202"}
    assert result["DAE202"][0].subject == "ODE_DAE_Switch"
    by_vr = ctx(formulation(root_attrs='enableDAEModeVariable="1"'), draft="formulation")
    assert fired(by_vr) == {}


def _var(**attrs: str) -> str:
    base = {"name": "dae", "valueReference": "1", "causality": "structuralParameter",
            "variability": "fixed", "start": "false"}
    base.update(attrs)
    tag = base.pop("type", "Boolean")
    body = base.pop("body", "")
    text = " ".join(f'{k}="{v}"' for k, v in base.items() if v is not None and v != "-")
    return f"<{tag} {text}>{body}</{tag}>"


@pytest.mark.parametrize("var,code", [
    (_var(type="Int32", start="0"), "DAE203"),
    (_var(type="UInt64", start="0"), "DAE203"),
    (_var(causality="parameter"), "DAE204"),
    (_var(causality="-", variability="-"), "DAE204"),   # a local with default variability
    (_var(causality="input", variability="-"), "DAE204"),
    (_var(variability="discrete"), "DAE205"),
    (_var(variability="constant"), "DAE205"),
    (_var(start="true"), "DAE206"),
    (_var(start="1"), "DAE206"),
    (_var(start="-"), "DAE206"),
    (_var(body='<Dimension start="2"/>'), "DAE207"),
])
def test_each_variable_fault_fires_exactly_its_rule(var, code):
    result = fired(ctx(alpha1(), model(dae_var=var)))
    assert set(result) == {code}
    (violation,) = result[code]
    assert violation.subject == "dae"
    assert violation.location.file == "modelDescription.xml"
    assert dict(violation.evidence)["value_reference"] == 1


@pytest.mark.parametrize("var", [
    _var(variability="tunable"), _var(start="0"), _var(variability="-"), _var(start=" false "),
])
def test_near_misses_pass(var):
    assert fired(ctx(alpha1(), model(dae_var=var))) == {}


def test_variable_location_points_at_the_variable():
    (violation,) = run(enable.enable_parameter_start_not_false,
                       ctx(alpha1(), model(dae_var=_var(start="true"))))
    assert violation.location.line == 5
    assert violation.location.path == "/fmiModelDescription/ModelVariables/Boolean[@name='dae']"


def test_referenced_by_dimension():
    extra = ('<Float64 name="a" valueReference="8"><Dimension valueReference="1"/></Float64>\n'
             '    <Float64 name="b" valueReference="9"><Dimension valueReference="1"/></Float64>')
    result = fired(ctx(alpha1(), model(extra=extra)))
    assert set(result) == {"DAE207"}
    (violation,) = result["DAE207"]
    assert violation.subject == "dae"
    assert dict(violation.evidence)["referenced_by"] == ("a", "b")
    assert violation.location.path.endswith("Float64[@name='a']")


def test_wrong_type_does_not_also_report_start():
    var = _var(type="Float64", start="1.0")
    assert set(fired(ctx(alpha1(), model(dae_var=var)))) == {"DAE203"}


def test_several_faults_give_several_findings():
    var = _var(type="Int32", causality="parameter", start="0")
    assert set(fired(ctx(alpha1(), model(dae_var=var)))) == {"DAE203", "DAE204"}


def test_duplicate_enable_elements():
    two = ENABLE + '\n  <EnableDAEParameter valueReference="1"/>'
    result = fired(ctx(alpha1(enable_xml=two)))
    assert set(result) == {"DAE208"}
    (violation,) = result["DAE208"]
    assert violation.location.line == 3
    assert dict(violation.evidence) == {
        "element": "EnableDAEParameter", "value_reference": 1,
        "first_element": "EnableDAEParameter", "first_value_reference": 1, "count": 2}


def test_duplicate_is_legacy_only_when_neither_the_manifest_nor_the_run_is_alpha1():
    # a manifest of an older draft checked as alpha.1 (--draft): the duplicate is the rule's
    # own case, not the legacy element-plus-attribute part
    legacy = formulation(enable_xml='<EnableDAE valueReference="1"/>',
                         root_attrs='enableDAEModeVariable="dae"')
    manifest = read_manifest(etree.ElementTree(etree.fromstring(legacy)), draft="formulation")
    model_ = read_model_description(etree.ElementTree(etree.fromstring(model())))
    as_alpha1 = CheckContext(model=model_, manifest=manifest, draft="alpha1")
    assert [v.part for v in run(enable.enable_parameter_duplicate, as_alpha1)] == [None]
    as_legacy = CheckContext(model=model_, manifest=manifest, draft="formulation")
    assert [v.part for v in run(enable.enable_parameter_duplicate, as_legacy)] == [
        "legacy-element-plus-attribute"]


def test_duplicate_evidence_names_a_reference_that_is_not_an_integer():
    two = '<EnableDAEParameter valueReference="x"/>\n  ' + ENABLE
    (violation,) = run(enable.enable_parameter_duplicate, ctx(alpha1(enable_xml=two)))
    assert dict(violation.evidence) == {
        "element": "EnableDAEParameter", "value_reference": 1,
        "first_element": "EnableDAEParameter", "first_value_reference": "x", "count": 2}


def test_element_plus_root_attribute_is_a_duplicate():
    context = ctx(formulation(enable_xml='<EnableDAE valueReference="1"/>',
                              root_attrs='enableDAEModeVariable="dae"'), draft="formulation")
    result = fired(context)
    assert set(result) == {"DAE208"}
    assert result["DAE208"][0].subject == "@enableDAEModeVariable"


def test_duplicates_pointing_at_different_bad_variables_report_each():
    two = ENABLE + '\n  <EnableDAEParameter valueReference="4"/>'
    result = fired(ctx(alpha1(enable_xml=two)))
    # the second points at the Float64 algebraic variable y
    assert set(result) == {"DAE208", "DAE203", "DAE204"}
    assert [v.subject for v in result["DAE203"]] == ["y"]


def test_duplicates_pointing_at_one_bad_variable_report_it_once():
    two = '<EnableDAEParameter valueReference="4"/>\n  <EnableDAEParameter valueReference="4"/>'
    result = fired(ctx(alpha1(enable_xml=two)))
    assert [v.subject for v in result["DAE203"]] == ["y"]
    assert [v.subject for v in result["DAE204"]] == ["y"]


def test_version_unknown_needs_a_version_and_points_at_it():
    from conformance.checks import newer_drafts
    assert run(newer_drafts.ls_version_unknown, ctx(alpha1(version=""))) == []
    # the minor version counts: 1.2.0-alpha.1 comes after 1.0.0-alpha.1
    [v] = run(newer_drafts.ls_version_unknown,
              ctx(alpha1(version='fmi-ls:fmi-ls-version="1.2.0-alpha.1"')))
    assert v.subject == "1.2.0-alpha.1"
    assert run(newer_drafts.ls_version_unknown,
               ctx(alpha1(version='fmi-ls:fmi-ls-version="1.0.0-alpha.1"'))) == []
    [v] = run(newer_drafts.ls_version_unknown,
              ctx(alpha1(version='fmi-ls:fmi-ls-version="1.0.0"')))
    assert (v.subject, v.location.file, v.location.line, v.location.path) == (
        "1.0.0", MANIFEST, 1, "/fmiDAEManifest/@fmi-ls:fmi-ls-version")


def test_enable_reference_is_not_judged_without_a_model():
    # modelDescription.xml unreadable: nothing to resolve the reference against
    man = read_manifest(etree.ElementTree(etree.fromstring(alpha1())), draft="alpha1")
    assert run(enable.enable_parameter_unknown_vr,
               CheckContext(model=None, manifest=man, draft="alpha1")) == []


def test_no_manifest_or_model_means_no_findings():
    empty = CheckContext(model=None, manifest=None, draft=None)
    for check in (header.ls_name_mismatch, header.ls_version_invalid,
                  header.ls_description_mismatch, *ENABLE_RULES):
        assert run(check, empty) == []


# ---------------------------------------------------------------------------- parts
# A sub-check whose basis differs from the rule's carries its part ([[rule.parts]]); the rule's
# own case carries none.
def test_header_parts():
    for check in (header.ls_name_mismatch, header.ls_version_invalid,
                  header.ls_description_mismatch):
        for context in (ctx(alpha1(name="", version="", description="")),
                        ctx(alpha1(name='fmi-ls-name="org.fmi-standard.fmi-ls-dae"',
                                   version='fmi-ls-version="1.0.0-alpha.1"',
                                   description='fmi-ls-description="x"'))):
            assert [v.part for v in run(check, context)] == ["missing-or-unqualified"]
    wrong_name = 'fmi-ls:fmi-ls-name="fmi-ls-dae"'
    assert [v.part for v in run(header.ls_name_mismatch, ctx(alpha1(name=wrong_name)))] == [None]
    legacy_name = formulation().replace(NAME, wrong_name)
    assert [v.part for v in run(header.ls_name_mismatch,
                                ctx(legacy_name, draft="formulation"))] == ["legacy-shape-name"]
    for version, part in (("draft", "legacy-not-version-like"), ("", None)):
        context = ctx(formulation(version=f'fmi-ls:fmi-ls-version="{version}"'),
                      draft="formulation")
        assert [v.part for v in run(header.ls_version_invalid, context)] == [part]
    assert [v.part for v in run(header.ls_version_invalid, ctx(alpha1(
        version='fmi-ls:fmi-ls-version="0.1"')))] == [None]
    legacy_text = formulation().replace(DESCRIPTION, 'fmi-ls:fmi-ls-description="DAE"')
    assert [v.part for v in run(header.ls_description_mismatch,
                                ctx(legacy_text, draft="formulation"))] == ["legacy-shape-text"]
    assert [v.part for v in run(header.ls_description_mismatch, ctx(alpha1(
        description='fmi-ls:fmi-ls-description="DAE"')))] == [None]


def test_header_cause_is_the_legacy_shape_and_only_there():
    # the legacy shape's findings share one cause (they fold into one defect, run/causes.py);
    # the same wrong name on the alpha.1 shape is a defect of its own
    from conformance.model.drafts.migrate import LEGACY_SHAPE_CAUSE
    wrong_name = 'fmi-ls:fmi-ls-name="fmi-ls-dae"'
    assert [v.cause for v in run(header.ls_name_mismatch, ctx(alpha1(name=wrong_name)))] == [None]
    legacy_name = formulation().replace(NAME, wrong_name)
    assert [v.cause for v in run(header.ls_name_mismatch, ctx(legacy_name, draft="formulation"))
            ] == [LEGACY_SHAPE_CAUSE]
    legacy_text = formulation().replace(DESCRIPTION, 'fmi-ls:fmi-ls-description="DAE"')
    assert [v.cause for v in run(header.ls_description_mismatch,
                                 ctx(legacy_text, draft="formulation"))] == [LEGACY_SHAPE_CAUSE]
    assert [v.cause for v in run(header.ls_description_mismatch, ctx(alpha1(
        description='fmi-ls:fmi-ls-description="DAE"')))] == [None]


def test_legacy_version_that_is_no_version_number():
    from conformance.model.drafts.migrate import LEGACY_SHAPE_CAUSE
    [v] = run(header.ls_version_invalid,
              ctx(formulation(version='fmi-ls:fmi-ls-version="draft"'), draft="formulation"))
    assert (v.subject, v.part, v.cause) == (
        "fmi-ls-version", "legacy-not-version-like", LEGACY_SHAPE_CAUSE)
    assert dict(v.evidence) == {"actual": "draft", "expected": "1.0.0-alpha.1",
                                "reason": "not a version"}


@pytest.mark.parametrize("enable_xml,part", [
    ('<EnableDAEParameter valueReference="99"/>', None),
    ('<EnableDAEParameter valueReference="x1"/>', "missing-or-not-integer"),
    ("<EnableDAEParameter/>", "missing-or-not-integer"),
])
def test_unknown_vr_parts(enable_xml, part):
    found = run(enable.enable_parameter_unknown_vr, ctx(alpha1(enable_xml=enable_xml)))
    assert [v.part for v in found] == [part]


def test_enable_parts():
    by_name = ctx(formulation(root_attrs='enableDAEModeVariable="ODE_DAE_Switch"'),
                  draft="formulation")
    assert [v.part for v in run(enable.enable_parameter_unknown_vr, by_name)] == \
        ["legacy-name-reference"]
    for start, part in (("-", "start-missing"), ("true", None)):
        found = run(enable.enable_parameter_start_not_false,
                    ctx(alpha1(), model(dae_var=_var(start=start))))
        assert [v.part for v in found] == [part]
    extra = '<Float64 name="a" valueReference="8"><Dimension valueReference="1"/></Float64>'
    assert [v.part for v in run(enable.enable_parameter_not_scalar,
                                ctx(alpha1(), model(extra=extra)))] == ["referenced-by-dimension"]
    assert [v.part for v in run(enable.enable_parameter_not_scalar, ctx(alpha1(), model(
        dae_var=_var(body='<Dimension start="2"/>'))))] == [None]
    two = ENABLE + '\n  <EnableDAEParameter valueReference="1"/>'
    assert [v.part for v in run(enable.enable_parameter_duplicate,
                                ctx(alpha1(enable_xml=two)))] == [None]
    legacy = ctx(formulation(enable_xml='<EnableDAE valueReference="1"/>',
                             root_attrs='enableDAEModeVariable="dae"'), draft="formulation")
    assert [v.part for v in run(enable.enable_parameter_duplicate, legacy)] == \
        ["legacy-element-plus-attribute"]
