"""``python -m bench.mutation``: run the campaign and write its report.

    python -m bench.mutation --out reports/mutation            # the whole campaign
    python -m bench.mutation --targets SimpleDAE/model.c --per-target 5 --sweep none
    python -m bench.mutation --list                             # targets and their mutant counts
    python -m bench.mutation --rescore reports/mutation/campaign.json   # verdicts edited: report again

Exit status 1 when a survivor is UNEXPLAINED (no verdict in verdicts.toml) or CONTRADICTED (a
consistent model change that breaks a promise); ``--stubs FILE`` then writes suggested entries
for them, to be reviewed and moved into verdicts.toml.
"""
from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Sequence

import conformance

from .campaign import REPO_ROOT, Cache, Runner, run_all
from .checking import MAIN, SETTINGS
from .generate import generate, sample, universalmutator_version
from .report import classify, rule_kills, tally, unexplained, write
from .sweep import run_sweep
from .targets import all_targets, describe
from .verdicts import DEFAULT_FILE, Verdict, VerdictError, load, stub

SWEEP_DEFAULT = "off,quick,long,budget-low,budget-high,seeds-3"


def _args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m bench.mutation", description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, default=0, help="seed of the sample (default 0)")
    p.add_argument("--per-target", type=int, default=25,
                   help="mutants sampled per scene file (default 25)")
    p.add_argument("--per-group", type=int, default=20,
                   help="mutants sampled per framework group (default 20)")
    p.add_argument("--targets", nargs="*", help="only these targets (names as --list shows)")
    p.add_argument("-j", "--jobs", type=int, default=2, help="parallel workers (default 2)")
    p.add_argument("--sweep", default=SWEEP_DEFAULT,
                   help=f"settings of the detection-against-time sweep, or 'none' "
                   f"(default {SWEEP_DEFAULT}; known: {', '.join(SETTINGS)})")
    p.add_argument("--sweep-count", type=int, default=40,
                   help="mutants in the sweep, a seeded subset of the built non-equivalent "
                   "ones (default 40)")
    p.add_argument("--out", type=Path, default=REPO_ROOT / "reports" / "mutation")
    p.add_argument("--fresh", action="store_true", help="ignore cached oracle and check "
                   "results (timings all of this run)")
    p.add_argument("--verdicts", type=Path, default=DEFAULT_FILE)
    p.add_argument("--stubs", type=Path, help="write suggested verdicts for the unexplained "
                   "and contradicted survivors to this file")
    p.add_argument("--list", action="store_true", help="list the targets and stop")
    p.add_argument("--rescore", type=Path, metavar="CAMPAIGN_JSON",
                   help="no checks: read a campaign.json, apply the current verdicts, and "
                   "write the report again (to --out)")
    p.add_argument("-v", "--verbose", action="store_true", help="log every mutant")
    return p.parse_args(argv)


def _git_commit() -> str:
    proc = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO_ROOT,
                          capture_output=True, text=True, check=False)
    return proc.stdout.strip() or "unknown"


def main(argv: Sequence[str] | None = None) -> int:
    args = _args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(message)s")
    try:
        verdicts = load(args.verdicts)
    except VerdictError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.rescore:
        data = json.loads(args.rescore.read_text())
        generated = {row["target"]: row["generated"] for row in data["targets"][:-1]}
        data.setdefault("covered", describe([t for t in all_targets() if t.name in generated]))
        return finish(data, data["mutants"], generated, verdicts, args)
    targets = [t for t in all_targets() if not args.targets or t.name in args.targets]
    if args.targets and len(targets) != len(set(args.targets)):
        print(f"error: unknown target in {args.targets}", file=sys.stderr)
        return 2
    sweep_settings = [] if args.sweep == "none" else args.sweep.split(",")
    if any(s not in SETTINGS for s in sweep_settings):
        print(f"error: --sweep takes settings among {', '.join(SETTINGS)}", file=sys.stderr)
        return 2
    started, load_start = time.perf_counter(), os.getloadavg()
    generated: dict[str, int] = {}
    chosen = []
    for t in targets:
        mutants = generate(t, jobs=args.jobs)
        generated[t.name] = len(mutants)
        count = args.per_group if t.functions else args.per_target
        picked = sample(mutants, count, seed=args.seed, target=t.name)
        chosen += picked
        if args.list:
            print(f"{t.name:28} host {t.host:14} {len(mutants):5} mutants, {len(picked)} sampled")
    if args.list:
        return 0
    t_generated = time.perf_counter()
    runner = Runner(Cache(fresh=args.fresh))
    records = run_all(runner, chosen, jobs=args.jobs)
    t_main = time.perf_counter()
    sweep = run_sweep(runner, records, sweep_settings, count=args.sweep_count, seed=args.seed,
                      jobs=args.jobs) if sweep_settings else None
    finished = time.perf_counter()
    checked = sum(r["outcome"] != "stillborn" for r in records)
    sweep_checks = (sweep["count"] * len(sweep_settings)) if sweep else 0
    meta: dict[str, Any] = {
        "seed": args.seed, "main": MAIN, "per_target": args.per_target,
        "per_group": args.per_group, "jobs": args.jobs, "commit": _git_commit(),
        "lsdae": conformance.__version__, "universalmutator": universalmutator_version(),
        "fresh": args.fresh, "seconds": {"generate": round(t_generated - started, 1),
                                         "campaign": round(t_main - t_generated, 1),
                                         "sweep": round(finished - t_main, 1),
                                         "total": round(finished - started, 1)}}
    meta["table"] = [
        ("seed", args.seed), ("sample", f"{args.per_target} per scene file, {args.per_group} "
                              "per framework group"),
        ("main setting", SETTINGS[MAIN].label), ("lsdae", f"{meta['lsdae']} at {meta['commit']}"),
        ("universalmutator", meta["universalmutator"]),
        ("machine", f"{platform.machine()}, {os.cpu_count()} CPUs, -j {args.jobs}, load "
                    f"{load_start[0]:.1f} at the start, {os.getloadavg()[0]:.1f} at the end"),
        ("run time", f"{meta['seconds']['total'] / 60:.1f} min (generation "
                     f"{meta['seconds']['generate']:.0f} s, campaign "
                     f"{meta['seconds']['campaign']:.0f} s, sweep {meta['seconds']['sweep']:.0f} s"
                     f"{', results partly from the cache' if not args.fresh else ''})"),
        ("lsdae checks", f"{checked} mutants at the main setting, {sweep_checks} in the sweep")]
    for rec in records:
        rec.pop("fmu", None)
    data = {"meta": meta, "covered": describe(targets), "sweep": sweep}
    return finish(data, records, generated, verdicts, args)


def finish(data: dict[str, Any], records: list[dict[str, Any]], generated: dict[str, int],
           verdicts: dict[str, Verdict], args: argparse.Namespace) -> int:
    """Explain the survivors, compute the tables, write the report, print the verdict."""
    classify(records, verdicts)
    data.update(targets=tally(records, generated), rules=rule_kills(records), mutants=records)
    write(data, args.out)
    total = data["targets"][-1]
    score = "n/a" if total["score"] is None else f"{100 * total['score']:.1f} %"
    print(f"{total['sampled']} mutants: {total['stillborn']} stillborn, {total['equivalent']} "
          f"equivalent, {total['killed']} killed, {total['survived']} survived "
          f"({total['missed-defect']} missed defects); score {score}; report in {args.out}")
    bad = unexplained(records)
    for r in bad:
        print(f"{r['explained']}: {r['id']}: {r['mutated'].strip()}"
              + (f"  [breaks: {'; '.join(r['promises'])}]" if r.get("promises") else ""))
    if bad and args.stubs:
        args.stubs.parent.mkdir(parents=True, exist_ok=True)
        args.stubs.write_text("\n".join(stub(r) for r in bad))
        print(f"suggested verdicts for review: {args.stubs}")
    return 1 if bad else 0
