"""Scale benchmark: the full check (``lsdae check``, default options) against the model's size.

For the Chain (3N + 3 structural nonzeros) and Blocks (about 30N, ``scenes/Blocks``) at
N = 100, 1,000 and 10,000 (``--sizes``), each case runs in a fresh process
(:mod:`bench.scale_case`: the command line's own entry, a JSON report), ``--runs`` times,
interleaved, and the tables give medians:

* the whole check's wall time, the worker's and the parent's peak resident size, the findings
  and the rules not run (both must be empty: the scenes are correct);
* per probe family (``conformance.probes.machinery.registry.FAMILIES``, and the worker's
  setup): seconds, FMI calls and the peak resident size of the worker during it, from the
  driver's log records;
* the targets of issue 22: time(10,000) / time(1,000) <= 12, the full check at 10,000 within
  30 s, the worker under 500 MiB, no finding at any size.

A model of 1,000 variables or more is probed by two workers at once
(``conformance.probes.machinery.lanes``);
``--one-worker`` also checks each such case with ``--probe-workers 1``, interleaved, for the
ratio of the two in the same runs. ``--baseline TREE`` also checks the Chain with the source
tree TREE (another revision's
checkout: its ``conformance`` package, the same FMUs), interleaved with this tree's runs, for a
side-by-side ratio. The load of the machine (1-minute load average) is recorded around each
case: on the shared 2-core machine it is rarely idle. Writes ``scale.md``, ``scale.json`` and
``scale.png`` into ``--out``.

    python -m bench.scale_bench [--sizes 100,1000,10000] [--runs 3] [--out reports/bench]
                                [--one-worker] [--baseline /path/to/other/checkout]
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any, Callable, Sequence

from lxml import etree

from bench.static_bench import machine_info
from conformance.model.manifest import MANIFEST
from conformance.probes.machinery.lanes import LARGE_MODEL
from conformance.probes.machinery.registry import FAMILY_OF
from scenes.Blocks import blocks
from scenes.Chain import chain

BUILDERS: dict[str, Callable[[int], Path]] = {"Chain": chain.build_chain,
                                              "Blocks": blocks.build_blocks}
CASE = Path(__file__).resolve().with_name("scale_case.py")
TARGET_RATIO, TARGET_SECONDS, TARGET_MIB = 12.0, 30.0, 500.0
MIB = 1 << 20


def variables(fmu: Path) -> int:
    """The variables of the FMU's modelDescription.xml (what decides the probe workers)."""
    with zipfile.ZipFile(fmu) as zf:
        root = etree.fromstring(zf.read("modelDescription.xml"))
    found = root.find("ModelVariables")
    return 0 if found is None else len(found)


def structural_nonzeros(fmu: Path) -> int:
    """The declared entries of the DAE Jacobian: the manifest's dependencies of residuals,
    state derivatives and outputs."""
    with zipfile.ZipFile(fmu) as zf:
        root = etree.fromstring(zf.read(MANIFEST))
    total = 0
    for el in root.iter():
        tag = etree.QName(el).localname if isinstance(el.tag, str) else ""
        if tag in ("Residual", "ContinuousStateDerivative", "Output"):
            total += len((el.get("dependencies") or "").split())
    return total


def run_case(fmu: Path, tree: str | None = None, timeout: float = 900.0,
             extra: Sequence[str] = ()) -> dict[str, Any]:
    """One ``lsdae check`` of ``fmu`` in a fresh process (``tree``: another checkout's code;
    ``extra``: further options of ``lsdae check``)."""
    env = dict(os.environ)
    if tree:
        # the tree's own environment when it has one: this one's editable install would supply
        # the modules the older tree lacks from this tree
        own = Path(tree) / ".venv" / "bin" / "python"
        env["PYTHONPATH"] = os.pathsep.join(p for p in (tree, env.get("PYTHONPATH", "")) if p)
        command = [str(own) if own.exists() else sys.executable, str(CASE), str(fmu)]
    else:
        command = [sys.executable, "-m", "bench.scale_case", str(fmu)]
    if extra:
        command += ["--", *extra]
    before = os.getloadavg()[0]
    out = subprocess.run(command, capture_output=True, text=True, env=env, timeout=timeout,
                         cwd=tree or None)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{out.stderr[-2000:]}")
    result = json.loads(out.stdout.strip().splitlines()[-1])
    result["load"] = [before, os.getloadavg()[0]]
    return result


def families(steps: Sequence[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Seconds and FMI calls summed, peak resident size maximal, per probe family."""
    out: dict[str, dict[str, float]] = {}
    for step in steps:
        family = "setup" if step["probe"] == "setup" else FAMILY_OF.get(step["probe"], "other")
        entry = out.setdefault(family, {"seconds": 0.0, "fmi_seconds": 0.0, "calls": 0,
                                        "peak_rss": 0})
        entry["seconds"] += float(step.get("seconds") or 0.0)
        entry["fmi_seconds"] += float(step.get("fmi_seconds") or 0.0)
        entry["calls"] += int(step.get("calls") or 0)
        entry["peak_rss"] = max(entry["peak_rss"], int(step.get("peak_rss") or 0))
    return out


def _median(values: Sequence[float]) -> float:
    return float(statistics.median(values)) if values else 0.0


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians over the runs of one case; the verdicts must agree between runs."""
    fams: dict[str, dict[str, list[float]]] = {}
    for run in runs:
        for name, entry in families(run["steps"]).items():
            for key, value in entry.items():
                fams.setdefault(name, {}).setdefault(key, []).append(value)
    verdicts = {json.dumps([sorted(f["code"] for f in run["findings"]),
                            sorted(r["code"] for r in run["rules_not_run"])]) for run in runs}
    first = runs[0]
    return {
        "seconds": _median([r["seconds"] for r in runs]),
        "seconds_all": [r["seconds"] for r in runs],
        "fmi_seconds": _median([sum(float(s.get("fmi_seconds") or 0.0) for s in r["steps"])
                                for r in runs]),
        "worker_seconds": _median([sum(float(s.get("seconds") or 0.0) for s in r["steps"])
                                   for r in runs]),
        # each worker's (lane's) steps added up: the longest is the probes' critical path
        "lane_seconds": [_median([sum(float(s.get("seconds") or 0.0) for s in r["steps"]
                                      if s.get("lane", 0) == lane) for r in runs])
                         for lane in sorted({s.get("lane", 0) for s in first["steps"]})],
        "worker_peak_mib": _median([r["worker_peak_rss"] / MIB for r in runs]),
        "parent_peak_mib": _median([r["parent_peak_rss"] / MIB for r in runs]),
        "load": _median([sum(r["load"]) / 2 for r in runs]),
        "findings": first["findings"], "rules_not_run": first["rules_not_run"],
        "verdicts_agree": len(verdicts) == 1,
        "families": {name: {k: _median(v) for k, v in entry.items()}
                     for name, entry in fams.items()},
        "endurance": first.get("endurance"), "simulation": first.get("simulation"),
    }


def run(args: argparse.Namespace, command: str) -> dict[str, Any]:
    sizes = [int(s) for s in args.sizes.split(",") if s]
    cases = [(scene, n, BUILDERS[scene](n)) for scene in args.scenes.split(",") for n in sizes]
    raw: dict[str, list[dict[str, Any]]] = {}
    for k in range(args.runs):
        for scene, n, fmu in cases:
            print(f"run {k + 1}/{args.runs}: {scene} N = {n}", file=sys.stderr, flush=True)
            raw.setdefault(f"{scene}:{n}", []).append(run_case(fmu))
            if args.one_worker and variables(fmu) >= LARGE_MODEL:
                raw.setdefault(f"one:{scene}:{n}", []).append(
                    run_case(fmu, extra=["--probe-workers", "1"]))
            if args.baseline and scene == "Chain":
                raw.setdefault(f"baseline:{n}", []).append(run_case(fmu, args.baseline))
    results = []
    for scene, n, fmu in cases:
        results.append({"scene": scene, "n": n, "nnz": structural_nonzeros(fmu),
                        **summarise(raw[f"{scene}:{n}"])})
    baseline = [{"scene": "Chain", "n": n, **summarise(raw[f"baseline:{n}"])}
                for n in sizes if f"baseline:{n}" in raw]
    one = [{"scene": scene, "n": n, **summarise(raw[f"one:{scene}:{n}"])}
           for scene, n, _ in cases if f"one:{scene}:{n}" in raw]
    return {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "machine": machine_info(), "runs": args.runs, "command": command,
            "results": results, "baseline": baseline, "baseline_tree": args.baseline or "",
            "one_worker": one,
            "targets": targets(results)}


def targets(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    by = {(r["scene"], r["n"]): r for r in results}
    for scene in dict.fromkeys(r["scene"] for r in results):
        big, mid = by.get((scene, 10000)), by.get((scene, 1000))
        if big and mid:
            ratio = big["seconds"] / mid["seconds"]
            nnz_ratio = big["nnz"] / mid["nnz"]
            out.append({"scene": scene, "target": "time(10,000) / time(1,000) <= 12",
                        "value": f"{ratio:.1f} (nonzeros {nnz_ratio:.1f}x)",
                        "met": ratio <= TARGET_RATIO})
        if big:
            out.append({"scene": scene, "target": "full check at 10,000 <= 30 s",
                        "value": f"{big['seconds']:.1f} s",
                        "met": big["seconds"] <= TARGET_SECONDS})
            out.append({"scene": scene, "target": "worker peak < 500 MiB at 10,000",
                        "value": f"{big['worker_peak_mib']:.0f} MiB",
                        "met": big["worker_peak_mib"] < TARGET_MIB})
        clean = all(not r["findings"] and r["verdicts_agree"]
                    for r in results if r["scene"] == scene)
        not_run = sum(len(r["rules_not_run"]) for r in results if r["scene"] == scene)
        out.append({"scene": scene, "target": "0 findings at every N (same in every run)",
                    "value": "0" if clean else "findings", "met": clean})
        out.append({"scene": scene, "target": "rules not run (not a target: shown)",
                    "value": str(not_run), "met": None})
    return out


# ------------------------------------------------------------------------------ the report

def _families(results: Sequence[dict[str, Any]]) -> list[str]:
    """Every family a case logged, in the order the worker ran them (setup first)."""
    order: dict[str, None] = {}
    for r in results:
        order.update(dict.fromkeys(r["families"]))
    return list(order)


def _lanes(r: dict[str, Any]) -> str:
    """Each worker's seconds, "a + b" where two ran at once."""
    return " + ".join(f"{s:.2f}" for s in r.get("lane_seconds") or [r["worker_seconds"]])


def _family_line(r: dict[str, Any], families: Sequence[str]) -> str:
    cells = []
    for name in families:
        f = r["families"].get(name)
        cells.append("–" if f is None else
                     f"{f['seconds']:.2f} ({f['fmi_seconds']:.2f}) / {int(f['calls']):,} / "
                     f"{f['peak_rss'] / MIB:.0f}")
    return f"| {r['scene']} | {r['n']:,} | " + " | ".join(cells) + " |"


def render_markdown(data: dict[str, Any]) -> str:
    mach = data["machine"]
    families = _families(data["results"])
    lines = [
        "# Scale benchmark: the full check against the number of variables",
        "",
        f"Run {data['date']} on {mach['cpu']} ({mach['usable_cores']} usable cores), "
        f"{mach['platform']}, Python {mach['python']}. `{data['command']}`: every case in a "
        f"fresh process running `lsdae check FMU` with the default options (probes, quick "
        f"endurance, simulation), medians of {data['runs']} interleaved runs. The machine is "
        "shared: *load* is the 1-minute load average around the case (2 cores: above 2 the "
        "check had less than a core).",
        "",
        "Chain: N algebraic variables in a chain (tridiagonal dg/dw, 3N + 3 declared nonzeros). "
        "Blocks: N algebraic variables in blocks of 10, each residual on its own block and the "
        "two beside it (about 30N nonzeros; `scenes/Blocks/README.md`). Both are correct: any "
        "finding is a false positive.",
        "",
        "## The whole check",
        "",
        "| scene | N | nonzeros | full check (s) | runs (s) | probe workers (s) | in the binary "
        "(s) | worker peak (MiB) | parent peak (MiB) | findings | rules not run | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["results"]:
        lines.append(
            f"| {r['scene']} | {r['n']:,} | {r['nnz']:,} | {r['seconds']:.2f} | "
            f"{', '.join(f'{s:.1f}' for s in r['seconds_all'])} | {_lanes(r)} | "
            f"{r['fmi_seconds']:.2f} | {r['worker_peak_mib']:.0f} | "
            f"{r['parent_peak_mib']:.0f} | {len(r['findings'])} | {len(r['rules_not_run'])} | "
            f"{r['load']:.1f} |")
    lines += ["", "*probe workers*: each worker's steps added up; two figures where two workers "
              "ran at once (1,000 variables or more, `conformance/probes/machinery/lanes.py`). "
              "*worker peak*: the larger worker's."]
    lines += ["", "## Targets (issue 22)", "", "| scene | target | measured | met |",
              "|---|---|---|---|"]
    for t in data["targets"]:
        met = "–" if t["met"] is None else ("yes" if t["met"] else "**no**")
        lines.append(f"| {t['scene']} | {t['target']} | {t['value']} | {met} |")
    if data.get("one_worker"):
        lines += ["", "## Two workers against one", "",
                  "The same FMUs, checked in the same runs, interleaved (medians): the default "
                  "(two workers at once from 1,000 variables) and `--probe-workers 1`.", "",
                  "| scene | N | two workers (s) | one worker (s) | one / two | the one "
                  "worker's steps (s) | findings the same |", "|---|---|---|---|---|---|---|"]
        ours = {(r["scene"], r["n"]): r for r in data["results"]}
        for o in data["one_worker"]:
            r = ours[(o["scene"], o["n"])]
            same = [f["code"] for f in o["findings"]] == [f["code"] for f in r["findings"]]
            lines.append(f"| {o['scene']} | {o['n']:,} | {r['seconds']:.2f} | "
                         f"{o['seconds']:.2f} | {o['seconds'] / r['seconds']:.2f} | "
                         f"{_lanes(o)} | {'yes' if same else '**no**'} |")
    if data.get("baseline"):
        lines += ["", f"## Side by side: the Chain with `{data['baseline_tree']}`", "",
                  "The same FMUs, checked in the same runs, interleaved (medians). The issue's "
                  "false verdicts are those of this baseline.", "",
                  "| N | this tree (s) | baseline (s) | ratio | baseline parent peak (MiB) | "
                  "baseline findings | baseline rules not run |", "|---|---|---|---|---|---|---|"]
        ours = {r["n"]: r for r in data["results"] if r["scene"] == "Chain"}
        for b in data["baseline"]:
            o = ours.get(b["n"])
            names = ", ".join(sorted({f["name"] for f in b["findings"]})) or "none"
            lines.append(
                f"| {b['n']:,} | {o['seconds']:.2f} | {b['seconds']:.2f} | "
                f"{b['seconds'] / o['seconds']:.2f} | {b['parent_peak_mib']:.0f} | {names} | "
                f"{len(b['rules_not_run'])} |" if o else f"| {b['n']:,} | – | {b['seconds']:.2f} "
                f"| – | {b['parent_peak_mib']:.0f} | {names} | {len(b['rules_not_run'])} |")
        lines += ["", "A tree that does not log its probe steps (the baseline) shows no worker "
                  "figures; its parent's peak is given instead."]
    lines += [
        "", "## Per probe family", "",
        "Each cell: seconds (of which inside the binary's functions) / FMI calls / the "
        "worker's peak resident size during the family (MiB), medians. *setup*: loading the "
        "binary, DAE and ODE instances, sampling the points (in each worker: two where two "
        "ran). The families of the two workers run at the same time; the rest of the full check "
        "is the static stage, the workers' start and the report.",
        "", "| scene | N | " + " | ".join(families) + " |",
        "|---|---|" + "---|" * len(families)]
    lines += [_family_line(r, families) for r in data["results"]]
    lines += ["", "![time and memory against the nonzeros](scale.png)", ""]
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    import matplotlib  # heavy: only to draw

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # after use("Agg")

    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(16, 4.8))
    scenes = list(dict.fromkeys(r["scene"] for r in data["results"]))
    for scene, marker in zip(scenes, "os^"):
        rows = sorted((r for r in data["results"] if r["scene"] == scene), key=lambda r: r["nnz"])
        nnz = [r["nnz"] for r in rows]
        line, = left.loglog(nnz, [r["seconds"] for r in rows], marker + "-", label=scene)
        if len(rows) > 1:   # linear growth from the middle size, for reference
            ref = rows[len(rows) // 2]
            left.loglog(nnz, [ref["seconds"] * n / ref["nnz"] for n in nnz], ":",
                        color=line.get_color(), label=f"{scene}: linear in nonzeros")
        middle.loglog(nnz, [r["worker_peak_mib"] for r in rows], marker + "-", label=scene)
    if data.get("baseline"):
        rows = sorted(data["baseline"], key=lambda r: r["n"])
        nnz = [3 * r["n"] + 3 for r in rows]
        left.loglog(nnz, [r["seconds"] for r in rows], "x--", color="grey",
                    label="Chain, baseline tree")
    left.axhline(TARGET_SECONDS, color="red", linewidth=0.8, linestyle="--", label="30 s")
    left.set_xlabel("structural nonzeros of the DAE Jacobian")
    left.set_ylabel("full check (s)")
    left.set_title("Time")
    left.legend(fontsize=7)
    middle.axhline(TARGET_MIB, color="red", linewidth=0.8, linestyle="--", label="500 MiB")
    middle.set_xlabel("structural nonzeros of the DAE Jacobian")
    middle.set_ylabel("worker peak resident size (MiB)")
    middle.set_title("Memory")
    middle.legend(fontsize=8)
    largest = [r for r in data["results"] if r["n"] == max(x["n"] for x in data["results"])]
    bottom = [0.0] * len(largest)
    colours = plt.get_cmap("tab20").colors
    for k, name in enumerate(_families(data["results"])):
        heights = [r["families"].get(name, {}).get("seconds", 0.0) for r in largest]
        if any(heights):
            right.bar([f"{r['scene']}\nN = {r['n']:,}" for r in largest], heights,
                      bottom=bottom, label=name, color=colours[k % len(colours)])
            bottom = [b + h for b, h in zip(bottom, heights)]
    right.set_ylabel("seconds in the worker")
    right.set_title("Probe families at the largest N")
    right.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.scale_bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"))
    parser.add_argument("--sizes", default="100,1000,10000")
    parser.add_argument("--scenes", default="Chain,Blocks")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--one-worker", action="store_true",
                        help="also check the cases of 1,000 variables or more with one worker")
    parser.add_argument("--baseline", default="",
                        help="another checkout whose code checks the Chain side by side")
    args = parser.parse_args(argv)
    command = " ".join(["python -m bench.scale_bench",
                        *(sys.argv[1:] if argv is None else list(argv))])
    result = run(args, command)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scale.json").write_text(json.dumps(result, indent=2) + "\n")
    (args.out / "scale.md").write_text(render_markdown(result))
    plot(result, args.out / "scale.png")
    print(render_markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
