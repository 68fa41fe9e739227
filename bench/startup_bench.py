"""Start-up benchmark: how long a command takes before and around its real work.

Each row is a command run as a subprocess, timed with :func:`time.perf_counter` around
:func:`subprocess.run`, interleaved round by round so that every command sees the same machine
load; the table gives medians over ``--repeat`` rounds and each command's ratio to the floor,
``python -c "import lxml.etree"`` (the interpreter plus the one library every check needs).

Rows: ``python -c pass``; the floor; ``lsdae --version``; ``lsdae rules``; a static check of a
small FMU (HelloWorldDAE, ``--no-probes``); the full check of the same FMU (probes included,
whose worker start-up is most of it). With ``--compare-rev REV`` the last two commands are also
run from a git worktree of REV (``python -m conformance`` with that tree first on the path) in
the same rounds, so that "not slower than before" is a ratio measured side by side.

Python bytecode is compiled first (``compileall``), as an installed package has it: a machine
with ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module on every run.

    python -m bench.startup_bench [--repeat 21] [--compare-rev HEAD~5] [--out reports/bench]
"""
from __future__ import annotations

import argparse
import compileall
import datetime as dt
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from scenes.build import build_scene

REPO_ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
TARGETS = {"lsdae --version": 3.0, "lsdae rules": 3.0, "static check, small FMU": 5.0}


def _commands(fmu: str, out: str) -> dict[str, list[str]]:
    py, lsdae = sys.executable, str(BIN / "lsdae")
    return {
        "python -c pass": [py, "-c", "pass"],
        "floor: import lxml.etree": [py, "-c", "import lxml.etree"],
        "lsdae --version": [lsdae, "--version"],
        "lsdae rules": [lsdae, "rules"],
        "static check, small FMU": [lsdae, "check", "--no-probes", fmu, "--format", f"json:{out}"],
        "full check, small FMU": [lsdae, "check", fmu, "--format", f"json:{out}"],
    }


def _reference(rev: str, tree: Path, fmu: str, out: str) -> dict[str, list[str]]:
    subprocess.run(["git", "-C", str(REPO_ROOT), "worktree", "add", "--detach", "-q", str(tree),
                    rev], check=True)
    compileall.compile_dir(tree / "conformance", quiet=1)
    run = [sys.executable, "-m", "conformance"]
    return {"static check, small FMU (python -m, this tree)": [*run, "check", "--no-probes", fmu,
                                                               "--format", f"json:{out}"],
            "full check, small FMU (python -m, this tree)": [*run, "check", fmu,
                                                             "--format", f"json:{out}"],
            f"static check, small FMU ({rev})": [*run, "check", "--no-probes", fmu,
                                                 "--format", f"json:{out}"],
            f"full check, small FMU ({rev})": [*run, "check", fmu, "--format", f"json:{out}"]}


def _time(argv: list[str], cwd: Path) -> float:
    start = time.perf_counter()
    proc = subprocess.run(argv, cwd=cwd, capture_output=True)
    elapsed = time.perf_counter() - start
    if proc.returncode not in (0, 1):
        raise SystemExit(f"startup_bench: {' '.join(argv)} exited {proc.returncode}: "
                         f"{proc.stderr.decode(errors='replace')[-500:]}")
    return elapsed


def run(repeat: int, compare_rev: str | None) -> dict:
    compileall.compile_dir(REPO_ROOT / "conformance", quiet=1)
    fmu = str(build_scene("HelloWorldDAE"))
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "report.json")
        commands = {name: (argv, REPO_ROOT) for name, argv in _commands(fmu, out).items()}
        tree = Path(tmp) / "reference"
        try:
            if compare_rev:
                for name, argv in _reference(compare_rev, tree, fmu, out).items():
                    commands[name] = (argv, REPO_ROOT if "this tree" in name else tree)
            for argv, cwd in commands.values():  # warm the page cache and the scene build
                _time(argv, cwd)
            times: dict[str, list[float]] = {name: [] for name in commands}
            for _ in range(repeat):
                for name, (argv, cwd) in commands.items():
                    times[name].append(_time(argv, cwd))
        finally:
            if compare_rev and tree.exists():
                subprocess.run(["git", "-C", str(REPO_ROOT), "worktree", "remove", "--force",
                                str(tree)], check=False)
    medians = {name: statistics.median(t) for name, t in times.items()}
    floor = medians["floor: import lxml.etree"]
    return {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "repeat": repeat, "compare_rev": compare_rev, "floor_s": floor,
            "rows": [{"command": name, "median_s": medians[name], "ratio": medians[name] / floor,
                      "target": TARGETS.get(name), "runs_s": times[name]} for name in commands],
            "machine": {"python": platform.python_version(), "platform": platform.platform(),
                        "cpus": _cpus()}}


def _cpus() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def markdown(result: dict) -> str:
    lines = ["# Start-up benchmark: commands against `python -c \"import lxml.etree\"`", "",
             f"Date: {result['date']}. Median of {result['repeat']} interleaved rounds, wall time "
             "of a subprocess (interpreter start included, bytecode compiled). Ratio: to the "
             "floor `python -c \"import lxml.etree\"`.", "",
             "| command | median ms | × floor | target |", "|---|---:|---:|---:|"]
    for row in result["rows"]:
        target = f"≤ {row['target']:g}×" if row["target"] else ""
        lines.append(f"| {row['command']} | {row['median_s'] * 1000:.0f} | {row['ratio']:.2f} "
                     f"| {target} |")
    if result["compare_rev"]:
        lines += ["", f"Rows marked ({result['compare_rev']}) ran that revision from a git "
                      "worktree with `python -m conformance`, in the same rounds."]
    machine = result["machine"]
    lines += ["", f"Machine: Python {machine['python']}, {machine['platform']}, "
                  f"{machine['cpus']} usable CPUs.", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=21)
    parser.add_argument("--compare-rev", metavar="REV",
                        help="also time the checks of this git revision, side by side")
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "reports" / "bench")
    args = parser.parse_args(argv)
    result = run(args.repeat, args.compare_rev)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "startup.json").write_text(json.dumps(result, indent=2) + "\n")
    text = markdown(result)
    (args.out / "startup.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
