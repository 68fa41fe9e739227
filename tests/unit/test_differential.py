"""scripts/differential.py: its mutated FMUs are the same for the same seed, and they make
rules fire (a differential run over FMUs that no rule finds fault with would compare nothing)."""
from __future__ import annotations

from conformance.run.engine import EngineOptions, check_paths
from conformance.reporters import json_report
from scripts.differential import verdicts, write_fmus


def test_the_same_seed_gives_the_same_fmus(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first = [p.read_bytes() for p in write_fmus(tmp_path / "a", 10, seed=3)]
    again = [p.read_bytes() for p in write_fmus(tmp_path / "b", 10, seed=3)]
    assert first == again
    other = [p.read_bytes() for p in write_fmus(tmp_path / "a", 10, seed=4)]
    assert other != first


def test_mutated_fmus_make_many_rules_fire(tmp_path):
    fmus = write_fmus(tmp_path, 60, seed=0)
    report = json_report.report_dict(check_paths(fmus, options=EngineOptions(probes=False)))
    found = verdicts(report)
    assert len(found) == 60
    fired = {f["code"] for findings, *_ in found.values() for f in findings}
    assert len(fired) >= 15
