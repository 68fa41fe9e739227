"""The command line's grammar: every command's arguments, and nothing else.

It imports only argparse and plain constants, so that ``lsdae --version`` and ``lsdae --help``
answer without loading the engine; :mod:`conformance.commands.cli` builds the parser from here and
imports the one command it runs.
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .. import __version__
from .config import ENDURANCE_LEVELS, FAIL_ON
from ..model.drafts.names import ALL_DRAFTS
from ..reporters import FORMATS


EXIT_CODES = """exit codes:
  0    no finding at the --fail-on severity (default: error) or above
  1    at least one such finding (findings accepted by --baseline do not count)
  2    usage error, or an internal error of lsdae (a one-line message, never a traceback)
  130  interrupted (Ctrl-C): the reports of the FMUs already checked are still written"""


def build_parser() -> argparse.ArgumentParser:
    raw = argparse.RawDescriptionHelpFormatter
    parser = argparse.ArgumentParser(
        prog="lsdae", description="Conformance checker for fmi-ls-dae FMUs.",
        epilog=EXIT_CODES + "\n\n`lsdae COMMAND --help` describes each command.",
        formatter_class=raw)
    parser.add_argument("--version", action="version", version=f"lsdae {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    check = sub.add_parser("check", help="check FMUs (.fmu files or unpacked folders)",
                           description="Check FMUs: the archive, the XML against the schemas, "
                                       "the static rules, and the binary with the probes.",
                           epilog=EXIT_CODES, formatter_class=raw)
    check.add_argument("paths", nargs="+", metavar="PATH",
                       help="a .fmu file or an unpacked FMU folder; several are checked in turn")
    _check_arguments(check)

    hook = sub.add_parser("pre-commit", help="check the FMUs that changed files belong to "
                                             "(the pre-commit hook's entry point)",
                          epilog=EXIT_CODES, formatter_class=raw)
    hook.add_argument("paths", nargs="*", metavar="FILE",
                      help=".fmu files, and modelDescription.xml or fmi-ls-dae manifests of "
                           "unpacked FMU folders")
    _check_arguments(hook)

    rules = sub.add_parser("rules", help="list the rules")
    rules.add_argument("--format", choices=("text", "markdown"), default="text",
                       help="text: one line per rule (default); markdown: the full rule docs "
                            "(docs/rules.md is this output)")

    explain = sub.add_parser("explain", help="show one rule in full")
    explain.add_argument("rule", metavar="CODE-or-name",
                         help="a rule code (DAE601) or name (algebraic-jacobian-singular)")
    add_simulate_parser(sub)
    add_fix_parser(sub)
    add_merge_parser(sub)
    return parser


def _jobs(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of processes: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError("-j takes 0 (one per CPU) or more")
    return value


def _check_arguments(check: argparse.ArgumentParser) -> None:
    check.add_argument("--format", action="append", metavar="NAME[:FILE]",
                       help=f"output format ({', '.join(FORMATS)}), optionally with a "
                            "file; repeatable. Default: console")
    check.add_argument("-o", "--output", metavar="FILE",
                       help="write the report to FILE instead of the terminal (for one --format "
                            "given without :FILE, e.g. --format json -o report.json)")
    check.add_argument("--select", action="append", metavar="RULES",
                       help="only these rules: codes, names or code prefixes, comma-separated")
    check.add_argument("--ignore", action="append", metavar="RULES", help="skip these rules")
    check.add_argument("--severity", action="append", metavar="RULE=LEVEL",
                       help="override a rule's severity (info, warning, error)")
    check.add_argument("--draft", default=None, choices=("auto", *ALL_DRAFTS),
                       help="which fmi-ls-dae draft to check against (default: auto-detect)")
    probes = check.add_mutually_exclusive_group()
    probes.add_argument("--no-probes", action="store_true",
                        help="static checks only: do not load the FMU's binary")
    probes.add_argument("--probes-only", action="store_true",
                        help="skip the schema and static rules; run the dynamic probes")
    check.add_argument("--endurance", choices=ENDURANCE_LEVELS, default=None,
                       help="endurance probes: thousands of calls on one instance, memory "
                            "growth, instance independence (default: quick; long: a longer "
                            "budget; off: skip them)")
    check.add_argument("--probe-workers", choices=("auto", "1", "2"), default="auto",
                       help="probe workers at once for one FMU (auto: two for an FMU of 1,000 "
                            "variables or more; the findings are the same)")
    check.add_argument("--seed", type=int, default=0,
                       help="seed for the probes' sampled points (recorded in the report)")
    check.add_argument("--config", type=Path, metavar="PYPROJECT",
                       help="read [tool.lsdae] from this file instead of the nearest pyproject")
    check.add_argument("--rule-option", action="append", metavar="RULE.OPTION=VALUE",
                       help="set a rule's option (see `lsdae explain RULE`), e.g. "
                            "DAE740.rtol=1e-4; repeatable; also [tool.lsdae.rule-options]")
    check.add_argument("--color", choices=("auto", "always", "never"), default="auto",
                       help="colour the console output (default: auto, on a terminal unless "
                            "NO_COLOR is set)")
    check.add_argument("-v", "--verbose", action="store_true", help="log what the engine does")
    _verdict_arguments(check)
    check.add_argument("--write-baseline", metavar="FILE",
                       help="write this run's findings to FILE as the accepted baseline")
    check.add_argument("-j", "--jobs", type=_jobs, default=None, metavar="N",
                       help="check N FMUs in parallel processes (0: one per CPU; default 1)")
    check.add_argument("--progress", choices=("auto", "always", "never"), default="auto",
                       help="progress on stderr (auto: on a terminal, outside CI, for several "
                            "FMUs or with probes)")
    check.add_argument("--shard", metavar="I/N", help="check only the I-th of N size-balanced "
                       "shares of the FMUs (one job of a CI matrix); `lsdae merge` joins the "
                       "shards' JSON reports and applies the baseline")
    check.add_argument("--cache-dir", metavar="DIR", help="keep each FMU's result in DIR, keyed "
                       "by its content and the settings; an unchanged FMU is not checked again")


def _verdict_arguments(parser: argparse.ArgumentParser) -> None:
    """What decides the exit code, the same for ``check`` and ``merge``."""
    parser.add_argument("--fail-on", choices=FAIL_ON, default=None,
                        help="the least severity that makes the exit code 1 (default: error)")
    parser.add_argument("--exit-zero", action="store_true", default=None,
                        help="exit 0 whatever is found (usage and internal errors still exit 2)")
    base = parser.add_mutually_exclusive_group()
    base.add_argument("--baseline", metavar="FILE",
                      help="accept the findings listed in FILE (written by --write-baseline): "
                           "they are shown, marked as baselined, and only new findings decide "
                           "the exit code")
    base.add_argument("--no-baseline", action="store_true",
                      help="ignore the baseline named in [tool.lsdae]")


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
    from ..numerics.settings import parse_times  # numpy: only when the option is given

    try:
        return parse_times(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


SIMULATE_EPILOG = """exit codes:
  0  the integration reached the stop time and the trajectory was written
  1  the integration failed or stopped early (the reason is printed; the trajectory up to
     where it ended is still written), the simulation found a fault (with --mode both: the DAE
     and ODE trajectories differ), nothing could be simulated, the output could not be
     written, or --fail-on was given and a static finding reaches it
  2  usage error (bad arguments, no such file)

The start time is the DefaultExperiment's startTime (0 without one); the stop time and the
tolerance are the DefaultExperiment's unless given. Static findings (archive, XML, schema) are
summarised in one line: `lsdae check FMU` shows them."""


def add_simulate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to ``subparsers`` (from ``add_subparsers``)."""
    p = subparsers.add_parser(
        "simulate", help="integrate an FMU in DAE mode (IDA) and/or ODE mode (CVODE)",
        description="Integrate an fmi-ls-dae FMU in DAE mode with SUNDIALS IDA (the FMU's "
                    "Jacobian), in ODE mode with CVODE, or both and compare them.",
        epilog=SIMULATE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
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


FIX_EPILOG = """exit codes:
  0  nothing at the --fail-on severity (default: error) remains after fixing
  1  at least one such finding remains
  2  usage error (no such FMU, no output chosen, -o naming the input without --in-place)

Only safe fixes are applied: those that follow from the files alone (`lsdae rules` marks the
fixable rules, `lsdae explain RULE` says how). Every other archive member is copied unchanged."""


def add_fix_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``fix`` subcommand to ``subparsers`` (from ``add_subparsers``)."""
    p = subparsers.add_parser(
        "fix", help="repair what can be derived from the files, then re-check",
        description="Apply the safe fixes to an FMU (.fmu file or unpacked folder) and re-check "
                    "it.", epilog=FIX_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", metavar="FMU", nargs="+",
                   help="a .fmu file or an unpacked FMU folder (several with --in-place or "
                        "--diff)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", metavar="FIXED", help="write the fixed FMU here")
    where.add_argument("--diff", action="store_true",
                       help="print a unified diff of every changed file; write nothing")
    p.add_argument("--in-place", action="store_true", help="overwrite the FMU itself")
    p.add_argument("--pre-commit", action="store_true",
                   help="the arguments are changed files (modelDescription.xml, manifests, "
                        ".fmu): fix the FMUs they belong to in place, and exit 1 when a file "
                        "changed (the lsdae-fix pre-commit hook)")
    p.add_argument("--select", action="append", metavar="RULES",
                   help="only these rules: codes, names or code prefixes, comma-separated")
    p.add_argument("--ignore", action="append", metavar="RULES", help="skip these rules")
    p.add_argument("--unsafe-fixes", action="store_true",
                   help="also apply the fixes from what the probes observed the binary do "
                        "(add an observed dependency, make an observed kind dependent); they "
                        "only widen what the manifest claims, each re-checked with the probes")
    p.add_argument("--no-probes", action="store_true",
                   help="do not load the binary for the final check (the safe fixes need none)")
    p.add_argument("--fail-on", choices=("error", "warning", "info", "never"), default="error",
                   help="the least severity that makes the exit code 1 (default: error)")
    p.add_argument("--color", choices=("auto", "always", "never"), default="auto",
                   help="colour the console output (default: auto, on a terminal)")
    return p


def add_merge_parser(sub: Any) -> None:
    merge = sub.add_parser(
        "merge", help="join the JSON reports of `lsdae check --shard I/N` jobs into one report",
        description="Join the JSON reports of the shards of one run (`lsdae check --shard I/N "
                    "--format json:FILE`) into the report the unsharded run would have "
                    "written, in any format, with its exit code.",
        epilog=EXIT_CODES, formatter_class=argparse.RawDescriptionHelpFormatter)
    merge.add_argument("reports", nargs="+", metavar="REPORT.json",
                       help="the JSON report of every shard, 1 to N, in any order")
    merge.add_argument("--format", action="append", metavar="NAME[:FILE]",
                       help="output format, as for `lsdae check`, optionally with a file; "
                            "repeatable. Default: console")
    merge.add_argument("-o", "--output", metavar="FILE",
                       help="write the report to FILE (for one --format given without :FILE)")
    _verdict_arguments(merge)
    merge.add_argument("--config", type=Path, metavar="PYPROJECT",
                       help="read [tool.lsdae] from this file instead of the nearest pyproject")
    merge.add_argument("--color", choices=("auto", "always", "never"), default="auto",
                       help="colour the console output (default: auto)")
    merge.add_argument("-v", "--verbose", action="store_true", help="log what merge does")
    merge.set_defaults(jobs=None, write_baseline=None)
