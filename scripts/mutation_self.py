"""Mutation testing of lsdae's own Python code with mutmut 3 (``make mutation-self``).

Each package is mutated on its own, in ``build/mutation-self/<package>/`` (links to the tree and
a ``pyproject.toml`` holding mutmut's settings for that package), and a mutant is run against
the package's own tests only (:data:`PACKAGES`); a mutant is killed when a test fails::

    python -m scripts.mutation_self --packages numerics            # its default sample
    python -m scripts.mutation_self --packages model --sample 300 --seed 1
    python -m scripts.mutation_self --packages numerics --sample 0 # every mutant
    python -m scripts.mutation_self --report-only                  # verdicts edited: report again
    python -m scripts.mutation_self --list                         # packages, tests, sample sizes

mutmut keeps its results in ``mutants/`` of the work folder and runs again only the mutants of
functions that changed; ``--fresh`` starts over. The report, ``reports/mutation-self/``
(``summary.md``, ``results.json``), is computed from mutmut's per-mutant results; the verdicts on
survivors come from ``bench/mutation_self_verdicts.toml``. Exit status 1 while a survivor is
unexplained (no verdict, or a verdict whose mutated line no longer matches). docs/mutation-self.md.
"""
from __future__ import annotations

import argparse
import ast
import json
import os
import random
import shutil
import subprocess
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
WORK = ROOT / "build" / "mutation-self"
VERDICTS = ROOT / "bench" / "mutation_self_verdicts.toml"
LINKED = ("conformance", "tests", "scenes", "rules", "schemas", "bench")  # in each work folder
PYTEST_ARGS = ["-p", "no:xdist", "-p", "no:cacheprovider", "--hypothesis-seed=0"]
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@dataclass(frozen=True)
class Package:
    mutate: tuple[str, ...]       # globs of the files mutated (mutmut's only_mutate)
    tests: tuple[str, ...]        # what pytest runs (mutmut's pytest_add_cli_args_test_selection)
    skip: tuple[str, ...] = ()    # globs never mutated (mutmut's do_not_mutate)
    sample: int | None = None     # mutants run by default (a seeded sample; None: every one)


def _whole(name: str) -> Package:
    return Package((f"conformance/{name}/*",), (f"tests/{name}",))


PACKAGES: dict[str, Package] = {
    **{name: _whole(name) for name in ("checks", "model", "intake", "report", "reporters",
                                       "fixes", "run", "commands")},
    # tests/numerics and the in-process tests of the simulation built on it (about 25 s in all;
    # the FMU simulations of tests/simulate/test_fmu_simulation.py are left out). About 5,000
    # mutants at about 1 s each on one process: a sample of 500 takes about 10 minutes.
    "numerics": Package(("conformance/numerics/*",),
                        ("tests/numerics", "tests/simulate/test_system.py",
                         "tests/probes/test_simulation_parts.py",
                         "tests/checks/test_option_defaults.py"), sample=500),
    # The pure parts only (no FMU binary, no worker process: mutmut sees only what runs in the
    # test process). Provisional: not yet run; to be settled by the session that runs them.
    "probes": Package(("conformance/probes/instruments/sampling.py",
                       "conformance/probes/instruments/jacobian_layout.py",
                       "conformance/probes/machinery/lanes.py",
                       "conformance/probes/machinery/narrowing.py"),
                      ("tests/probes/test_lanes.py", "tests/probes/test_runner.py")),
    "simulate": Package(("conformance/simulate/system.py", "conformance/simulate/output.py"),
                        ("tests/simulate/test_system.py",)),
}

# mutmut's status names -> our outcomes; a timeout counts as killed but is shown apart
OUTCOME = {"killed": "killed", "segfault": "killed", "caught by type check": "killed",
           "timeout": "timeout", "survived": "survived", "no tests": "survived"}
SURVIVOR_CODES = (0, 5, 33)   # mutmut's exit codes of survived and no tests


# ------------------------------------------------------------------ running mutmut

def _mutmut() -> str:
    beside = Path(sys.executable).with_name("mutmut")
    return str(beside) if beside.exists() else (shutil.which("mutmut") or "mutmut")


def _toml(value: Any) -> str:
    return json.dumps(value)   # strings and lists of strings read the same in TOML


def config_text(pkg: Package) -> str:
    """The work folder's pyproject.toml: mutmut's settings and the project's pytest options."""
    pytest_opts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]
    mutmut = {"source_paths": ["conformance"], "only_mutate": list(pkg.mutate),
              "do_not_mutate": list(pkg.skip),
              "pytest_add_cli_args_test_selection": list(pkg.tests),
              "pytest_add_cli_args": PYTEST_ARGS, "also_copy": list(LINKED[2:])}
    lines = ["# written by scripts/mutation_self.py; edit PACKAGES there", "[tool.mutmut]"]
    lines += [f"{k} = {_toml(v)}" for k, v in mutmut.items()]
    lines += ["", "[tool.pytest.ini_options]"]
    lines += [f"{k} = {_toml(v)}" for k, v in pytest_opts["ini_options"].items()]
    return "\n".join(lines) + "\n"


def prepare(name: str, fresh: bool) -> Path:
    """The package's work folder; its mutants/ goes when mutmut's settings changed (mutmut
    would keep results of the old test selection for functions that did not change) or
    ``fresh``."""
    work = WORK / name
    config = work / "pyproject.toml"
    text = config_text(PACKAGES[name])
    if fresh or not config.is_file() or config.read_text() != text:
        shutil.rmtree(work / "mutants", ignore_errors=True)
    work.mkdir(parents=True, exist_ok=True)
    config.write_text(text)
    for entry in LINKED:
        link = work / entry
        if not link.is_symlink():
            link.symlink_to(os.path.relpath(ROOT / entry, work))
    return work


def _env() -> dict[str, str]:
    """Scenes built by tests go to the tree's cache, not to each copy's. BLAS runs on one
    thread: mutmut forks each mutant's test process from a process that has run the tests, and
    a child forked while OpenBLAS's threads exist can hang on a lock (a test of conformance/
    numerics/dae.py then ends as a false ``timeout``, which counts as killed)."""
    return {**os.environ, **{v: "1" for v in BLAS_THREADS},
            "LSDAE_SCENE_CACHE": os.environ.get("LSDAE_SCENE_CACHE")
            or str(ROOT / ".cache" / "scenes")}


# mutmut 3 has no command that only writes the mutants; this is the first step of `mutmut run`
# (mutmut/__main__.py, _run), which keeps the results of the functions that did not change.
GENERATE = ("import mutmut.__main__ as m, pathlib; pathlib.Path('mutants').mkdir(exist_ok=True); "
            "m.copy_src_dir(); m.copy_also_copy_files(); m.setup_source_paths(); "
            "m.create_mutants(1)")


def generate(work: Path) -> None:
    subprocess.run([sys.executable, "-c", GENERATE], cwd=work, env=_env(), check=True,
                   stdout=subprocess.DEVNULL)


def statuses(work: Path) -> dict[str, tuple[int | None, float | None]]:
    """Every mutant's exit code and test time, from mutmut's ``mutants/**/*.py.meta``."""
    out: dict[str, tuple[int | None, float | None]] = {}
    for meta in sorted((work / "mutants").rglob("*.py.meta")):
        data = json.loads(meta.read_text())
        for key, code in data["exit_code_by_key"].items():
            out[key] = (code, data["durations_by_key"].get(key))
    return out


def sample(names: Sequence[str], count: int | None, seed: int, package: str) -> list[str]:
    """The first ``count`` of the names (sorted) shuffled by ``random.Random("<seed>/<package>")``
    (all when None): a larger sample of the same seed holds the smaller one."""
    order = sorted(names)
    random.Random(f"{seed}/{package}").shuffle(order)
    return sorted(order if count is None else order[:count])


def run(work: Path, names: list[str] | None, children: int) -> None:
    """``mutmut run``: every mutant not yet run (``names`` None), or these by name."""
    cmd = [_mutmut(), "run", "--max-children", str(children), *(names or [])]
    subprocess.run(cmd, cwd=work, env=_env(), check=True)


# What `mutmut show NAME` prints below its header line, for many mutants in one process
# (`mutmut show` takes a second or two per mutant, most of it starting up).
SHOW = ("import json, sys; from mutmut.mutation.diff_apply import find_mutant, "
        "get_diff_for_mutant as d; json.dump({n: d(n, path=find_mutant(n).path) "
        "for n in json.load(sys.stdin)}, sys.stdout)")


def diffs(work: Path, names: list[str]) -> dict[str, str]:
    if not names:
        return {}
    done = subprocess.run([sys.executable, "-c", SHOW], cwd=work, env=_env(), check=True,
                          input=json.dumps(names), capture_output=True, text=True)
    return json.loads(done.stdout)


def changed_lines(text: str) -> tuple[list[str], list[str]]:
    """The removed and the added lines of a diff, stripped."""
    body = [line for line in text.splitlines() if not line.startswith(("---", "+++"))]
    return ([line[1:].strip() for line in body if line.startswith("-")],
            [line[1:].strip() for line in body if line.startswith("+")])


# ------------------------------------------------------------------ names and places

def split_name(name: str) -> tuple[str, str]:
    """``conformance.numerics.limits.x_f__mutmut_3`` -> (module, function ``f`` or ``C.m``)."""
    parts = name.split(".")
    i = max(k for k, p in enumerate(parts) if p.startswith(("x_", "xǁ")))
    mangled = ".".join(parts[i:]).partition("__mutmut_")[0]
    function = mangled[2:] if mangled.startswith("x_") else ".".join(mangled.split("ǁ")[1:3])
    return ".".join(parts[:i]), function


def module_path(module: str) -> str:
    path = Path(*module.split("."))
    return (path / "__init__.py" if (ROOT / path).is_dir() else path.with_suffix(".py")).as_posix()


def source_line(module: str, function: str, removed: list[str]) -> int | None:
    """The line of the source file the mutant changes: the first removed line, looked for
    inside the function."""
    tree = ast.parse((ROOT / module_path(module)).read_text())
    *outer, last = function.split(".")
    body = tree.body
    for cls in outer:
        body = next((n.body for n in body if isinstance(n, ast.ClassDef) and n.name == cls), [])
    node = next((n for n in body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
                 and n.name == last), None)
    if node is None or not removed:
        return None
    lines = (ROOT / module_path(module)).read_text().splitlines()
    for number in range(node.lineno, (node.end_lineno or node.lineno) + 1):
        if lines[number - 1].strip() == removed[0]:
            return number
    return None


# ------------------------------------------------------------------ verdicts

class VerdictError(ValueError):
    """mutation_self_verdicts.toml is malformed."""


def load_verdicts(path: Path = VERDICTS) -> dict[str, dict[str, str]]:
    """``[verdict."<mutant>"]`` with ``verdict`` (equivalent or open), ``mutated`` (the lines
    the mutant adds, stripped and joined by `` / ``: the report's *mutated* column) and
    ``reason`` (required for equivalent)."""
    if not path.is_file():
        return {}
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8")).get("verdict", {})
    except tomllib.TOMLDecodeError as exc:
        raise VerdictError(f"{path}: {exc}") from None
    for key, entry in table.items():
        if entry.get("verdict") not in ("equivalent", "open") or "mutated" not in entry:
            raise VerdictError(f"{path}: {key!r} needs verdict (equivalent or open) and mutated")
        if entry["verdict"] == "equivalent" and not entry.get("reason"):
            raise VerdictError(f"{path}: equivalent {key!r} needs a reason")
        if entry.get("reason", "").startswith("REVIEW"):
            raise VerdictError(f"{path}: {key!r} is a stub nobody reviewed (reason REVIEW)")
    return table


def stub(record: dict[str, Any]) -> str:
    """An entry for an unexplained survivor, to be reviewed and moved into the verdicts."""
    return "\n".join([f"[verdict.{json.dumps(record['name'], ensure_ascii=False)}]",
                      'verdict = "open"   # or "equivalent"',
                      f"mutated = {json.dumps(' / '.join(record['added']), ensure_ascii=False)}",
                      f'reason = "REVIEW: {record["module"]}:{record["line"] or "?"}"', ""])


def judge(record: dict[str, Any], verdicts: dict[str, dict[str, str]]) -> None:
    """A survivor's verdict: the recorded one when its mutated line is still the mutant's,
    else ``unexplained`` (mutmut numbers the mutants of a function anew when it changes)."""
    entry = verdicts.get(record["name"])
    mutated = " / ".join(record["added"])
    if entry is None:
        record.update(verdict="unexplained", reason="")
    elif entry["mutated"].strip() != mutated:
        record.update(verdict="unexplained", reason=f"stale verdict: it was recorded for "
                      f"`{entry['mutated']}`, the mutant now reads `{mutated}`")
    else:
        record.update(verdict=entry["verdict"], reason=entry.get("reason", ""))


# ------------------------------------------------------------------ the numbers

def records_of(package: str, work: Path, chosen: list[str],
               verdicts: dict[str, dict[str, str]]) -> list[dict[str, Any]]:
    from mutmut.stats import status_by_exit_code   # mutmut's own reading of its exit codes
    found = statuses(work)
    shown = diffs(work, [n for n in chosen if status_by_exit_code[found[n][0]] != "killed"])
    out = []
    for name in chosen:
        code, seconds = found[name]
        status = status_by_exit_code[code]
        module, function = split_name(name)
        rec = {"name": name, "package": package, "module": module_path(module),
               "function": function, "status": status, "seconds": seconds,
               "outcome": OUTCOME.get(status, "other")}
        if rec["outcome"] != "killed":
            rec["diff"] = shown[name]
            rec["removed"], rec["added"] = changed_lines(rec["diff"])
            rec["line"] = source_line(module, function, rec["removed"])
        if rec["outcome"] == "survived":
            judge(rec, verdicts)
        out.append(rec)
    return out


def tally(records: list[dict[str, Any]], key: str,
          generated: Counter[str]) -> list[dict[str, Any]]:
    """One row per package or module (and a total). Score = (killed + timeout) / (mutants -
    equivalent - other): equivalent survivors and mutants mutmut could not judge are left out."""
    groups: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for rec in records:
        groups[rec[key]].append(rec)
    rows = []
    for name in [*sorted(groups), "total"]:
        recs = records if name == "total" else groups[name]
        out = Counter(r["outcome"] for r in recs)
        verdict = Counter(r.get("verdict") for r in recs if r["outcome"] == "survived")
        judged = len(recs) - verdict["equivalent"] - out["other"]
        rows.append({key: name, "generated": sum(generated.values()) if name == "total"
                     else generated[name], "mutants": len(recs), "killed": out["killed"],
                     "timeout": out["timeout"], "survived": out["survived"],
                     "equivalent": verdict["equivalent"], "open": verdict["open"],
                     "unexplained": verdict["unexplained"], "other": out["other"],
                     "score": (out["killed"] + out["timeout"]) / judged if judged else None})
    return rows


# ------------------------------------------------------------------ the report

def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f} %"


def _cell(text: str) -> str:
    return "`" + text.replace("`", "'").replace("|", "\\|") + "`" if text else ""


def _table(rows: list[dict[str, Any]], key: str) -> list[str]:
    out = [f"| {key} | generated | mutants | killed | timeout | survived | equivalent | open | "
           "unexplained | other | score |", "|---|" + "---:|" * 10]
    for r in rows:
        name = "**total**" if r[key] == "total" else f"`{r[key]}`"
        out.append(f"| {name} | {r['generated']} | {r['mutants']} | {r['killed']} | "
                   f"{r['timeout']} | {r['survived']} | {r['equivalent']} | {r['open']} | "
                   f"{r['unexplained']} | {r['other']} | {_pct(r['score'])} |")
    return out


def markdown(data: dict[str, Any]) -> str:
    meta = data["meta"]
    out = ["# Mutation testing of lsdae's own code", "",
           "Written by `make mutation-self` (`python -m scripts.mutation_self`); every number is "
           "computed from mutmut's per-mutant results (`results.json`). How to read it and how to "
           "add a verdict: `docs/mutation-self.md`.", "", "| | |", "|---|---|"]
    out += [f"| {k} | {v} |" for k, v in meta["table"]]
    out += ["", "Score = (killed + timeout) / (mutants - equivalent - other). *killed*: a test "
            "failed; *timeout*: the tests ran over mutmut's time limit (listed below: check that "
            "they are real); *survived*: every test passed, or no selected test runs the "
            "function (mutmut's `no tests`); *other*: mutmut could not judge (not checked, "
            "suspicious).",
            "", "## Per package", "", *_table(data["packages"], "package"),
            "", "## Per module", "", *_table(data["modules"], "module"), "",
            "## Tests run per package", "", "*last run*: its time and the mutants it ran "
            "(mutmut runs only those without a result); *mutant time*: mutmut's test time of "
            "the mutants reported.", "",
            "| package | mutated | tests | last run s | mutants run | mutant time s |",
            "|---|---|---|---:|---:|---:|"]
    out += [f"| `{p}` | {', '.join(_cell(g) for g in s['mutate'])} | "
            f"{', '.join(_cell(t) for t in s['tests'])} | {s['seconds']:.0f} | "
            f"{s['mutants_run']} | {s['test_seconds']:.0f} |"
            for p, s in meta["selection"].items()]
    survivors = [r for r in data["mutants"] if r["outcome"] == "survived"]
    out += ["", f"## Survivors ({len(survivors)})", ""]
    for verdict in ("unexplained", "open", "equivalent"):
        group = [r for r in survivors if r["verdict"] == verdict]
        if not group:
            continue
        out += [f"### {verdict} ({len(group)})", "",
                "| mutant | status | line | original | mutated | reason |",
                "|---|---|---|---|---|---|"]
        out += [f"| `{r['name']}` | {r['status']} | {r['module']}:{r['line'] or '?'} | "
                f"{_cell(' / '.join(r['removed']))} | {_cell(' / '.join(r['added']))} | "
                f"{r['reason'].replace('|', '/')} |" for r in group]
        out.append("")
    odd = [r for r in data["mutants"] if r["outcome"] in ("timeout", "other")]
    if odd:
        out += ["## Timeouts and mutants mutmut did not judge", "",
                "| mutant | status | line | original | mutated |", "|---|---|---|---|---|"]
        out += [f"| `{r['name']}` | {r['status']} | {r['module']}:{r['line'] or '?'} | "
                f"{_cell(' / '.join(r['removed']))} | {_cell(' / '.join(r['added']))} |"
                for r in odd]
    return "\n".join(out) + "\n"


def _version(package: str) -> str:
    from importlib.metadata import version
    return version(package)


def _commit() -> str:
    return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()


# ------------------------------------------------------------------ main

def _args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m scripts.mutation_self",
                                description=__doc__.split("\n")[0])
    p.add_argument("--packages", nargs="+", choices=sorted(PACKAGES), metavar="PACKAGE",
                   default=sorted(PACKAGES), help="packages to mutate (default: all; "
                   f"known: {', '.join(sorted(PACKAGES))})")
    p.add_argument("--sample", type=int, metavar="N",
                   help="run N mutants per package, a seeded random sample; 0: every mutant "
                   "(default: the package's own sample size, see --list)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sample (default 0)")
    p.add_argument("--max-children", type=int, default=2,
                   help="mutmut's parallel test processes (default 2)")
    p.add_argument("--fresh", action="store_true", help="forget mutmut's earlier results")
    p.add_argument("--retest-survivors", action="store_true",
                   help="run the survivors again (tests were added since)")
    p.add_argument("--report-only", action="store_true",
                   help="run nothing: report mutmut's results as they are (verdicts edited)")
    p.add_argument("--out", type=Path, default=ROOT / "reports" / "mutation-self")
    p.add_argument("--verdicts", type=Path, default=VERDICTS)
    p.add_argument("--stubs", type=Path, metavar="FILE",
                   help="write an entry to review for every unexplained survivor to FILE")
    p.add_argument("--list", action="store_true", help="list the packages and stop")
    return p.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = _args(argv)
    if args.list:
        for name, pkg in PACKAGES.items():
            print(f"{name:10} mutates {' '.join(pkg.mutate)}; tests {' '.join(pkg.tests)}; "
                  f"sample {pkg.sample or 'all'}")
        return 0
    try:
        verdicts = load_verdicts(args.verdicts)
    except VerdictError as exc:
        print(f"mutation-self: {exc}", file=sys.stderr)
        return 2
    start = time.monotonic()
    records: list[dict[str, Any]] = []
    per_package: Counter[str] = Counter()
    per_module: Counter[str] = Counter()
    selection: dict[str, dict[str, Any]] = {}
    sizes: dict[str, int | None] = {}
    for name in args.packages:
        began = time.monotonic()
        work = WORK / name
        if not args.report_only:
            generate(prepare(name, args.fresh))
        found = statuses(work)
        size = PACKAGES[name].sample if args.sample is None else args.sample or None
        chosen = sample(list(found), size, args.seed, name)
        sizes[name] = size
        pending = [n for n in chosen if found[n][0] is None]
        if args.retest_survivors:   # mutmut keeps a survivor's result until asked again
            pending += [n for n in chosen if found[n][0] in SURVIVOR_CODES]
        if not args.report_only:
            print(f"mutation-self: {name}: {len(pending)} of {len(chosen)} mutants to run",
                  flush=True)
            if pending:
                by_name = size is not None or args.retest_survivors
                run(work, pending if by_name else None, args.max_children)
            (work / "last-run.json").write_text(json.dumps(
                {"seconds": time.monotonic() - began, "mutants_run": len(pending),
                 "max_children": args.max_children}))
        last = work / "last-run.json"
        last_run = json.loads(last.read_text()) if last.is_file() else \
            {"seconds": 0.0, "mutants_run": 0, "max_children": None}
        recs = records_of(name, work, chosen, verdicts)
        records += recs
        per_package[name] = len(found)
        per_module.update(module_path(split_name(n)[0]) for n in found)
        selection[name] = {"mutate": list(PACKAGES[name].mutate),
                           "tests": list(PACKAGES[name].tests), **last_run,
                           "test_seconds": sum(r["seconds"] or 0 for r in recs)}
    seconds = sum(s["seconds"] for s in selection.values())
    mutant_seconds = sum(s["test_seconds"] for s in selection.values())
    ran = sum(s["mutants_run"] for s in selection.values())
    packages = tally(records, "package", per_package)
    modules = tally(records, "module", per_module)
    sampled = ", ".join(f"{p}: " + ("all" if n is None else f"{n}") for p, n in sizes.items()) \
        + f" (seed {args.seed})"
    table = [("commit", _commit()), ("mutmut", _version("mutmut")),
             ("packages", ", ".join(args.packages)), ("mutants", sampled),
             ("max children", ", ".join(f"{p}: {s['max_children']}"
                                        for p, s in selection.items())),
             ("run time", f"{seconds:.0f} s: the last run of each package (mutant generation "
              f"and `mutmut run` of the {ran} mutants it ran); this invocation "
              f"{time.monotonic() - start:.0f} s"),
             ("mutant time", f"{mutant_seconds:.0f} s: mutmut's test time of every mutant "
              "reported, summed (whichever run ran it)"),
             ("pytest options", " ".join(PYTEST_ARGS))]
    data = {"meta": {"table": table, "seconds": seconds, "mutant_seconds": mutant_seconds,
                     "sample": sizes,
                     "seed": args.seed, "selection": selection},
            "packages": packages, "modules": modules, "mutants": records}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "results.json").write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n")
    (args.out / "summary.md").write_text(markdown(data))
    if args.stubs:
        args.stubs.write_text("\n".join(stub(r) for r in records
                                        if r.get("verdict") == "unexplained"))
    total = packages[-1]
    print(f"mutation-self: {total['mutants']} mutants, {total['killed']} killed, "
          f"{total['survived']} survived ({total['equivalent']} equivalent, {total['open']} "
          f"open, {total['unexplained']} unexplained), {total['other']} other, score "
          f"{_pct(total['score'])}; report in {args.out}")
    return 1 if total["unexplained"] else 0


if __name__ == "__main__":
    sys.exit(main())
