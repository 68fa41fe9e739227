"""Every defect variant is caught by its rule and nothing else; every probe rule has one."""
from __future__ import annotations

import re

import pytest

from conformance.report.catalogue import default_catalogue, with_options
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Severity
from tests.checkkit import checked
from tests.fixtures import DEFECTS, Defect, FIXTURES, SCENES_DIR, build_defect
from tests.reportkit import raw_placeholders

PROBE_RULES = [r for r in default_catalogue() if r.stage == "probe"]


@pytest.mark.parametrize("defect", DEFECTS, ids=[d.id for d in DEFECTS])
def test_defect_is_caught_by_its_rule_only(defect: Defect):
    if defect.options:  # a rule option of its own (checkkit asks with the default catalogue)
        report = check_fmu(build_defect(defect), options=EngineOptions(probes=True),
                           catalogue=with_options(default_catalogue(), defect.options))
    else:
        report = checked(build_defect(defect), options=EngineOptions(probes=True))
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
