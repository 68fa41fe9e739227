"""Detection against time (issue 20, point 2): the same mutants checked at several settings.

The mutants are the campaign's built, non-equivalent ones (a seeded subset of ``count`` of them
when there are more: the long endurance run costs about 20 s a check). Each is checked at every
setting of :data:`checking.SETTINGS` given, the settings of one mutant one after the other in
the same worker, so that the machine's load falls on all of them alike; the originals are
checked the same way. The oracle's results are not needed again: only the checks rerun. A
mutant counts as killed at a setting by the campaign's criterion against the original's report
at that setting.
"""
from __future__ import annotations

import logging
import random
import statistics
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from .campaign import Runner
from .checking import SETTINGS, CheckResult, outcome

log = logging.getLogger(__name__)
BUILT = ("killed", "survived", "check-timeout", "check-failed", "internal-error")


def choose(records: list[dict[str, Any]], count: int, seed: int) -> list[dict[str, Any]]:
    eligible = [r for r in records if r["outcome"] in BUILT]
    if count >= len(eligible):
        return eligible
    rng = random.Random(f"{seed}/sweep")
    return [eligible[i] for i in sorted(rng.sample(range(len(eligible)), count))]


def run_sweep(runner: Runner, records: list[dict[str, Any]], settings: list[str], *,
              count: int, seed: int, jobs: int) -> dict[str, Any]:
    chosen = choose(records, count, seed)
    hosts = sorted({r["host"] for r in chosen})
    originals: dict[tuple[str, str], CheckResult] = {}

    def host_checks(host: str) -> None:
        fmu = runner.original(host)["fmu"]
        for s in settings:
            originals[(host, s)] = runner.check(fmu, SETTINGS[s])

    def mutant_checks(rec: dict[str, Any]) -> dict[str, Any]:
        out = {}
        for s in settings:
            result = runner.check(Path(rec["fmu"]), SETTINGS[s])
            out[s] = {"outcome": outcome(originals[(rec["host"], s)], result),
                      "seconds": round(result.seconds, 3)}
        log.info("sweep %s: %s", rec["id"],
                 " ".join(f"{s}={v['outcome']}/{v['seconds']:.1f}s" for s, v in out.items()))
        return out

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        list(pool.map(host_checks, hosts))
        per_mutant = dict(zip([r["id"] for r in chosen], pool.map(mutant_checks, chosen)))
    rows = []
    for s in settings:
        seconds = [per_mutant[r["id"]][s]["seconds"] for r in chosen]
        killed = sum(per_mutant[r["id"]][s]["outcome"] == "killed" for r in chosen)
        rows.append({"setting": s, "label": SETTINGS[s].label, "mutants": len(chosen),
                     "killed": killed, "fraction": killed / len(chosen) if chosen else 0.0,
                     "median_seconds": statistics.median(seconds) if seconds else 0.0,
                     "p90_seconds": sorted(seconds)[int(0.9 * (len(seconds) - 1))]
                     if seconds else 0.0,
                     "total_seconds": sum(seconds),
                     "original_seconds": {h: round(originals[(h, s)].seconds, 3)
                                          for h in hosts}})
    return {"count": len(chosen), "seed": seed, "rows": rows, "mutants": per_mutant}


def plot(sweep: dict[str, Any], path: Path) -> None:
    """Killed fraction against the median check time per mutant, one point per setting."""
    import matplotlib  # lazy: only the report of a sweep draws

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=110)
    for row in sweep["rows"]:
        ax.scatter(row["median_seconds"], 100 * row["fraction"], s=36)
        ax.annotate(row["setting"], (row["median_seconds"], 100 * row["fraction"]),
                    textcoords="offset points", xytext=(6, 4), fontsize=9)
    ax.set_xscale("log")
    ax.set_ylim(0, 100)
    ax.set_xlabel("median lsdae check time per mutant [s] (log scale)")
    ax.set_ylabel("mutants killed [%]")
    ax.set_title(f"Detection against time ({sweep['count']} mutants, the same at every setting)",
                 fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
