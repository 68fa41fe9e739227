"""``lsdae simulate FMU``: integrate an fmi-ls-dae FMU and write its trajectory.

    lsdae simulate FMU [--mode dae|ode|both] [--stop-time T] [--rtol R]
                       [--output-times t1,t2,...] [-o trajectory.csv]

The binary is loaded only in the probe worker process, as for ``lsdae check``: this command runs
the simulation probes (``conformance/probes/simulation.py``, which call
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
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .catalogue import Catalogue, default_catalogue
from .engine import EngineOptions, check_fmu
from .findings import Report, Severity, thaw
from .fmu import MODEL_DESCRIPTION, ArchiveReadError, open_fmu
from .reporters import REPORTER_BY_NAME
from .model import read_model_description
from .xmlsafe import parse_xml

RULES_BY_MODE = {"dae": ("DAE801", "DAE802", "DAE803", "DAE804"),
                 "ode": ("DAE801", "DAE803", "DAE804"),
                 "both": ("DAE801", "DAE802", "DAE803", "DAE804", "DAE805")}
# Archive, XML and engine pseudo-rules, and the runner's binary-* rules: a broken FMU says why.
ALWAYS = ("DAE0", "DAE70")
RUNNER_MARGIN_S = 30.0


@dataclass
class Simulation:
    """What one FMU's simulation gave: the report (findings, skipped rules), the runs (DAE mode
    first), the comparison of the two modes, and the catalogue used (for reporters)."""

    report: Any
    catalogue: Any
    trajectories: list[Any] = field(default_factory=list)  # Trajectory
    comparison: dict[str, Any] | None = None

    def skipped(self) -> list[str]:
        """Why rules of this simulation did not run (distinct reasons, in code order)."""
        codes = set(RULES_BY_MODE["both"])
        return list(dict.fromkeys(r for c, r in sorted(self.report.rules_skipped)
                                  if c in codes))


def default_experiment(path: Path | str) -> dict[str, float]:
    """The DefaultExperiment's startTime, stopTime and tolerance that are finite numbers, read
    safely (``{}`` when absent or unreadable)."""
    source, _ = open_fmu(Path(path))
    if source is None:
        return {}
    with source:
        try:
            data = source.read(MODEL_DESCRIPTION)
        except (KeyError, ArchiveReadError, OSError):
            return {}
    tree, _ = parse_xml(data, file=MODEL_DESCRIPTION)
    element = tree.getroot().find("DefaultExperiment") if tree is not None else None
    out: dict[str, float] = {}
    for key in ("startTime", "stopTime", "tolerance"):
        try:
            value = float(element.get(key)) if element is not None else math.nan
        except (TypeError, ValueError):
            continue
        if math.isfinite(value):
            out[key] = value
    return out


SETTABLE_START = ("input", "parameter")


def start_values(path: Path | str, items: list[str]) -> tuple[tuple[str, float], ...]:
    """``NAME=VALUE`` items as (name, value), checked against modelDescription.xml: the name is
    a scalar Float64 input or parameter (as fmpy's start_values); ValueError says what is wrong."""
    if not items:
        return ()
    source, _ = open_fmu(Path(path))
    variables = {}
    if source is not None:
        with source:
            try:
                data = source.read(MODEL_DESCRIPTION)
            except (KeyError, ArchiveReadError, OSError):
                data = None
        tree, _ = parse_xml(data, file=MODEL_DESCRIPTION) if data else (None, [])
        if tree is not None:
            variables = {v.name: v for v in read_model_description(tree).variables}
    out = []
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep:
            raise ValueError(f"--start-value takes NAME=VALUE, not {item!r}")
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"--start-value {name}: not a number: {text!r}") from None
        var = variables.get(name)
        if var is None:
            raise ValueError(f"--start-value: the FMU has no variable {name!r}")
        if var.causality not in SETTABLE_START or var.type != "Float64" or var.dimensions:
            raise ValueError(f"--start-value {name}: only scalar Float64 inputs and parameters "
                             f"can be given (it is a {var.type} {var.causality})")
        out.append((name, value))
    return tuple(out)


def default_stop_time(path: Path | str) -> float | None:
    """The DefaultExperiment's stopTime; None when absent or unreadable."""
    return default_experiment(path).get("stopTime")


def simulation_catalogue(settings: Any, *, time_limit: float | None = None) -> Catalogue:
    """The default catalogue with ``settings`` as the options of simulation-failed, and the
    runner's time limits raised above the wall-clock budget (``time_limit``, per run)."""
    limit = settings.wall_seconds if time_limit is None else time_limit
    runs = 2 if settings.mode == "both" else 1
    rules = []
    for rule in default_catalogue():
        if rule.name == "simulation-failed":
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, **settings.as_options(),
                 "output_times": tuple(settings.output_times),
                 "start_values": tuple(tuple(p) for p in settings.start_values)}.items())))
        elif rule.name == "binary-timed-out":
            # the confirmation runs of ode-dae-trajectory-mismatch take up to one budget more
            rule = dataclasses.replace(rule, options=tuple(sorted({
                **rule.option_values, "probe_seconds": 2 * limit + RUNNER_MARGIN_S,
                "fmu_seconds": (runs + 1) * limit + 2 * RUNNER_MARGIN_S}.items())))
        rules.append(rule)
    return Catalogue(rules)


def simulate_fmu(path: Path | str, settings: Any) -> Simulation:
    """Simulate the FMU at ``path`` (file or folder) as ``settings`` say; never raises for a
    bad FMU (its faults are findings of the report)."""
    catalogue = simulation_catalogue(settings)
    options = EngineOptions(select=(*ALWAYS, *RULES_BY_MODE[settings.mode]), probes_only=True)
    report = check_fmu(Path(path), options=options, catalogue=catalogue, display_path=str(path))
    info = thaw(report.info)
    simulation = info.get("simulation") if isinstance(info, dict) else None
    result = Simulation(report, catalogue)
    if isinstance(simulation, dict) and simulation.get("times") is not None:
        from .numerics.settings import Trajectory  # numpy: only once a run is read back

        result.trajectories.append(Trajectory.from_info(simulation))
        if isinstance(simulation.get("ode"), dict):
            result.trajectories.append(Trajectory.from_info(simulation["ode"]))
        if isinstance(simulation.get("comparison"), dict):
            result.comparison = simulation["comparison"]
    return result


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
    from .numerics.settings import parse_times  # numpy: only when the option is given

    try:
        return parse_times(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


EPILOG = """exit codes:
  0  the integration reached the stop time and the trajectory was written
  1  the integration failed or stopped early (the reason is printed; the trajectory up to
     where it ended is still written), the simulation found a fault (with --mode both: the DAE
     and ODE trajectories differ), nothing could be simulated, the output could not be
     written, or --fail-on was given and a static finding reaches it
  2  usage error (bad arguments, no such file)

The start time is the DefaultExperiment's startTime (0 without one); the stop time and the
tolerance are the DefaultExperiment's unless given. Static findings (archive, XML, schema) are
summarised in one line: `lsdae check FMU` shows them."""


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to ``subparsers`` (from ``add_subparsers``)."""
    p = subparsers.add_parser(
        "simulate", help="integrate an FMU in DAE mode (IDA) and/or ODE mode (CVODE)",
        description="Integrate an fmi-ls-dae FMU in DAE mode with SUNDIALS IDA (the FMU's "
                    "Jacobian), in ODE mode with CVODE, or both and compare them.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", metavar="FMU", help="a .fmu file or an unpacked FMU folder")
    p.add_argument("--mode", choices=("dae", "ode", "both"), default="dae",
                   help="DAE mode (default), ODE mode, or both and compare")
    p.add_argument("--stop-time", type=_positive(float), metavar="T",
                   help="default: the DefaultExperiment's stopTime, else start + 1")
    p.add_argument("--rtol", type=_positive(float), default=None, metavar="R",
                   help="relative tolerance (default: the DefaultExperiment's tolerance, else "
                        "1e-6); atol = rtol * nominal per variable")
    p.add_argument("--output-times", type=_times, metavar="t1,t2,...",
                   help="output times (default: an even grid, see --output-points)")
    p.add_argument("--output-points", type=_positive(int), default=101, metavar="N",
                   help="number of evenly spaced output times, start and stop included")
    p.add_argument("-o", "--output", metavar="CSV",
                   help="write the trajectory (DAE mode, or ODE mode with --mode ode) here")
    p.add_argument("--ode-output", metavar="CSV",
                   help="with --mode both: write the ODE-mode trajectory here")
    p.add_argument("--start-value", action="append", metavar="NAME=VALUE", default=[],
                   help="start value of a Float64 input or parameter (repeatable), set before "
                        "the initialisation; an input keeps it during the run")
    p.add_argument("--max-steps", type=_positive(int), default=100_000, metavar="N",
                   help="step budget per mode (default 100000)")
    p.add_argument("--time-limit", type=_positive(float), default=60.0, metavar="S",
                   help="wall-clock budget per mode in seconds (default 60)")
    p.add_argument("--fail-on", choices=("error", "warning"), default=None,
                   help="also exit 1 when a finding (static or of the simulation) reaches this "
                        "severity; by default only a failed integration does")
    p.add_argument("--color", choices=("auto", "always", "never"), default="auto",
                   help="colour the console output (default: auto, when a terminal)")
    p.add_argument("-v", "--verbose", action="store_true", help="log what the engine does")
    return p


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
    from .numerics.settings import Settings  # numpy: only when simulating

    path = Path(args.fmu)
    if not path.exists():
        print(f"lsdae: {path}: no such file or folder", file=sys.stderr)
        return EXIT_USAGE
    if args.rtol is not None and args.rtol >= 1:
        print("lsdae: --rtol must be below 1", file=sys.stderr)
        return EXIT_USAGE
    try:
        given = start_values(path, args.start_value)
    except ValueError as exc:
        print(f"lsdae: {exc}", file=sys.stderr)
        return EXIT_USAGE
    experiment = default_experiment(path)
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
    """Two lines about one run: where it got, at what cost, and how it ended."""
    state = "reached the stop time" if traj.ok else f"{traj.status}: {traj.message}"
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
            f"FMI calls, {traj.wall_s:.3f} s{residual}\n")


def _comparison_line(comparison: dict) -> str:
    worst = comparison.get("worst") or {}
    if not worst:
        return "DAE vs ODE: nothing to compare\n"
    return (f"DAE vs ODE: largest gap {worst['gap']:.3g} tolerance units ({worst['variable']} "
            f"at t = {worst['t']:.6g}) over {comparison.get('compared_times')} output times\n")


def _write(args: argparse.Namespace, trajectories: list) -> bool:
    from .simulate.output import write_csv  # numpy: only when writing

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
