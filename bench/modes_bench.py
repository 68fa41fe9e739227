"""Both-modes benchmark: what probing every promise in both modes (issue 21) adds to a full check.

Each row is one FMU, checked in full (``lsdae check``, probes on, the default endurance level)
by this tree and by a reference revision from before the ODE-mode probes (``--compare-rev``,
default ``dde93ea``, its package exported with ``git archive``), each as a subprocess
(``python -m conformance`` with the tree first on the path), the two interleaved round by round so that both see the same machine load. The table
gives the medians over ``--runs`` rounds, the time added (this tree minus the reference) and
that time as a share of the reference's full check; the target is under one half, for the
scenes as a whole (the sum of the medians) and for each scene. The corpus models of Model
Exchange are timed too: the reference does not probe them at all (``binary not checked``), so
their added time is the whole probe stage they now get.

The added time is the ODE-mode surveys (Continuous-Time Mode and Initialization Mode), the
start values read on a fresh instance, and the invariant probe where an FMU declares one.

    python -m bench.modes_bench [--runs 3] [--compare-rev dde93ea] [--out reports/bench]
"""
from __future__ import annotations

import argparse
import compileall
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.startup_bench import REPO_ROOT
from scenes.build import build_scene, corpus_names, scene_names

REFERENCE = "dde93ea"   # main before issue 21: DAE mode only, no plain Model Exchange probing
TARGET = 0.5            # the added time, as a share of the reference's full check


def _corpus_model_exchange() -> list[str]:
    """The corpus models with a <ModelExchange> element (the others are not probed)."""
    out = []
    for name in corpus_names():
        text = (REPO_ROOT / "scenes" / "corpus" / name / "modelDescription.xml").read_text()
        if "<ModelExchange" in text:
            out.append(name)
    return out


def _time(argv: list[str], cwd: Path) -> float:
    start = time.perf_counter()
    proc = subprocess.run(argv, cwd=cwd, capture_output=True)
    elapsed = time.perf_counter() - start
    if proc.returncode not in (0, 1):
        raise SystemExit(f"modes_bench: {' '.join(argv)} exited {proc.returncode}: "
                         f"{proc.stderr.decode(errors='replace')[-500:]}")
    return elapsed


def run(runs: int, rev: str) -> dict:
    compileall.compile_dir(REPO_ROOT / "conformance", quiet=1)
    fmus = {name: str(build_scene(name)) for name in [*scene_names(), *_corpus_model_exchange()]}
    kinds = {name: ("scene" if name in scene_names() else "corpus") for name in fmus}
    times: dict[str, dict[str, list[float]]] = {n: {"reference": [], "this tree": []}
                                                for n in fmus}
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "reference"
        out = str(Path(tmp) / "report.json")
        tree.mkdir()
        archive = subprocess.run(["git", "-C", str(REPO_ROOT), "archive", rev, "conformance",
                                  "schemas", "rules"], check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
        compileall.compile_dir(tree / "conformance", quiet=1)
        trees = {"reference": tree, "this tree": REPO_ROOT}
        for name, fmu in fmus.items():     # warm the page cache, the scene builds
            for cwd in trees.values():
                _time([sys.executable, "-m", "conformance", "check", fmu,
                       "--format", f"json:{out}"], cwd)
        for _ in range(runs):
            for name, fmu in fmus.items():
                for label, cwd in trees.items():
                    times[name][label].append(_time(
                        [sys.executable, "-m", "conformance", "check", fmu,
                         "--format", f"json:{out}"], cwd))
    rows = []
    for name in fmus:
        before = statistics.median(times[name]["reference"])
        after = statistics.median(times[name]["this tree"])
        rows.append({"fmu": name, "kind": kinds[name], "reference_s": before, "this_s": after,
                     "added_s": after - before, "share": (after - before) / before,
                     "runs_reference_s": times[name]["reference"],
                     "runs_this_s": times[name]["this tree"]})
    scenes = [r for r in rows if r["kind"] == "scene"]
    total_before = sum(r["reference_s"] for r in scenes)
    total_after = sum(r["this_s"] for r in scenes)
    return {"date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "runs": runs,
            "reference": rev, "rows": rows, "target": TARGET,
            "scenes": {"reference_s": total_before, "this_s": total_after,
                       "added_s": total_after - total_before,
                       "share": (total_after - total_before) / total_before},
            "machine": {"python": sys.version.split()[0], "cpus": len(os.sched_getaffinity(0))
                        if hasattr(os, "sched_getaffinity") else os.cpu_count()}}


def markdown(result: dict) -> str:
    s = result["scenes"]
    lines = [
        "# Both modes: what the ODE-mode probes add to a full check", "",
        f"Date: {result['date']}. Medians of {result['runs']} interleaved rounds; each cell is a "
        f"full `lsdae check` (probes on, endurance quick) as a subprocess, this tree against "
        f"`{result['reference']}` (before issue 21: DAE mode only, and no probe at all for a "
        "Model Exchange FMU without the layer). Added: this tree minus the reference; share: "
        f"added / reference; target: under {result['target']:g} for the scenes.", "",
        "| FMU | kind | reference s | this tree s | added s | share |",
        "|---|---|---:|---:|---:|---:|"]
    for r in result["rows"]:
        lines.append(f"| {r['fmu']} | {r['kind']} | {r['reference_s']:.2f} | "
                     f"{r['this_s']:.2f} | {r['added_s']:+.2f} | {r['share']:+.0%} |")
    lines += [f"| **scenes, all** | | **{s['reference_s']:.2f}** | **{s['this_s']:.2f}** | "
              f"**{s['added_s']:+.2f}** | **{s['share']:+.0%}** |", "",
              "Corpus rows: the reference does not load these binaries (no layer, \"binary not "
              "checked\"), so their added time is the whole ODE-mode probe stage, worker start "
              "included.", "",
              f"Machine: Python {result['machine']['python']}, {result['machine']['cpus']} "
              "usable CPUs.", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--compare-rev", metavar="REV", default=REFERENCE)
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "reports" / "bench")
    args = parser.parse_args(argv)
    result = run(args.runs, args.compare_rev)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "modes.json").write_text(json.dumps(result, indent=2) + "\n")
    text = markdown(result)
    (args.out / "modes.md").write_text(text)
    print(text)
    verdict = "under" if result["scenes"]["share"] < result["target"] else "OVER"
    print(f"scenes: {result['scenes']['share']:+.0%} added, {verdict} the target "
          f"{result['target']:g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
