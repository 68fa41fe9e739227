"""Reports for the reporter tests: one built by hand, one from the real engine on fixtures.

The hand-built report covers every shape a reporter must handle: an archive and a folder FMU,
errors, warnings and info, a grouped finding, an error a baseline accepted, text that needs
escaping in every format, a
crashed binary whose rule the catalogue does not know yet, an internal error, skipped rules,
and a clean FMU. Its catalogue is built here too, so the saved outputs in ``expected/`` change
only when a reporter changes.

Set ``LSDAE_UPDATE_EXPECTED=1`` to rewrite the saved outputs after an intended change, then
read the diff.
"""
from __future__ import annotations

import os
from pathlib import Path

from conformance.report.catalogue import Catalogue, RuleSpec, default_catalogue
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import (
    Finding,
    FmuReport,
    Location,
    Report,
    RunInfo,
    Severity,
    evidence,
)
from conformance.model.layer import NOT_A_DAE_FMU
from tests.fixtures import all_cases, materialise

HERE = Path(__file__).resolve().parent


EXPECTED = HERE / "expected"
SCHEMAS = HERE / "schemas"
MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
MD = "modelDescription.xml"
CRASH_NAMES = {"binary-crashed", "binary-timed-out", "binary-memory-limit", "internal-error"}


def _rule(code: str, name: str, severity: Severity, stage: str = "static", **kw) -> RuleSpec:
    return RuleSpec(
        code=code, name=name, severity=severity, stage=stage, drafts=kw.get("drafts", ("*",)),
        needs=kw.get("needs", ()), spec=kw.get("spec", f"DAE-{code[-2:]}; fmi-ls-dae §2"),
        summary=kw.get("summary", f"Summary of {name}."),
        rationale=kw.get("rationale", f"Why {name} matters to an importer."),
        bad=kw.get("bad", "<Bad/>"), good=kw.get("good", "<Good/>"))


SAMPLE_CATALOGUE = Catalogue([
    _rule("DAE001", "archive-unreadable", Severity.ERROR, "archive"),
    _rule("DAE021", "legacy-draft-shape", Severity.WARNING, "schema"),
    _rule("DAE091", "manifest-missing", Severity.INFO, "archive"),
    _rule("DAE099", "internal-error", Severity.ERROR, "archive"),
    _rule("DAE201", "enable-parameter-missing", Severity.ERROR, needs=("manifest",)),
    _rule("DAE203", "enable-parameter-not-boolean", Severity.ERROR,
          summary="The enable parameter is not a <Boolean>.",
          rationale="An importer switches DAE mode with fmi3SetBoolean. " * 40),
    _rule("DAE301", "algebraic-variable-unknown-vr", Severity.ERROR, needs=("manifest",)),
    _rule("DAE701", "initial-residual-nonzero", Severity.ERROR, "probe", needs=("binary",)),
])

SAMPLE_RUN = RunInfo(timestamp="2026-11-21T23:28:40+01:00", hostname="ci-runner",
                     durations=(("models/Broken.fmu", 0.25), ("models/unpacked/Plain", 0.125),
                                ("models/Crashy.fmu", 1.5), ("models/Clean.fmu", 0.0625)))


def _f(code, name, severity, message, file=None, line=None, path=None, subject=None,
       snippet=None, count=1, ev=()) -> Finding:
    return Finding(code, name, severity, message,
                   Location(file=file, line=line, path=path, snippet=snippet), ev, subject,
                   count)


def sample_report() -> Report:
    broken = FmuReport(
        path="models/Broken.fmu", draft="formulation",
        findings=(
            _f("DAE021", "legacy-draft-shape", Severity.WARNING,
               "the manifest follows the Formulation draft; to migrate: rename it", MANIFEST, 2,
               "/fmiLayeredStandardManifest", None, "<fmiLayeredStandardManifest>"),
            _f("DAE203", "enable-parameter-not-boolean", Severity.ERROR,
               "enable parameter 'dae' is a <Float64>, not a <Boolean>", MD, 12,
               "/fmiModelDescription/ModelVariables/Float64[@name='dae']", "dae",
               '    <Float64 name="dae" valueReference="1"/>',
               ev=evidence(value_reference=1, type="Float64")),
            _f("DAE301", "algebraic-variable-unknown-vr", Severity.ERROR,
               "4 items ('w1', 'w2', 'w3', 'w4') name no variable", MANIFEST, 7,
               None, None, '  <AlgebraicVariable valueReference="91"/>', 4,
               evidence(count=4, subjects=["w1", "w2", "w3", "w4"], lines=[7, 8, 9, 10])),
            _f("DAE201", "enable-parameter-missing", Severity.ERROR,
               "the manifest names no enable parameter", MANIFEST, 3, "/fmiDAEManifest", None,
               "<fmiDAEManifest>", ev=evidence(baselined=True)),
            _f("DAE301", "algebraic-variable-unknown-vr", Severity.ERROR,
               "odd name 'a|b`c<d>%e,f:g\r\n::error::injected' @octocat #1 *x* [l](u)",
               MANIFEST, 12, None, "a|b`c<d>%e,f:g\r\n::error::injected", "\x01bad"),
        ),
        rules_run=("DAE021", "DAE201", "DAE203", "DAE301"),
        rules_skipped=(("DAE701", "probes turned off (--no-probes)"),),
        info=evidence(model_name="Broken", fmi_version="3.0", variables=9,
                      jacobian={"rows": ["g1"]}),
    )
    plain = FmuReport(
        path="models/unpacked/Plain", draft=None,
        findings=(_f("DAE091", "manifest-missing", Severity.INFO,
                     f"no fmi-ls-dae manifest ({MANIFEST}): a Model Exchange FMU that does "
                     "not use the DAE layer; the DAE rules are skipped", MANIFEST),),
        rules_run=(),
        rules_skipped=(("DAE201", NOT_A_DAE_FMU), ("DAE301", NOT_A_DAE_FMU),
                       ("DAE701", NOT_A_DAE_FMU)),
        info=evidence(model_name="Plain", probes=f"not run: {NOT_A_DAE_FMU}"),
    )
    crashy = FmuReport(
        path="models/Crashy.fmu", draft="alpha1",
        findings=(
            _f("DAE099", "internal-error", Severity.ERROR,
               "lsdae failed while checking this FMU: KeyError: 'x'"),
            _f("DAE790", "binary-crashed", Severity.ERROR,
               "the binary crashed (SIGSEGV) in fmi3GetFloat64", None, None, None, None, None,
               1, evidence(signal="SIGSEGV", call="fmi3GetFloat64")),
        ),
        rules_run=("DAE201", "DAE701"),
        rules_skipped=(("DAE720", "the worker failed before the probes could run"),),
        rules_not_run=(("DAE720", "the worker failed before the probes could run"),),
    )
    clean = FmuReport(path="models/Clean.fmu", draft="alpha1", findings=(),
                      rules_run=("DAE201", "DAE203", "DAE301", "DAE701"))
    return Report(tool_version="9.9.9", fmus=(broken, plain, crashy, clean),
                  options=evidence(draft="auto", probes=False))


# The engine on real fixture cases; the selection keeps the saved outputs independent of rules
# added later (each rule added to the catalogue would otherwise add a test case).
ENGINE_CASES = {"DAE001/fail": "fixtures/DAE001.fmu", "DAE021/fail": "fixtures/DAE021",
                "DAE091/fail": "fixtures/DAE091", "DAE203/fail": "fixtures/DAE203",
                "DAE302/fail": "fixtures/DAE302", "DAE203/pass": "fixtures/clean"}
ENGINE_SELECT = ("DAE001", "DAE021", "DAE090", "DAE091", "DAE201", "DAE203", "DAE302")


def engine_report(tmp: Path) -> Report:
    """Run the static engine on fixture cases, under stable display paths."""
    by_id = {c.id: c for c in all_cases()}
    options = EngineOptions(probes=False, select=ENGINE_SELECT)
    fmus = []
    for n, (case_id, display) in enumerate(ENGINE_CASES.items()):
        path = materialise(by_id[case_id], tmp / f"case{n}")
        fmus.append(check_fmu(path, options=options, display_path=display))
    return Report(tool_version="9.9.9", fmus=tuple(fmus), options=evidence(probes=False))


def engine_catalogue() -> Catalogue:
    full = default_catalogue()
    return Catalogue([full[c] for c in ENGINE_SELECT])


ENGINE_RUN = RunInfo(timestamp="2026-11-21T22:28:40+00:00", hostname="ci-runner",
                     durations=tuple((p, 0.5) for p in ENGINE_CASES.values()))


def compare_expected(name: str, text: str) -> None:
    """Compare with ``expected/<name>``; rewrite it instead when LSDAE_UPDATE_EXPECTED is set."""
    target = EXPECTED / name
    if os.environ.get("LSDAE_UPDATE_EXPECTED"):
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8", newline="")
        return
    assert target.exists(), f"{target} is missing: run with LSDAE_UPDATE_EXPECTED=1"
    with target.open(encoding="utf-8", newline="") as fh:  # keep a CR in a message visible
        saved = fh.read()
    assert text == saved, (f"{name} differs from the saved output; if the change is intended, "
                           "rerun with LSDAE_UPDATE_EXPECTED=1 and review the diff")


def new_counts(fmu_json: dict) -> dict[str, int]:
    """Findings by severity that no baseline accepted, from one FMU of the JSON report."""
    out = {"error": 0, "warning": 0, "info": 0}
    for f in fmu_json["findings"]:
        if not (f["evidence"] or {}).get("baselined"):
            out[f["severity"]] += 1
    return out


def expected_junit_counts(report_json: dict) -> list[dict[str, int]]:
    """Per FMU: tests, failures, errors, skipped, derived from the JSON report alone."""
    out = []
    for fmu in report_json["fmus"]:
        by_code: dict[str, list[dict]] = {}
        for f in fmu["findings"]:
            by_code.setdefault(f["code"], []).append(f)
        applied = set(fmu["rules_run"]) | set(by_code)
        skipped = {s["code"] for s in fmu["rules_skipped"]} - applied
        failures = errors = 0
        for findings in by_code.values():
            bad = [f for f in findings if f["severity"] == "error"
                   and not (f["evidence"] or {}).get("baselined")]
            if bad and any(f["name"] in CRASH_NAMES for f in bad):
                errors += 1
            elif bad:
                failures += 1
        out.append({"tests": len(applied) + len(skipped), "failures": failures,
                    "errors": errors, "skipped": len(skipped)})
    return out
