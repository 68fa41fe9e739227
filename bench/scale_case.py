"""One case of the scale benchmark: ``lsdae check FMU`` (the default full check) in this process.

    python -m bench.scale_case FMU [--endurance quick] [--rule-option CODE.key=value ...]

Runs the command line's own entry (``conformance.commands.cli.main``) with the default options and a
JSON report, and prints one JSON object: the wall time of the whole check, this process's peak
resident size, what each step of the probe worker cost (seconds, FMI calls, peak resident size,
from the driver's log records, ``conformance.probes.machinery.driver``), and the verdicts (findings by
rule, rules not run). A fresh process per case, so that each peak is that case's own.
"""
from __future__ import annotations

import argparse
import json
import logging
import resource
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Sequence


class _Collect(logging.Handler):
    """Keeps the ``probe_stats`` of the driver's log records."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.stats: list[dict[str, Any]] = []

    def emit(self, record: logging.LogRecord) -> None:
        stats = getattr(record, "probe_stats", None)
        if isinstance(stats, dict):
            self.stats.append(dict(stats))


def _cli() -> Any:
    """The command line of the ``conformance`` package on the path: ``commands/cli.py`` since the
    rooms of issue 19, ``cli.py`` before (a baseline checkout). Chosen by the loaded package's own
    folder, because the editable install's finder would otherwise supply this tree's modules."""
    import conformance

    if (Path(conformance.__file__).parent / "commands" / "cli.py").exists():
        from conformance.commands import cli
    else:
        from conformance import cli  # type: ignore[no-redef]
    return cli


def run_case(fmu: Path, extra: Sequence[str] = ()) -> dict[str, Any]:
    cli = _cli()

    collect = _Collect()
    driver_log = logging.getLogger("conformance.probes.machinery.driver")
    driver_log.setLevel(logging.DEBUG)
    driver_log.propagate = False  # kept, not printed
    driver_log.addHandler(collect)
    with tempfile.TemporaryDirectory(prefix="lsdae-scale-") as tmp:
        out = Path(tmp) / "report.json"
        start = time.perf_counter()
        code = cli.main(["check", str(fmu), "--format", f"json:{out}", "--progress", "never",
                         *extra])
        seconds = time.perf_counter() - start
        report = json.loads(out.read_text(encoding="utf-8"))
    fmu_report = report["fmus"][0]
    findings = [{"code": f["code"], "name": f["name"], "severity": f["severity"],
                 "message": f["message"][:300]} for f in fmu_report["findings"]]
    endurance = fmu_report["info"].get("endurance")
    simulation = fmu_report["info"].get("simulation") or {}
    return {
        "fmu": str(fmu), "exit_code": code, "seconds": seconds,
        "parent_peak_rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "worker_peak_rss": max((s.get("peak_rss") or 0 for s in collect.stats), default=0),
        "steps": collect.stats, "findings": findings,
        "rules_not_run": fmu_report.get("rules_not_run", []),
        "endurance": endurance,
        "simulation": {k: simulation.get(k) for k in ("status", "steps", "fmi_calls",
                                                      "jacobian", "message")},
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.scale_case", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=Path)
    parser.add_argument("extra", nargs=argparse.REMAINDER,
                        help="further options of lsdae check (after --)")
    args = parser.parse_args(argv)
    extra = [a for a in args.extra if a != "--"]
    print(json.dumps(run_case(args.fmu, extra)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
