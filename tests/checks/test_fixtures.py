"""Every fixture case produces exactly the codes it expects (at warning or error level), and a
failing case's findings of its rule are exactly those of its ``[[exact]]`` tables: severity,
subject, file, line, part and evidence (tests/exactkit.py)."""
from __future__ import annotations

import pytest

from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import Severity
from tests.fixtures import Case, all_cases, materialise
from tests.exactkit import assert_exact
from tests.reportkit import raw_placeholders

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
    assert raw_placeholders(report) == []
    if case.kind == "pass":
        assert case.code not in every, f"{case.id}: the rule fired on its passing case\n{detail}"
    else:
        assert case.code in found, f"{case.id}: the rule did not fire\n{detail}"
    exact = case.spec.get("exact", [])
    if case.kind == "fail":
        assert exact, f"{case.id}: a failing case names its findings exactly ([[exact]])"
    of_rule = [f for f in report.findings if f.code == case.code]
    assert len(of_rule) == len(exact), (
        f"{case.id}: {len(of_rule)} findings of {case.code}, {len(exact)} expected\n{detail}")
    for table in exact:
        found = assert_exact(report, code=case.code, severity=table["severity"],
                             subject=table.get("subject"), file=table.get("file"),
                             line=table.get("line"), part=table.get("part"),
                             evidence=table["evidence"])
        for key in table.get("evidence_none", []):
            assert found.evidence_dict().get(key, "absent") is None, (
                f"{case.id}: evidence {key} should be None: {found.evidence_dict()}")
