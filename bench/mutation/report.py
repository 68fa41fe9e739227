"""The campaign's numbers, computed from the records (never written by hand), and its report:
``campaign.json`` (every record), ``summary.md`` (the tables), ``detection-vs-time.png``.

Score = killed / (killed + missed), missed being the survivors whose recorded verdict is
``missed-defect``; unexplained survivors are shown apart and keep the score from being final.
"""
from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from .sweep import plot
from .verdicts import CLASSES, Verdict, explain

TIMING_RULES = {"DAE702", "DAE804"}   # verdicts that depend on the machine's speed
OUTCOMES = ("stillborn", "equivalent", "killed", "informed", "survived", "check-timeout",
            "check-failed", "internal-error")


def classify(records: list[dict[str, Any]], verdicts: dict[str, Verdict]) -> None:
    """Attach each survivor's verdict and its state (explained, UNEXPLAINED, CONTRADICTED)."""
    for rec in records:
        if rec["outcome"] == "survived":
            rec["explained"] = explain(rec, verdicts)
            verdict = verdicts.get(rec["id"])
            rec["verdict"] = verdict.to_json() if verdict else None


def unexplained(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The survivors that make the campaign fail: UNEXPLAINED or CONTRADICTED."""
    return [r for r in records if r.get("explained") in ("UNEXPLAINED", "CONTRADICTED")]


def tally(records: list[dict[str, Any]], generated: dict[str, int]) -> list[dict[str, Any]]:
    """One row per target (and a total): the counts and the score."""
    by_target: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for rec in records:
        by_target[rec["target"]].append(rec)
    rows = []
    for target in [*generated, "total"]:
        recs = records if target == "total" else by_target.get(target, [])
        counts = Counter(r["outcome"] for r in recs)
        classes = Counter((r.get("verdict") or {}).get("class", "UNEXPLAINED")
                          for r in recs if r["outcome"] == "survived")
        killed, missed = counts["killed"], classes["missed-defect"]
        rows.append({"target": target,
                     "host": recs[0]["host"] if recs and target != "total" else "",
                     "generated": sum(generated.values()) if target == "total"
                     else generated[target],
                     "sampled": len(recs), **{o: counts[o] for o in OUTCOMES},
                     **{c: classes[c] for c in (*CLASSES, "UNEXPLAINED")},
                     "score": killed / (killed + missed) if killed + missed else None,
                     "per_kill": findings_per_kill(recs)})
    return rows


def findings_per_kill(records: list[dict[str, Any]]) -> dict[str, float] | None:
    """The new error and warning findings of each killed mutant (its ``killed_by``): mean,
    median and max; one defect should be one finding (issue 29: mean <= 1.3, max <= 3)."""
    counts = sorted(len(r.get("killed_by", [])) for r in records if r["outcome"] == "killed")
    if not counts:
        return None
    mid = len(counts) // 2
    median = counts[mid] if len(counts) % 2 else (counts[mid - 1] + counts[mid]) / 2
    return {"mean": sum(counts) / len(counts), "median": median, "max": counts[-1]}


def _per_kill(value: dict[str, float] | None) -> str:
    return "-" if value is None else \
        f"{value['mean']:.2f} / {value['median']:g} / {value['max']:g}"


def rule_kills(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per rule: mutants with a new finding of it, and those it alone killed."""
    anyk: Counter[str] = Counter()
    alone: Counter[str] = Counter()
    names: dict[str, str] = {}
    for rec in records:
        if rec["outcome"] != "killed":
            continue
        codes = sorted({c for c, _, _ in rec["killed_by"]})
        for c, _, n in rec["killed_by"]:
            names[c] = n
        anyk.update(codes)
        if len(codes) == 1:
            alone[codes[0]] += 1
    return [{"code": c, "name": names[c], "killed": anyk[c], "alone": alone[c]}
            for c in sorted(anyk, key=lambda c: (-anyk[c], c))]


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f} %"


def _cell(text: str) -> str:
    return "`" + text.strip().replace("`", "'").replace("|", "\\|").replace("\n", " ⏎ ") + "`"


def markdown(data: dict[str, Any]) -> str:
    meta, rows = data["meta"], data["targets"]
    out = ["# Mutation campaign (issue 20)", "",
           "Written by `make mutation` (`python -m bench.mutation`); every number below is "
           "computed by the campaign from `campaign.json`. How to read it: `docs/mutation.md`.",
           "", "| | |", "|---|---|"]
    out += [f"| {k} | {v} |" for k, v in meta["table"]]
    if data.get("covered"):
        out += ["", "## What was mutated", "",
                "Each scene file whole (its live lines); the framework "
                "(`scenes/common/fmi3_framework.c`) in groups of functions, with their lines; why "
                "these and not others: `docs/mutation.md`.", "",
                "| target | host | functions (lines) |", "|---|---|---|"]
        out += [f"| `{c['target']}` | {c['host']} | "
                + (", ".join(f"`{f}` {a}-{b}" for f, a, b in c["functions"]) or "the whole file")
                + " |" for c in data["covered"]]
    out += ["", "## Per target", "",
            "| target | host | generated | sampled | stillborn | equivalent | killed | informed "
            "| survived (consistent / missed / undetectable / unexplained) | timeout / failed / "
            "internal | score | findings per kill (mean / median / max) |",
            "|---|---|---:|---:|---:|---:|---:|---:|---|---|---:|---:|"]
    for r in rows:
        name = f"**{r['target']}**" if r["target"] == "total" else f"`{r['target']}`"
        out.append(f"| {name} | {r['host']} | {r['generated']} | {r['sampled']} | "
                   f"{r['stillborn']} | {r['equivalent']} | {r['killed']} | {r['informed']} | "
                   f"{r['survived']} "
                   f"({r['consistent-model-change']} / {r['missed-defect']} / "
                   f"{r['undetectable']} / {r['UNEXPLAINED']}) | {r['check-timeout']} / "
                   f"{r['check-failed']} / {r['internal-error']} | {_pct(r['score'])} | "
                   f"{_per_kill(r['per_kill'])} |")
    told = [r for r in data["mutants"] if r["outcome"] == "informed"]
    if told:
        out += ["", f"## Told at information ({len(told)})", "",
                "No new error or warning, but a new finding of information: lsdae says it at "
                "the weight its text gives (docs/verdicts.md), which calls nothing "
                "non-conformant. Neither killed nor missed: outside the score.", ""]
        out += [f"- `{r['id']}`: " + "; ".join(f"{c} {n} ({s})" for c, s, n in
                                                r.get("informed_by", [])) for r in told]
    survivors = [r for r in data["mutants"] if r["outcome"] == "survived"]
    out += ["", f"## Survivors ({len(survivors)})", "",
            "Grouped by verdict; the promise a missed defect breaks, and the evidence.", ""]
    for cls in (*CLASSES, None):
        group = [r for r in survivors if ((r.get("verdict") or {}).get("class")) == cls]
        if not group:
            continue
        out += [f"### {cls or 'UNEXPLAINED'} ({len(group)})", "",
                "| mutant | line | mutated to | verdict |", "|---|---|---|---|"]
        for r in group:
            v = r.get("verdict") or {}
            why = (f"**{v['promise']}**: " if v.get("promise") else "") + v.get("reason", "")
            if r.get("explained") == "CONTRADICTED":
                why = "**CONTRADICTED** by the promise checks: " + "; ".join(r["promises"])
            out.append(f"| `{r['id']}` | {_cell(r['original'])} | {_cell(r['mutated'])} | "
                       f"{why.replace('|', '/')} |")
        out.append("")
    odd = [r for r in data["mutants"] if r.get("equivalent_but_reported") or
           r["outcome"] in ("check-timeout", "check-failed", "internal-error") or
           r["outcome"] == "killed" and {c for c, _, _ in r["killed_by"]} <= TIMING_RULES]
    if odd:
        out += ["## To look at", "",
                "Equivalent by the oracle but with new findings (a false alarm of lsdae or a "
                "blind spot of the oracle), kills by time budgets alone (DAE702, DAE804: they "
                "depend on the machine's load), checks that timed out or failed, internal "
                "errors.",
                "", "| mutant | outcome | mutated to | findings or detail |", "|---|---|---|---|"]
        for r in odd:
            detail = "; ".join(f"{c} {n} ({s})" for c, s, n in r.get("killed_by", [])) or \
                (r.get("checks", {}).get(data["meta"]["main"], {}).get("detail") or "")
            out.append(f"| `{r['id']}` | {r['outcome']} | {_cell(r['mutated'])} | "
                       f"{detail[:200].replace('|', '/')} |")
        out.append("")
    out += ["## Rules that killed", "", "A mutant killed by several rules counts for each; "
            "*alone*: the only rule with a new finding.", "",
            "| rule | name | mutants killed | alone |", "|---|---|---:|---:|"]
    out += [f"| {r['code']} | {r['name']} | {r['killed']} | {r['alone']} |"
            for r in data["rules"]]
    if data.get("sweep"):
        sw = data["sweep"]
        out += ["", "## Detection against time", "",
                f"{sw['count']} of the built, non-equivalent mutants (seeded), each checked at "
                "every setting in turn in one worker (so the load falls alike); time is the "
                "wall time of the `lsdae check` process, summed over seeds for `seeds-3`.", "",
                "| setting | what | killed | median s | p90 s | total s |",
                "|---|---|---:|---:|---:|---:|"]
        out += [f"| {r['setting']} | {r['label']} | {r['killed']}/{r['mutants']} "
                f"({_pct(r['fraction'])}) | {r['median_seconds']:.2f} | {r['p90_seconds']:.2f} "
                f"| {r['total_seconds']:.0f} |" for r in sw["rows"]]
        out += ["", "![killed fraction against median check time](detection-vs-time.png)"]
    return "\n".join(out) + "\n"


def write(data: dict[str, Any], out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "campaign.json").write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    (out / "summary.md").write_text(markdown(data))
    if data.get("sweep"):
        plot(data["sweep"], out / "detection-vs-time.png")
