"""A probe finding is never caused by the XML: faulty numeric attributes are the static stage's.

The probes scale by nominal values, stay within min/max and start from the FMU's initial values.
When those attributes are faulty (rules/attributes.toml), the static rule reports it and the
probes use nothing flagged: a correct binary gets no probe finding.
"""
from __future__ import annotations

import pytest

from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Severity
from tests.fixtures import variant

X = ('<Float64 name="x1" valueReference="1" causality="local" variability="continuous" '
     'initial="exact" ')


def _x1(attributes: str) -> tuple[tuple[str, str], ...]:
    """An edit of the state x1's attributes (start 0.5, nominal 1 in the scene)."""
    return ((X + 'start="0.5" nominal="1"/>', X + attributes + "/>"),)


CASES = {
    "negative nominal": (_x1('start="0.5" nominal="-1e300"'), {"DAE521"}),
    "zero nominal": (_x1('start="0.5" nominal="0"'), {"DAE521"}),
    "infinite nominal": (_x1('start="0.5" nominal="INF"'), {"DAE520"}),
    "min above max": (_x1('start="0.5" min="10" max="-10"'), {"DAE522"}),
    "NaN start": (_x1('start="NaN"'), {"DAE520"}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_faulty_attribute_is_only_a_static_finding(case):
    edits, expected = CASES[case]
    fmu = variant("SimpleDAE", md_edits=edits)
    report = check_fmu(fmu, options=EngineOptions(probes=True))
    # the attribute's own rule at any weight (a non-finite start or nominal is information
    # since issue 29: no text forbids it), every other finding from a warning up
    found = {f.code for f in report.findings
             if f.severity >= Severity.WARNING or f.code in expected}
    detail = "\n".join(f"  {f.severity} {f.code} {f.name}: {f.message}" for f in report.findings)
    assert found == expected, f"{case}: {sorted(found)} instead of {sorted(expected)}\n{detail}"
    assert any(c.startswith("DAE7") for c in report.rules_run), "the probes did not run"
