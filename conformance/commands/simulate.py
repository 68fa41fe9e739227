"""``lsdae simulate FMU``: integrate an fmi-ls-dae FMU and write its trajectory.

    lsdae simulate FMU [--mode dae|ode|both] [--stop-time T] [--rtol R]
                       [--output-times t1,t2,...] [-o trajectory.csv]

The binary is loaded only in the probe worker process, as for ``lsdae check``: this command runs
the simulation probes (``conformance/probes/simulation/verdicts.py``, which call
:func:`conformance.simulate.integrate.simulate_instance`) through the engine with its own settings
(:func:`simulate_fmu`: a copy of the catalogue whose ``simulation-failed`` options are the
command line's, and whose time limits fit the budget), then reads the trajectories back from the
report's ``info["simulation"]``. A crash or hang of the FMU is a ``binary-*`` finding, never a
traceback. It sits above the engine, beside ``cli``.

Exit codes, as ``fmpy simulate``: 0 the integration reached the stop time and the trajectory was
written, 1 it failed (with the reason; the trajectory up to where it ended is still written), a
simulation rule found a fault (DAE and ODE mode disagree), or ``--fail-on`` was given and a
static finding reaches it, 2 usage error. Static findings are summarised
in one line with a pointer to ``lsdae check``.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path
from typing import Any

from .arguments import add_simulate_parser as add_parser
from ..report.catalogue import default_catalogue
from .exit_codes import EXIT_FINDINGS, EXIT_OK, EXIT_USAGE
from ..report.findings import Report, Severity
from ..reporters import REPORTER_BY_NAME
from ..run.simulate_fmu import (RULES_BY_MODE, Simulation, default_experiment, read_model,
                           simulate_fmu, start_values)

__all__ = ["Simulation", "add_parser", "run", "simulate_fmu", "summary"]


def _is_simulation_finding(finding: Any) -> bool:
    """Findings of the run itself: the simulation rules, the binary-* rules, internal errors."""
    return (finding.code in RULES_BY_MODE["both"] or finding.code.startswith("DAE70")
            or finding.name == "internal-error")


def _static_line(findings: list[Any], path: Path) -> str:
    counts = {s: sum(f.severity == s for f in findings) for s in (Severity.ERROR,
                                                                   Severity.WARNING,
                                                                   Severity.INFO)}
    parts = [f"{n} {s}{'' if n == 1 else 's'}" for s, n in counts.items() if n]
    names = list(dict.fromkeys(f.name for f in findings))
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    return (f"static check: {', '.join(parts)} ({shown}); `lsdae check {path}` shows "
            "them\n")


def run(args: argparse.Namespace) -> int:
    """Run ``lsdae simulate``; returns the exit code."""
    from ..numerics.settings import Settings  # numpy: only when simulating

    path = Path(args.fmu)
    if not path.exists():
        print(f"lsdae: {path}: no such file or folder", file=sys.stderr)
        return EXIT_USAGE
    if args.rtol is not None and args.rtol >= 1:
        print("lsdae: --rtol must be below 1", file=sys.stderr)
        return EXIT_USAGE
    model = read_model(path)  # once, for the DefaultExperiment and the start values
    try:
        given = start_values(model, args.start_value)
    except ValueError as exc:
        print(f"lsdae: {exc}", file=sys.stderr)
        return EXIT_USAGE
    experiment = default_experiment(model)
    options = dict(default_catalogue()["simulation-failed"].option_values)  # the defaults
    tolerance = experiment.get("tolerance")
    rtol = args.rtol or (tolerance if tolerance is not None and 0 < tolerance < 1
                         else options["rtol"])
    settings = Settings(**{
        **options, "mode": args.mode, "rtol": rtol,
        "stop_time": args.stop_time or experiment.get("stopTime") or 0.0,
        "output_points": args.output_points, "output_times": tuple(args.output_times or ()),
        "max_steps": args.max_steps, "wall_seconds": args.time_limit, "record_wall_time": True,
        "start_values": given})
    result = simulate_fmu(path, settings)
    for traj in result.trajectories:
        sys.stdout.write(summary(traj))
    if result.comparison:
        sys.stdout.write(_comparison_line(result.comparison))
    written = _write(args, result.trajectories)
    report = result.report
    own = [f for f in report.findings if _is_simulation_finding(f)]
    static = [f for f in report.findings if not _is_simulation_finding(f)]
    if own:
        _print_findings(dataclasses.replace(report, findings=tuple(own)), result.catalogue,
                        args.color)
    if static:
        sys.stdout.write(_static_line(static, path))
    reasons = result.skipped()
    if not result.trajectories:
        first_static = next((f for f in static if f.severity >= Severity.ERROR), None)
        reason = (reasons[0] if reasons else f"{first_static.name}: {first_static.message}"
                  if first_static else str(dict(report.info).get("probes",
                                                                 "no simulation ran")))
        print(f"lsdae: nothing was simulated: {reason}", file=sys.stderr)
        return EXIT_FINDINGS
    incomplete = [t for t in result.trajectories if not t.ok]
    if incomplete and not own:
        for reason in reasons[:3]:
            print(f"note: {reason}")
    if not written:
        return EXIT_FINDINGS
    if incomplete:
        print(f"lsdae: the {incomplete[0].mode.upper()}-mode integration stopped at t = "
              f"{incomplete[0].t_end:.10g} of {incomplete[0].stop_time:g}: "
              f"{incomplete[0].message}", file=sys.stderr)
        return EXIT_FINDINGS
    if any(f.severity >= Severity.WARNING for f in own):
        return EXIT_FINDINGS  # the runs' own verdict, e.g. DAE and ODE mode disagree
    if args.fail_on and (report.worst or Severity.INFO) >= Severity.parse(args.fail_on) \
            and report.findings:
        return EXIT_FINDINGS
    return EXIT_OK


def summary(traj: Any) -> str:
    """Two lines about one run (three with events): where it got, at what cost, how it ended."""
    state = ("reached the stop time" if traj.ok and traj.terminated_at is None
             else traj.message if traj.ok else f"{traj.status}: {traj.message}")
    init = traj.init or {}
    before = (init.get("residual_before") or {}).get("max_abs")
    after = (init.get("residual_after") or {}).get("max_abs")
    residual = (f"; initial residual {before:.3g} -> {after:.3g}"
                if before is not None and after is not None else "")
    along = traj.residual_along or {}
    if along.get("max_abs") is not None:
        residual += (f"; largest residual along the run {along['max_abs']:.3g} "
                     f"({along['residual']} at t = {along['t']:.6g})")
    return (f"{traj.mode.upper()} mode: t = {traj.t_start:g} .. {traj.t_end:.10g} of "
            f"{traj.stop_time:g}, {state}\n"
            f"  rtol {traj.rtol:g}, {traj.steps} steps, {traj.function_calls} "
            f"{'residual' if traj.mode == 'dae' else 'right-hand side'} and "
            f"{traj.jacobian_calls} Jacobian evaluations ({traj.jacobian}), {traj.fmi_calls} "
            f"FMI calls, {traj.wall_s:.3f} s{residual}\n{_events_line(traj)}")


def _events_line(traj: Any) -> str:
    """The events of a run that watched event indicators or had one ("" otherwise)."""
    if not traj.has_events:
        return ""
    times = traj.event_times
    shown = ", ".join(f"{t:.6g}" for t in times[:5]) + (", ..." if len(times) > 5 else "")
    return (f"  {traj.state_events} state event{'' if traj.state_events == 1 else 's'}, "
            f"{traj.time_events} time event{'' if traj.time_events == 1 else 's'} "
            f"({traj.indicators} event indicator{'' if traj.indicators == 1 else 's'})"
            f"{f' at t = {shown}' if times else ''}\n")


def _comparison_line(comparison: dict) -> str:
    worst = comparison.get("worst") or {}
    if not worst:
        return "DAE vs ODE: nothing to compare\n"
    return (f"DAE vs ODE: largest gap {worst['gap']:.3g} tolerance units ({worst['variable']} "
            f"at t = {worst['t']:.6g}) over {comparison.get('compared_times')} output times\n")


def _write(args: argparse.Namespace, trajectories: list) -> bool:
    from ..simulate.output import write_csv  # numpy: only when writing

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
    use = color == "always" or (color == "auto" and sys.stdout.isatty()
                                and not os.environ.get("NO_COLOR"))
    text = REPORTER_BY_NAME["console"](Report(tool_version="", fmus=(report,)), catalogue,
                                       color=use)
    sys.stdout.write("\n" + text)
