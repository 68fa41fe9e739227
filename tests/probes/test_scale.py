"""The full check of large models (issue 22): correct scalable scenes are clean at every size,
defects of dg/dw are found at every size, a true derivative that underflows is no mismatch,
and the verdicts do not depend on the machine's load.

The bench (``python -m bench.scale_bench``, reports/bench/scale.md) measures time and memory up
to 10,000 variables; here the sizes stay around 1,000, where the sparse paths already run
(``dense_up_to`` is 200), so the suite stays fast.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conformance.report.catalogue import default_catalogue
from conformance.run.engine import EngineOptions, check_fmu
from conformance.report.findings import thaw
from conformance.numerics import colouring as col
from conformance.numerics import measure
from conformance.numerics.floors import TINY
from tests.fixtures import blocks, chain

SCENES = Path(__file__).resolve().parents[2] / "scenes"
OPTIONS = {r.code: r.option_values for r in default_catalogue()}
DENSE_UP_TO = OPTIONS["DAE745"]["dense_up_to"]


def _clean(report) -> None:
    assert report.findings == (), [(f.code, f.subject, f.message) for f in report.findings]
    assert report.rules_not_run == ()
    assert [c for c, _ in report.rules_skipped if c.startswith(("DAE7", "DAE8"))] == []


def test_blocks_xml_is_the_generators():
    here = SCENES / "Blocks"
    assert (here / "modelDescription.xml").read_text() == blocks.model_description(30)
    assert (here / "fmi-ls-manifest.xml").read_text() == blocks.manifest(30)


@pytest.mark.parametrize("build, n", [(chain.build_chain, 300), (chain.build_chain, 1000),
                                      (blocks.build_blocks, 100), (blocks.build_blocks, 1000)],
                         ids=["Chain-300", "Chain-1000", "Blocks-100", "Blocks-1000"])
def test_a_correct_scalable_scene_is_clean_with_the_full_check(build, n):
    # the default check: every probe, endurance and simulation; above dense_up_to the sparse
    # conditioning, the sparse simulation and the counted budgets run
    report = check_fmu(build(n), options=EngineOptions(probes=True))
    _clean(report)
    info = thaw(report.info)
    assert info["endurance"]["stopped"] == "budget"
    assert info["simulation"]["status"] == "ok"
    kept = OPTIONS["DAE801"]["published_series"]   # x and the n algebraic variables
    assert info["simulation"].get("series_left_out", 0) == max(0, n + 1 - kept)
    assert len(info["simulation"]["series"]) == min(n + 1, kept)


@pytest.mark.parametrize("n", [4, 300, 1000])
@pytest.mark.parametrize("defect, code", [("DEFECT_SINGULAR_GW", "DAE746"),
                                          ("DEFECT_ILL_CONDITIONED", "DAE745")])
def test_dgdw_defects_are_found_at_every_size(defect, code, n):
    report = check_fmu(chain.build_chain(n, defines=[defect]),
                       options=EngineOptions(probes=True, select=("DAE74",)))
    assert {f.code for f in report.findings} == {code}
    (finding,) = report.findings
    ev = finding.evidence_dict()
    assert ev["size"] == n
    assert ("method" in ev) == (n > DENSE_UP_TO)   # the sparse estimate says so, the SVD not
    # the near-null direction: the end of the chain, where the last residual repeats the one
    # before it (a short chain's spreads over all of it)
    assert ev["involved"]
    if n > 10:
        assert set(ev["involved"]) <= {f"w[{n - k}]" for k in range(1, 6)}


def test_an_underflowing_true_derivative_is_no_mismatch():
    # Along the chain the sensitivity of w[i] to x shrinks by about 4.5 per link: at N = 1000
    # the initial unknowns' derivatives underflow. The FMU's directional derivative is right
    # (a subnormal number), the finite difference of the row is 0 with an error estimate of
    # 0: only the floor keeps that from being a mismatch.
    report = check_fmu(chain.build_chain(1000),
                       options=EngineOptions(probes=True, select=("DAE740", "DAE741", "DAE742",
                                                                  "DAE744", "DAE75")))
    _clean(report)


def test_the_floor_decides_only_where_the_row_resolves_nothing():
    # the family at the level of the comparison: rows of a Jacobian whose true values underflow
    # (directional and adjoint both exact, subnormal), and an ordinary row that stays judged
    m, n = 3, 3
    true = np.array([[1.0, 2.0, 0.0], [3e-321, 0.0, 4e-321], [0.0, 5e-322, 0.0]])
    pattern = col.Pattern.from_rows(n, [[0, 1], [0, 2], [1]])
    colouring = col.colour_columns(pattern)
    sources = measure.Sources(lambda d: true @ (np.ones(n) + d), lambda s: true @ s,
                              lambda v: v @ true)
    e = measure.measure(sources, pattern, colouring, np.full(n, 1e-5), np.ones(n),
                        np.random.default_rng(0))
    ops = OPTIONS["DAE740"]
    for values in (e.dd, e.adj):
        diff, tol, err, scale = measure.disagreement(e, values, np.ones(n), m, rtol=ops["rtol"],
                                                     margin=ops["margin"], ulps=ops["ulps"])
        assert not np.any(diff > tol)
        tiny_rows = np.isin(e.rows, [1, 2])
        scaled = ops["margin"] * err + ops["rtol"] * scale
        assert np.any(diff[tiny_rows] > scaled[tiny_rows])   # without the floor: a mismatch
        assert np.all(tol[~tiny_rows] == scaled[~tiny_rows])  # the ordinary row: unchanged
    wrong = e.dd.copy()
    wrong[~np.isin(e.rows, [1, 2]) & (e.cols == 1)] = 2.5    # a real mismatch is still one
    diff, tol, _, _ = measure.disagreement(e, wrong, np.ones(n), m, rtol=ops["rtol"],
                                           margin=ops["margin"], ulps=ops["ulps"])
    assert np.any(diff > tol)
    assert np.all(np.abs(true[1:]) < 1e3 * TINY)   # the rows judged by the floor: subnormal


BUSY = "import time\nend = time.monotonic() + 600\nwhile time.monotonic() < end:\n    pass\n"


def test_the_same_fmu_gets_the_same_report_on_a_busy_machine():
    # the other core kept busy by a loop: the check is slower, its verdicts must not change
    fmu = chain.build_chain(500)
    quiet = check_fmu(fmu, options=EngineOptions(probes=True))
    busy = subprocess.Popen([sys.executable, "-c", BUSY])
    try:
        loaded = check_fmu(fmu, options=EngineOptions(probes=True))
    finally:
        busy.kill()
        busy.wait()
    _clean(quiet)
    assert loaded == quiet


def test_scale_bench_counts_nonzeros_and_sums_families():
    from bench import scale_bench as sb  # the benchmark harness: only for this test

    assert sb.structural_nonzeros(chain.build_chain(4)) == 3 * 4 + 3
    assert sb.structural_nonzeros(blocks.build_blocks(30)) == 3 + 10 * 20 + 10 * 30 + 10 * 20 + 20
    steps = [{"probe": "setup", "seconds": 1.0, "calls": 14, "peak_rss": 100},
             {"probe": "DAE740", "seconds": 2.0, "calls": 30, "peak_rss": 300},
             {"probe": "DAE741", "seconds": 0.5, "calls": 0, "peak_rss": 200}]
    fams = sb.families(steps)
    assert fams["setup"] == {"seconds": 1.0, "fmi_seconds": 0.0, "calls": 14, "peak_rss": 100}
    assert fams["derivatives"] == {"seconds": 2.5, "fmi_seconds": 0.0, "calls": 30,
                                   "peak_rss": 300}
    run = {"seconds": 3.0, "worker_peak_rss": 300 << 20, "parent_peak_rss": 50 << 20,
           "load": [1.0, 1.0], "findings": [], "rules_not_run": [], "steps": steps}
    result = {"scene": "Chain", "n": 1000, "nnz": 3003, **sb.summarise([run, run])}
    big = {**result, "n": 10000, "nnz": 30003, "seconds": 20.0}
    targets = {t["target"]: t["met"] for t in sb.targets([result, big])}
    assert targets["time(10,000) / time(1,000) <= 12"] is True
    assert targets["full check at 10,000 <= 30 s"] is True
    text = sb.render_markdown({"date": "d", "machine": {"cpu": "c", "usable_cores": 2,
                                                        "platform": "p", "python": "3"},
                               "runs": 2, "command": "c", "results": [result, big],
                               "targets": sb.targets([result, big]), "baseline": []})
    assert "| Chain | 10,000 | 30,003 | 20.00 |" in text


def test_scale_bench_gives_each_workers_time_and_the_one_worker_side_by_side():
    from bench import scale_bench as sb  # the benchmark harness: only for this test

    assert sb.variables(chain.build_chain(4)) == 14
    steps = [{"probe": "setup", "seconds": 1.0, "calls": 14, "peak_rss": 100, "lane": 0},
             {"probe": "setup", "seconds": 1.5, "calls": 14, "peak_rss": 100, "lane": 1},
             {"probe": "DAE740", "seconds": 6.0, "calls": 30, "peak_rss": 300, "lane": 0},
             {"probe": "DAE750", "seconds": 4.0, "calls": 9, "peak_rss": 200, "lane": 1}]
    run = {"seconds": 9.0, "worker_peak_rss": 300 << 20, "parent_peak_rss": 50 << 20,
           "load": [1.0, 1.0], "findings": [], "rules_not_run": [], "steps": steps}
    two = {"scene": "Blocks", "n": 1000, "nnz": 29823, **sb.summarise([run])}
    assert two["lane_seconds"] == [7.0, 5.5] and two["worker_seconds"] == 12.5
    single = [{**s, "lane": 0} for s in steps[:1] + steps[2:]]
    one = {"scene": "Blocks", "n": 1000, **sb.summarise([{**run, "seconds": 12.0,
                                                          "steps": single}])}
    text = sb.render_markdown({"date": "d", "machine": {"cpu": "c", "usable_cores": 2,
                                                        "platform": "p", "python": "3"},
                               "runs": 1, "command": "c", "results": [two], "one_worker": [one],
                               "targets": sb.targets([two]), "baseline": []})
    assert "| Blocks | 1,000 | 29,823 | 9.00 | 9.0 | 7.00 + 5.50 |" in text
    assert "| Blocks | 1,000 | 9.00 | 12.00 | 1.33 | 11.00 | yes |" in text
