"""Every defect variant is caught by its rule and nothing else; every probe rule has one."""
from __future__ import annotations

import pytest

from conformance.catalogue import default_catalogue
from conformance.engine import EngineOptions, check_fmu
from conformance.findings import Severity
from tests.probes import defects_basic, defects_derivatives, defects_simulation
from tests.probes.variants import Defect, build

DEFECTS: list[Defect] = [*defects_basic.DEFECTS, *defects_derivatives.DEFECTS,
                         *defects_simulation.DEFECTS]
PROBE_RULES = [r for r in default_catalogue() if r.stage == "probe"]


@pytest.mark.parametrize("defect", DEFECTS, ids=[d.id for d in DEFECTS])
def test_defect_is_caught_by_its_rule_only(defect: Defect):
    report = check_fmu(build(defect), options=EngineOptions(probes=True))
    expected = {defect.code, *defect.also}
    found = {f.code for f in report.findings
             if f.severity >= Severity.WARNING or f.code in expected}
    detail = "\n".join(f"  {f.severity} {f.code} {f.name}: {f.message}" for f in report.findings)
    assert found == expected, (f"{defect.id}: extra {sorted(found - expected)}, "
                               f"missing {sorted(expected - found)}\n{detail}")


@pytest.mark.parametrize("rule", PROBE_RULES, ids=[r.code for r in PROBE_RULES])
def test_every_probe_rule_has_a_defect_variant(rule):
    assert any(d.code == rule.code for d in DEFECTS), (
        f"{rule.code} {rule.name} has no defect variant in tests/probes/defects_*.py")
