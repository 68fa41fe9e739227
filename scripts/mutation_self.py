"""Mutation testing of lsdae's own Python code with mutmut 3 (``make mutation-self``).

Each package is mutated on its own, in ``build/mutation-self/<package>/`` (links to the tree and
a ``pyproject.toml`` holding mutmut's settings for that package), and a mutant is run against
the package's own tests only (``bench/mutation_self/<package>.toml``); a mutant is killed when a test fails::

    python -m scripts.mutation_self --packages numerics            # its default sample
    python -m scripts.mutation_self --packages model --sample 300 --seed 1
    python -m scripts.mutation_self --packages numerics --sample 0 # every mutant
    python -m scripts.mutation_self --report-only                  # verdicts edited: report again
    python -m scripts.mutation_self --list                         # packages, tests, sample sizes

mutmut keeps its results in ``mutants/`` of the work folder and runs again only the mutants of
functions that changed; ``--fresh`` starts over. The report, ``reports/mutation-self/``
(``summary.md``, ``results.json``), is computed from mutmut's per-mutant results; the verdicts on
survivors and the defect classes they showed come from the same files. Exit status 1 while a
survivor is unexplained (no verdict, or a verdict whose mutated line no longer matches).
docs/mutation-self.md.
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
SETTINGS = ROOT / "bench" / "mutation_self"   # <package>.toml: settings, verdicts, classes
LINKED = ("conformance", "tests", "scenes", "rules", "schemas", "bench")  # in each work folder
PYTEST_ARGS = ["-p", "no:xdist", "-p", "no:cacheprovider", "--hypothesis-seed=0"]
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@dataclass(frozen=True)
class Package:
    mutate: tuple[str, ...]       # globs of the files mutated (mutmut's only_mutate)
    tests: tuple[str, ...]        # what pytest runs (mutmut's pytest_add_cli_args_test_selection)
    skip: tuple[str, ...] = ()    # globs never mutated (mutmut's do_not_mutate)
    sample: int | None = None     # mutants run by default (a seeded sample; None: every one)


class VerdictError(ValueError):
    """A file of bench/mutation_self/ is malformed."""


def _read(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise VerdictError(f"{path}: {exc}") from None


def _package(path: Path, table: dict[str, Any]) -> Package:
    if not table.get("mutate") or not table.get("tests"):
        raise VerdictError(f"{path}: [package] needs mutate and tests")
    return Package(tuple(table["mutate"]), tuple(table["tests"]), tuple(table.get("skip", ())),
                   table.get("sample") or None)


def load_packages(folder: Path = SETTINGS) -> dict[str, Package]:
    """One package per ``<name>.toml`` of the folder, from its ``[package]`` table."""
    return {path.stem: _package(path, _read(path).get("package", {}))
            for path in sorted(folder.glob("*.toml"))}


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
    lines = ["# written by scripts/mutation_self.py; edit bench/mutation_self/<package>.toml", "[tool.mutmut]"]
    lines += [f"{k} = {_toml(v)}" for k, v in mutmut.items()]
    lines += ["", "[tool.pytest.ini_options]"]
    lines += [f"{k} = {_toml(v)}" for k, v in pytest_opts["ini_options"].items()]
    return "\n".join(lines) + "\n"


def prepare(name: str, pkg: Package, fresh: bool) -> Path:
    """The package's work folder; its mutants/ goes when mutmut's settings changed (mutmut
    would keep results of the old test selection for functions that did not change) or
    ``fresh``."""
    work = WORK / name
    config = work / "pyproject.toml"
    text = config_text(pkg)
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

def _check_verdict(path: Path, key: str, entry: dict[str, Any]) -> None:
    if entry.get("verdict") not in ("equivalent", "open") or "mutated" not in entry:
        raise VerdictError(f"{path}: {key!r} needs verdict (equivalent or open) and mutated")
    if entry["verdict"] == "equivalent" and not entry.get("reason"):
        raise VerdictError(f"{path}: equivalent {key!r} needs a reason")
    if entry.get("reason", "").startswith("REVIEW"):
        raise VerdictError(f"{path}: {key!r} is a stub nobody reviewed (reason REVIEW)")


def _check_class(path: Path, key: str, entry: dict[str, Any]) -> None:
    if not entry.get("title") or not entry.get("mutants") or not entry.get("tests"):
        raise VerdictError(f"{path}: class {key!r} needs title, mutants and tests")


def load_verdicts(folder: Path = SETTINGS) -> tuple[dict[str, dict[str, Any]],
                                                    dict[str, dict[str, Any]]]:
    """The verdicts and the defect classes of every package file of the folder.

    ``[verdict."<mutant>"]``: ``verdict`` (equivalent or open), ``mutated`` (the lines the
    mutant adds, stripped and joined by `` / ``: the report's *mutated* column) and ``reason``
    (required for equivalent). ``[class.<id>]``: ``title`` (what the tests could not see),
    ``mutants`` (the survivors that showed it), ``tests`` (the tests that now close it),
    ``decides`` (what verdict of lsdae's the place decides)."""
    verdicts: dict[str, dict[str, Any]] = {}
    classes: dict[str, dict[str, Any]] = {}
    for path in sorted(folder.glob("*.toml")):
        data = _read(path)
        for key, entry in data.get("verdict", {}).items():
            _check_verdict(path, key, entry)
            verdicts[key] = entry
        for key, entry in data.get("class", {}).items():
            _check_class(path, key, entry)
            if key in classes:
                raise VerdictError(f"{path}: class {key!r} is defined twice")
            classes[key] = {**entry, "package": path.stem}
    return verdicts, classes


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

def class_rows(classes: dict[str, dict[str, Any]], records: list[dict[str, Any]],
               packages: Sequence[str]) -> list[dict[str, Any]]:
    """Each defect class of the packages run, its mutants' outcomes in this report (``not
    run``: outside the sample) and whether the tests now close it: every one of its mutants
    that was run is killed."""
    outcome = {r["name"]: r["outcome"] for r in records}
    rows = []
    for key, entry in sorted(classes.items()):
        if entry["package"] not in packages:
            continue
        states = {m: outcome.get(m, "not run") for m in entry["mutants"]}
        ran = [o for o in states.values() if o != "not run"]
        rows.append({"class": key, "package": entry["package"], "title": entry["title"],
                     "decides": entry.get("decides", ""), "tests": list(entry["tests"]),
                     "mutants": states,
                     "closed": bool(ran) and all(o in ("killed", "timeout") for o in ran)})
    return rows


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
    classes = data.get("classes", [])
    if classes:
        closed = sum(c["closed"] for c in classes)
        out += [f"## What the tests could not see: defect classes ({closed} of {len(classes)} "
                "closed)", "", "Each class is a kind of change to a place that decides a "
                "verdict which survived the tests when the campaign first ran; *closed*: every "
                "one of its mutants in this run is killed by the tests named.", "",
                "| class | package | what the tests could not see | decides | mutants | "
                "closed by | closed |", "|---|---|---|---|---|---|---|"]
        for c in classes:
            mutants = "<br>".join(f"`{m.rpartition('.')[2]}`: {o}" for m, o in c["mutants"].items())
            tests = "<br>".join(_cell(t) for t in c["tests"])
            out.append(f"| `{c['class']}` | `{c['package']}` | {c['title']} | {c['decides']} | "
                       f"{mutants} | {tests} | {'yes' if c['closed'] else '**no**'} |")
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

def _args(argv: Sequence[str] | None, names: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m scripts.mutation_self",
                                description=__doc__.split("\n")[0])
    p.add_argument("--packages", nargs="+", choices=names, metavar="PACKAGE",
                   default=names, help="packages to mutate (default: all; "
                   f"known: {', '.join(names)})")
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
    p.add_argument("--settings", type=Path, default=SETTINGS,
                   help="folder of the package files (settings, verdicts, classes)")
    p.add_argument("--stubs", type=Path, metavar="FILE",
                   help="write an entry to review for every unexplained survivor to FILE")
    p.add_argument("--list", action="store_true", help="list the packages and stop")
    return p.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    try:
        packages_known = load_packages(SETTINGS)
    except VerdictError as exc:
        print(f"mutation-self: {exc}", file=sys.stderr)
        return 2
    args = _args(argv, sorted(packages_known))
    if args.list:
        for name, pkg in packages_known.items():
            print(f"{name:10} mutates {' '.join(pkg.mutate)}; tests {' '.join(pkg.tests)}; "
                  f"sample {pkg.sample or 'all'}")
        return 0
    try:
        packages_known = load_packages(args.settings)
        verdicts, classes = load_verdicts(args.settings)
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
            generate(prepare(name, packages_known[name], args.fresh))
        found = statuses(work)
        size = packages_known[name].sample if args.sample is None else args.sample or None
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
        selection[name] = {"mutate": list(packages_known[name].mutate),
                           "tests": list(packages_known[name].tests), **last_run,
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
            "packages": packages, "modules": modules, "mutants": records,
            "classes": class_rows(classes, records, args.packages)}
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
