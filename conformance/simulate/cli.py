"""``lsdae simulate FMU``: integrate an fmi-ls-dae FMU and write its trajectory.

    lsdae simulate FMU [--mode dae|ode|both] [--stop-time T] [--rtol R]
                       [--output-times t1,t2,...] [-o trajectory.csv]

The binary is loaded only in the probe worker process, as for ``lsdae check``: this command runs
the simulation probes (``conformance/probes/simulation.py``) through the engine with its own
settings (a copy of the catalogue whose ``simulation-failed`` options are the command line's,
and whose time limits fit the budget), then reads the trajectory back from the report. A crash
or hang of the FMU is a finding, never a traceback.

Exit codes: 0 the stop time was reached without a finding, 1 a finding (the trajectory up to
where the run ended is still written), 2 usage error or nothing could be simulated.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

EXIT_OK, EXIT_FINDINGS, EXIT_USAGE = 0, 1, 2


def _positive(kind: type) -> Any:
    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be positive: {text!r}")
        return value
    return parse


def _times(text: str) -> tuple[float, ...]:
    from .settings import parse_times

    try:
        return parse_times(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to ``subparsers`` (from ``add_subparsers``)."""
    p = subparsers.add_parser(
        "simulate", help="integrate an FMU in DAE mode (IDA) and/or ODE mode (CVODE)",
        description="Integrate an fmi-ls-dae FMU in DAE mode with SUNDIALS IDA (the FMU's "
                    "Jacobian), in ODE mode with CVODE, or both and compare them.")
    p.add_argument("fmu", metavar="FMU", help="a .fmu file or an unpacked FMU folder")
    p.add_argument("--mode", choices=("dae", "ode", "both"), default="dae",
                   help="DAE mode (default), ODE mode, or both and compare")
    p.add_argument("--stop-time", type=_positive(float), metavar="T",
                   help="default: the DefaultExperiment's stopTime, else start + 1")
    p.add_argument("--rtol", type=_positive(float), default=1e-6, metavar="R",
                   help="relative tolerance (default 1e-6); atol = rtol * nominal per variable")
    p.add_argument("--output-times", type=_times, metavar="t1,t2,...",
                   help="output times (default: an even grid, see --output-points)")
    p.add_argument("--output-points", type=_positive(int), default=101, metavar="N",
                   help="number of evenly spaced output times, start and stop included")
    p.add_argument("-o", "--output", metavar="CSV",
                   help="write the trajectory (DAE mode, or ODE mode with --mode ode) here")
    p.add_argument("--ode-output", metavar="CSV",
                   help="with --mode both: write the ODE-mode trajectory here")
    p.add_argument("--max-steps", type=_positive(int), default=100_000, metavar="N",
                   help="step budget per mode (default 100000)")
    p.add_argument("--time-limit", type=_positive(float), default=60.0, metavar="S",
                   help="wall-clock budget per mode in seconds (default 60)")
    p.add_argument("--color", choices=("auto", "always", "never"), default="auto")
    p.add_argument("-v", "--verbose", action="store_true", help="log what the engine does")
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``lsdae simulate``; returns the exit code."""
    from ..findings import Severity
    from .run import default_stop_time, simulate_fmu
    from .settings import Settings

    path = Path(args.fmu)
    if not path.exists():
        print(f"lsdae: {path}: no such file or folder", file=sys.stderr)
        return EXIT_USAGE
    if args.rtol >= 1:
        print("lsdae: --rtol must be below 1", file=sys.stderr)
        return EXIT_USAGE
    stop = args.stop_time or default_stop_time(path) or 0.0
    settings = Settings(mode=args.mode, rtol=args.rtol, stop_time=stop,
                        output_points=args.output_points,
                        output_times=tuple(args.output_times or ()), max_steps=args.max_steps,
                        wall_seconds=args.time_limit, record_wall_time=True)
    result = simulate_fmu(path, settings)
    for traj in result.trajectories:
        sys.stdout.write(summary(traj))
    if result.comparison:
        sys.stdout.write(_comparison_line(result.comparison))
    written = _write(args, result.trajectories)
    report = result.report
    if report.findings:
        _print_findings(report, result.catalogue, args.color)
    reasons = result.skipped()
    if not result.trajectories:
        reason = reasons[0] if reasons else str(dict(report.info).get("probes",
                                                                      "no simulation ran"))
        print(f"lsdae: nothing was simulated: {reason}", file=sys.stderr)
        return EXIT_FINDINGS if report.findings else EXIT_USAGE
    if not report.findings and any(not t.ok for t in result.trajectories):
        for reason in reasons[:3]:
            print(f"note: {reason}")
    if not written:
        return EXIT_USAGE
    incomplete = any(not t.ok for t in result.trajectories)
    worst = report.worst
    return EXIT_FINDINGS if incomplete or (worst is not None and worst >= Severity.WARNING) \
        else EXIT_OK


def summary(traj: Any) -> str:
    """Two lines about one run: where it got, at what cost, and how it ended."""
    state = "reached the stop time" if traj.ok else f"{traj.status}: {traj.message}"
    init = traj.init or {}
    before = (init.get("residual_before") or {}).get("max_abs")
    after = (init.get("residual_after") or {}).get("max_abs")
    residual = (f"; initial residual {before:.3g} -> {after:.3g}"
                if before is not None and after is not None else "")
    return (f"{traj.mode.upper()} mode: t = {traj.t_start:g} .. {traj.t_end:.10g} of "
            f"{traj.stop_time:g}, {state}\n"
            f"  rtol {traj.rtol:g}, {traj.steps} steps, {traj.function_calls} "
            f"{'residual' if traj.mode == 'dae' else 'right-hand side'} and "
            f"{traj.jacobian_calls} Jacobian evaluations ({traj.jacobian}), {traj.fmi_calls} "
            f"FMI calls, {traj.wall_s:.3f} s{residual}\n")


def _comparison_line(comparison: dict) -> str:
    worst = comparison.get("worst") or {}
    if not worst:
        return "DAE vs ODE: nothing to compare\n"
    return (f"DAE vs ODE: largest gap {worst['gap']:.3g} tolerance units ({worst['variable']} "
            f"at t = {worst['t']:.6g}) over {comparison.get('compared_times')} output times\n")


def _write(args: argparse.Namespace, trajectories: list) -> bool:
    from .output import write_csv

    targets = [(args.output, trajectories[0] if trajectories else None)]
    if args.ode_output:
        ode = next((t for t in trajectories if t.mode == "ode"), None)
        if ode is None:
            print("lsdae: --ode-output needs --mode both", file=sys.stderr)
        targets.append((args.ode_output, ode))
    ok = True
    for file, traj in targets:
        if not file or traj is None:
            continue
        try:
            write_csv(traj, file)
        except OSError as exc:
            print(f"lsdae: cannot write {file}: {exc}", file=sys.stderr)
            ok = False
    return ok


def _print_findings(report: Any, catalogue: Any, color: str) -> None:
    import os

    from ..findings import Report
    from ..reporters import REPORTER_BY_NAME

    use = color == "always" or (color == "auto" and sys.stdout.isatty()
                                and not os.environ.get("NO_COLOR"))
    text = REPORTER_BY_NAME["console"](Report(tool_version="", fmus=(report,)), catalogue,
                                       color=use)
    sys.stdout.write("\n" + text)
