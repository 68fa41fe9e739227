"""What the probe worker sends back is what the probe yielded: every field of a violation."""
from __future__ import annotations

import json

from conformance.report.findings import Location, Violation, evidence
from conformance.runtime.protocol import violation_from_json, violation_json


def test_a_violation_crosses_the_process_boundary_whole():
    """A probe's sub-check (``part``) decides the finding's severity: it must survive the JSON
    line from the worker, as message, location, evidence, subject and rule do."""
    sent = Violation("d(r)/d(w) is wrong", Location("m.xml", 3, 4, "/a/b"),
                     evidence(mode="DAE mode", values=[1.0, 2.0], nested={"k": [1, 2]}),
                     subject="d(r)/d(w)", rule="directional-derivative-mismatch",
                     part="dae-mode")
    assert violation_from_json(json.loads(json.dumps(violation_json(sent)))) == sent
    plain = Violation("x")
    assert violation_from_json(json.loads(json.dumps(violation_json(plain)))) == plain


def test_the_cause_crosses_too():
    sent = Violation("m", subject="d(a)/d(b)", cause="derivative entry d(a)/d(b), deviation -1")
    assert violation_from_json(json.loads(json.dumps(violation_json(sent)))) == sent
