"""Every fixture case produces exactly the codes it expects (at warning or error level)."""
from __future__ import annotations

import pytest

from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Severity
from tests.fixturekit import Case, all_cases, materialise

CASES = all_cases()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_fixture(case: Case, tmp_path):
    path = materialise(case, tmp_path)
    options = EngineOptions(probes=False, draft=case.spec.get("draft", "auto"))
    report = check_fmu(path, options=options)
    every = {f.code for f in report.findings}
    found = {f.code for f in report.findings
             if f.severity >= Severity.WARNING or f.code in case.expect}
    extra, missing = found - case.expect, case.expect - found
    detail = "\n".join(f"  {f.severity} {f.code} {f.name}: {f.message} "
                       f"({f.location.file}:{f.location.line})" for f in report.findings)
    assert not extra and not missing, (
        f"{case.id}: extra {sorted(extra)}, missing {sorted(missing)}\nfindings:\n{detail}")
    if case.kind == "pass":
        assert case.code not in every, f"{case.id}: the rule fired on its passing case\n{detail}"
    else:
        assert case.code in found, f"{case.id}: the rule did not fire\n{detail}"
