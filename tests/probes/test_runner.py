"""The probe runner: what is probed and what is skipped, isolation, limits, determinism."""
from __future__ import annotations

import dataclasses
import re
import importlib
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conformance.report.catalogue import Catalogue, default_catalogue
from conformance.run.engine import EngineOptions, check_fmu, check_paths
from conformance.report.findings import Severity, thaw
from conformance.model.manifest import MANIFEST
from conformance.probes.machinery import driver, registry, runner
from conformance.probes.instruments.api import Point
from conformance.probes.machinery.registry import PROBES
from conformance.probes.instruments.sampling import near_points, start_point
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.layout import Layout
from tests.checkkit import checked
from tests.fixtures import FORMULATION_MANIFEST, build_scene, variant

CATALOGUE = default_catalogue()
PROBE_CODES = {r.code for r in CATALOGUE if r.stage == "probe"}


def _probe_findings(report):
    return [f for f in report.findings if f.code in PROBE_CODES]


def _probe_skips(report):
    return {c: r for c, r in report.rules_skipped if c in PROBE_CODES}


def _rewrite(src: Path, dest: Path, *, drop=lambda name: False, replace=None) -> Path:
    """A copy of the FMU ``src`` without the members ``drop`` selects, some replaced."""
    replace = replace or {}
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dest, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            if drop(info.filename):
                continue
            zout.writestr(info, replace.get(info.filename, zin.read(info)))
    return dest


def _catalogue(**options) -> Catalogue:
    """The default catalogue with some options of the runner rules changed.

    A runner rule the catalogue does not name (renamed?) or an option no runner rule has (a
    typo) fails here instead of leaving the limits at their defaults.
    """
    unknown = sorted(set(runner.RUNNER_RULES) - {rule.name for rule in CATALOGUE})
    assert unknown == [], f"runner rules missing from the catalogue: {unknown}"
    known = {k for rule in CATALOGUE if rule.name in runner.RUNNER_RULES for k, _ in rule.options}
    assert set(options) <= known, f"no runner rule has the options {sorted(set(options) - known)}"
    rules = []
    for rule in CATALOGUE:
        if rule.name in runner.RUNNER_RULES:
            opts = dict(rule.options)
            opts.update({k: v for k, v in options.items() if k in opts})
            rule = dataclasses.replace(rule, options=tuple(sorted(opts.items())))
        rules.append(rule)
    return Catalogue(rules)


# ------------------------------------------------------------------------ catalogue

def test_probe_registry_matches_probe_catalogue():
    emitted_by_runner = {CATALOGUE[n].code for n in runner.RUNNER_RULES}
    assert set(PROBES) - PROBE_CODES == set(), "probes without a probe-stage catalogue entry"
    assert PROBE_CODES - set(PROBES) - emitted_by_runner == set(), "probe rules nobody runs"
    assert set(PROBES) & emitted_by_runner == set()


@pytest.mark.parametrize("home", sorted(set(registry.MODULE_OF.values())))
def test_each_module_holds_exactly_the_codes_the_registry_names(home):
    family, name = home.split(".")
    module = importlib.import_module(f"conformance.probes.{home}")
    assert sorted(module.PROBES) == sorted(registry.MODULES[family][name])
    assert all(PROBES[code] is module.PROBES[code] for code in module.PROBES)
    assert all(registry.FAMILY_OF[code] == family for code in module.PROBES)


def test_no_other_module_of_a_family_holds_probes():
    """A probe is found only where the registry looks: no family module holds a PROBES dict
    the registry does not name."""
    root = Path(importlib.import_module("conformance.probes").__file__).parent
    for family in registry.MODULES:
        holders = {p.stem for p in (root / family).glob("*.py")
                   if re.search(r"^PROBES\b", p.read_text(encoding="utf-8"), re.M)}
        assert holders == set(registry.MODULES[family]), family


def test_no_code_is_in_two_families():
    codes = [code for family in registry.FAMILIES.values() for code in family]
    assert len(codes) == len(set(codes)) == len(PROBES)
    modules = [code for m in registry.MODULES.values() for codes in m.values() for code in codes]
    assert sorted(modules) == sorted(codes)


def test_limits_come_from_the_catalogue():
    rules = {n: CATALOGUE[n] for n in runner.RUNNER_RULES}
    limits = runner.Limits.from_rules(rules)
    options = {k: v for r in rules.values() for k, v in r.option_values.items()}
    assert dataclasses.asdict(limits) == {k: options[k] for k in dataclasses.asdict(limits)}
    assert limits.probe_seconds > 0 and limits.fmu_seconds >= limits.probe_seconds


# ------------------------------------------------------------------- what is probed

def test_no_binary_for_this_platform_skips_every_probe(tmp_path):
    fmu = _rewrite(build_scene("HelloWorldDAE"), tmp_path / "nobinary.fmu",
                   drop=lambda n: n.startswith("binaries/"))
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    skips = _probe_skips(report)
    assert set(skips) == PROBE_CODES
    assert set(skips.values()) == {f"no binary for {runner.host_platform_tuple()}"}
    assert _probe_findings(report) == []


def test_no_probes_option_skips_with_its_own_reason():
    report = check_fmu(build_scene("Robertson"), options=EngineOptions(probes=False))
    assert set(_probe_skips(report).values()) == {"probes turned off (--no-probes)"}


MANIFEST_PROBES = {r.code for r in CATALOGUE if r.stage == "probe" and "manifest" in r.needs}
ODE_PROBES = PROBE_CODES - MANIFEST_PROBES     # the ODE-mode contract of any ME FMU


def test_the_ode_contract_rules_need_no_manifest():
    assert {CATALOGUE[n].code for n in runner.RUNNER_RULES} <= ODE_PROBES
    for name in ("directional-derivative-mismatch", "adjoint-derivative-mismatch",
                 "dependency-undeclared", "dependency-never-observed",
                 "dependencies-kind-violated", "initial-dependency-undeclared",
                 "initial-dependencies-kind-violated",
                 "initial-directional-derivative-mismatch", "start-value-not-applied"):
        assert CATALOGUE[name].code in ODE_PROBES, name


def test_unparseable_manifest_leaves_ode_mode_to_probe():
    fmu = variant("HelloWorldDAE", manifest_edits=[("<ModelStructure>", "<ModelStructure")])
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    skips = _probe_skips(report)
    assert set(skips) == MANIFEST_PROBES
    assert all("manifest" in r for r in skips.values())
    assert "nothing to check or probe" in dict(report.info)["manifest"]
    assert ODE_PROBES - {CATALOGUE[n].code for n in runner.RUNNER_RULES} <= set(
        report.rules_run) | set(skips) | {c for c, _ in report.rules_not_run}
    modes = dict(dict(report.info)["modes"])
    assert modes["ODE mode"] == "probed" and modes["DAE mode"].startswith("not probed")
    assert _probe_findings(report) == []


def test_fmu_without_manifest_is_probed_in_ode_mode(tmp_path):
    fmu = _rewrite(build_scene("HelloWorldDAE"), tmp_path / "plain.fmu",
                   drop=lambda n: n == MANIFEST)
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    assert set(_probe_skips(report)) - ODE_PROBES == MANIFEST_PROBES
    assert {"DAE742", "DAE750", "DAE713"} <= set(report.rules_run)
    assert report.binary_not_checked is None
    assert _probe_findings(report) == []


def test_fmu_without_manifest_and_no_probes_says_the_binary_was_not_checked(tmp_path):
    fmu = _rewrite(build_scene("HelloWorldDAE"), tmp_path / "plain.fmu",
                   drop=lambda n: n == MANIFEST)
    report = check_fmu(fmu, options=EngineOptions(probes=False))
    assert "--no-probes" in (report.binary_not_checked or "")
    assert set(_probe_skips(report)) == PROBE_CODES


def test_dae_only_fmu_is_probed_in_dae_mode_after_the_static_error():
    fmu = variant("HelloWorldDAE", defines=["DEFECT_DAE_ONLY"],
                  manifest_edits=[('<EnableDAEParameter valueReference="1"/>', "")])
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    assert "DAE201" in {f.code for f in report.findings}  # enable-parameter-missing (static)
    # the variable 'dae' still declares start="false", and the binary holds true: the start
    # check names it, and no probe of DAE mode finds anything
    assert [(f.name, f.subject) for f in _probe_findings(report)] == [
        ("start-value-not-applied", "dae")]
    ran = set(report.rules_run)
    for name in ("algebraic-not-settable", "initial-residual-nonzero", "nan-or-inf",
                 "evaluation-not-repeatable", "enable-handshake"):
        assert CATALOGUE[name].code in ran, name


def test_refused_dae_initialisation_falls_back_to_a_runtime_switch():
    # SimpleDAE's switch is tunable: initialise in ODE mode, switch in Reconfiguration Mode
    report = check_fmu(build_scene("SimpleDAE", defines=["DEFECT_DAE_INIT_REFUSED"]),
                       options=EngineOptions(probes=True))
    (finding,) = _probe_findings(report)
    assert finding.name == "dae-initialization-refused" and finding.severity == Severity.INFO
    assert finding.evidence_dict()["dae_mode_probed"] == "runtime-switch"
    assert _probe_skips(report) == {}


@pytest.mark.parametrize("shape", ["formulation", "by-name"])
def test_legacy_manifest_shapes_are_probed(tmp_path, shape):
    text = FORMULATION_MANIFEST
    if shape == "by-name":  # LS-int SimpleDAE: the switch named in a root attribute
        text = text.replace('  <EnableDAE valueReference="1"/>\n', "").replace(
            "<fmiLayeredStandardManifest\n", '<fmiLayeredStandardManifest enableDAEModeVariable="dae"\n')
    fmu = _rewrite(build_scene("HelloWorldDAE"), tmp_path / f"{shape}.fmu",
                   replace={MANIFEST: text.encode()})
    report = check_fmu(fmu, options=EngineOptions(probes=True, probes_only=True))
    assert _probe_findings(report) == []
    assert _probe_skips(report) == {}
    assert CATALOGUE["initial-residual-nonzero"].code in report.rules_run


# ------------------------------------------------------------------ isolation, limits

def test_one_worker_per_fmu(monkeypatch):
    starts = []
    original = driver.Driver._start

    def counting(self, *args):
        starts.append(1)
        return original(self, *args)

    monkeypatch.setattr(driver.Driver, "_start", counting)
    check_fmu(build_scene("SimpleDAE"), options=EngineOptions(probes=True))
    assert len(starts) == 1


def test_fatal_status_restarts_the_worker_without_a_finding(monkeypatch):
    starts = []
    original = driver.Driver._start

    def counting(self, *args):
        starts.append([r.code for r in self.remaining])
        return original(self, *args)

    monkeypatch.setattr(driver.Driver, "_start", counting)
    fmu = build_scene("HelloWorldDAE", defines=["DEFECT_FATAL_DIRECTIONAL"])
    # illegal-call-accepted's directional calls get fmi3Fatal too: one more restart, left out
    report = check_fmu(fmu, options=EngineOptions(probes=True, select=("DAE7",),
                                                  ignore=("DAE74", "DAE75", "DAE739")))
    nan = CATALOGUE["nan-or-inf"].code
    assert len(starts) == 2 and nan in starts[0] and nan not in starts[1]
    assert not [f for f in report.findings if f.name in runner.RUNNER_RULES]
    assert CATALOGUE["evaluation-failed"].code in report.rules_run


def test_crash_is_a_finding_and_the_next_fmu_is_checked():
    crashing = build_scene("HelloWorldDAE", defines=["DEFECT_SEGFAULT_GETFLOAT64"])
    clean = build_scene("Robertson")
    report = check_paths([crashing, clean], options=EngineOptions(probes=True))
    first, second = report.fmus
    crashed = [f for f in first.findings if f.name == "binary-crashed"]
    assert crashed and all(f.severity == Severity.ERROR for f in crashed)
    ev = crashed[0].evidence_dict()
    assert ev["call"] == "fmi3GetFloat64" and ev["call_in_progress"] is True
    assert ev["exit"] == "killed by SIGSEGV"
    assert not [f for f in second.findings if f.name in runner.RUNNER_RULES]
    assert CATALOGUE["nan-or-inf"].code in second.rules_run


def test_a_crash_in_a_getter_of_several_variables_is_narrowed_to_the_one_that_crashes():
    """DEFECT_SEGFAULT_GETFLOAT64 crashes reading a residual in Continuous-Time Mode; the probes
    read the residuals with other variables. One finding (issue 29): a worker of its own reads
    each variable of the crashing call alone, and its crash names the first residual, the
    probes' crashes listed as the same defect."""
    report = checked(build_scene("HelloWorldDAE", defines=["DEFECT_SEGFAULT_GETFLOAT64"]),
                     options=EngineOptions(probes=True))
    (crash,) = [f for f in report.findings if f.name == "binary-crashed"]
    ev = crash.evidence_dict()
    assert (ev["variables"], ev["value_references"], ev["value_reference_count"]) == (
        ("g1",), (6,), 1)
    assert crash.message.startswith(
        "the binary crashed (killed by SIGSEGV) during fmi3GetFloat64 of 'g1' (valueReference "
        "6), in lsdae's narrowing of the crash (each variable of the call read alone, "
        "Continuous-Time Mode, DAE mode); the same defect in ")
    also = thaw(ev["also"])
    assert also and {a["rule"] for a in also} == {crash.code}
    assert all("during fmi3GetFloat64 of " in a["message"] and "'g1'" in a["message"]
               and "variables (" in a["message"] for a in also)


def test_findings_of_probes_before_a_crash_are_kept():
    # enable-handshake (first) fails on the ODE derivatives; the crash comes later
    fmu = build_scene("HelloWorldDAE", defines=["DEFECT_ODE_DERIVATIVES_FAIL",
                                                "DEFECT_SEGFAULT_GETFLOAT64"])
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    names = {f.name for f in report.findings}
    assert {"enable-handshake", "binary-crashed"} <= names


def test_per_fmu_time_limit_skips_the_rest(tmp_path):
    fmu = build_scene("SimpleDAE", defines=["DEFECT_HANG_DIRECTIONAL"])
    catalogue = _catalogue(probe_seconds=30.0, fmu_seconds=3.0)
    report = check_fmu(fmu, options=EngineOptions(probes=True), catalogue=catalogue)
    timed_out = [f for f in report.findings if f.name == "binary-timed-out"]
    assert len(timed_out) == 1
    ev = timed_out[0].evidence_dict()
    assert ev["limit"] == "per FMU" and ev["call"] == "fmi3GetDirectionalDerivative"
    skips = _probe_skips(report)
    assert skips and all("per-FMU time limit" in r for r in skips.values())


def test_memory_limit_is_an_option():
    fmu = build_scene("HelloWorldDAE", defines=["DEFECT_MEMORY_BLOWUP"])
    report = check_fmu(fmu, options=EngineOptions(probes=True),
                       catalogue=_catalogue(address_space_mib=768))
    found = [f for f in report.findings if f.name == "binary-memory-limit"]
    assert found and found[0].evidence_dict()["limit_mib"] == 768
    assert not [f for f in report.findings if f.name == "binary-crashed"]


def test_a_missing_fmi_function_is_not_loadable():
    report = check_fmu(build_scene("Robertson", defines=["DEFECT_MISSING_EXPORT"]),
                       options=EngineOptions(probes=True))
    (finding,) = _probe_findings(report)
    assert finding.name == "binary-not-loadable"
    error = finding.evidence_dict()["error"]
    assert "fmi3GetClock" in error
    assert "/tmp" not in error  # no temporary path: reports are reproducible


# --------------------------------------------------------------------- points, seeds

def test_points_and_seed_are_recorded_and_deterministic():
    fmu = build_scene("Robertson")
    a = check_fmu(fmu, options=EngineOptions(probes=True, seed=7))
    b = check_fmu(fmu, options=EngineOptions(probes=True, seed=7))
    c = check_fmu(fmu, options=EngineOptions(probes=True, seed=8))
    info = dict(a.info)
    assert info["seed"] == 7
    points = info["points"]
    assert points[0][0] == ("label", "start") and len(points) == 4
    assert a == b
    assert dict(c.info)["points"] != points


def test_crash_reports_are_deterministic():
    fmu = build_scene("Robertson", defines=["DEFECT_EXIT_IN_CALL"])
    a = check_fmu(fmu, options=EngineOptions(probes=True))
    b = check_fmu(fmu, options=EngineOptions(probes=True))
    assert a.findings == b.findings and a.findings


def _layout(bounds) -> Layout:
    return Layout(states=(1,), derivatives=(2,), ode_states=(1,), ode_derivatives=(2,),
                  algebraic=(3,), residuals=(4,), inputs=(), outputs=(), ode_outputs=(),
                  enable=None, enable_status="absent", enable_tunable=False, token="",
                  model_identifier="M", nominal={1: 1e-5, 3: 1.0}, bounds=bounds)


def test_near_points_stay_within_bounds_and_scale_with_nominal():
    layout = _layout({1: (0.0, 2e-6), 3: (0.9, 1.0)})
    start = Point(0.0, {1: 1e-6, 3: 1.0}, "start")
    points = near_points(start, layout, np.random.default_rng(3), count=50)
    assert all(0.0 <= p.values[1] <= 2e-6 and 0.9 <= p.values[3] <= 1.0 for p in points)
    assert all(p.t >= start.t for p in points)
    spread = np.std([p.values[1] for p in points])
    assert 1e-8 < spread < 1e-5   # perturbed on the scale of the nominal, not of 1
    again = near_points(start, layout, np.random.default_rng(3), count=50)
    assert again == points


def test_start_point_keeps_finite_values_and_notes_the_others():
    class FakeInstance:
        mode = "dae"

        def get_float64(self, vrs):
            return np.array([{1: 0.5, 3: float("nan")}[vr] for vr in vrs])

    layout = dataclasses.replace(_layout({}), start={3: 0.25})
    noted: dict[int, float] = {}
    point = start_point(FakeInstance(), layout, noted)  # type: ignore[arg-type]
    assert point.values == {1: 0.5, 3: 0.25}
    assert list(noted) == [3] and np.isnan(noted[3])


def test_call_record_round_trip():
    record = CallRecord()
    record.set_probe("DAE720")
    record.enter("fmi3GetDirectionalDerivative")
    assert CallRecord.parse(record.buffer) == ("DAE720", "fmi3GetDirectionalDerivative", True)
    record.leave()
    assert CallRecord.parse(record.buffer)[2] is False
    assert CallRecord.parse(b"") == ("", "", False)


def test_call_record_keeps_the_value_references_of_the_call_in_progress():
    """A getter's or setter's value references (the count, the first REFS_KEPT of an array),
    none for a call without them or a raw pointer the record does not read."""
    import ctypes
    from conformance.runtime.callrecord import REFS_KEPT
    record = CallRecord()
    refs = (ctypes.c_uint * 3)(5, 4294967295, 7)
    record.enter("fmi3GetFloat64", 1, refs, 3)
    assert CallRecord.refs(record.buffer) == (3, (5, 4294967295, 7))
    record.enter("fmi3GetFloat64", 2, refs, 1)
    assert CallRecord.refs(record.buffer) == (1, (5,))
    many = (ctypes.c_uint * (REFS_KEPT + 4))(*range(REFS_KEPT + 4))
    record.enter("fmi3SetFloat64", 3, many, REFS_KEPT + 4)
    assert CallRecord.refs(record.buffer) == (REFS_KEPT + 4, tuple(range(REFS_KEPT)))
    record.enter("fmi3GetFloat64", 4, ctypes.cast(refs, ctypes.POINTER(ctypes.c_uint)), 3)
    assert CallRecord.refs(record.buffer) == (0, ())
    record.enter("fmi3EnterEventMode", 5)
    assert CallRecord.refs(record.buffer) == (0, ())
    assert CallRecord.refs(b"") == (0, ())

