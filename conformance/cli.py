"""Command line: argument parsing and wiring only; each command returns the exit code.

The commands live beside it: :mod:`conformance.check_command` (``check``, ``pre-commit``),
:mod:`conformance.rules_command` (``rules``, ``explain``) and :mod:`conformance.simulate_command`;
the exit codes and :class:`~conformance.exit_codes.UsageError` in :mod:`conformance.exit_codes`.
"""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Sequence

from . import __version__
from .catalogue import CatalogueError
from .check_command import cmd_check, cmd_precommit
from .config import ENDURANCE_LEVELS, FAIL_ON
from .drafts.detect import ALL_DRAFTS
from .exit_codes import EXIT_INTERRUPTED, EXIT_USAGE, UsageError
from .reporters import REPORTER_BY_NAME
from .rules_command import cmd_explain, cmd_rules
from . import simulate_command
from . import fix_command
from . import merge_command


EXIT_CODES = """exit codes:
  0    no finding at the --fail-on severity (default: error) or above
  1    at least one such finding (findings accepted by --baseline do not count)
  2    usage error, or an internal error of lsdae (a one-line message, never a traceback)
  130  interrupted (Ctrl-C): the reports of the FMUs already checked are still written"""


def _parser() -> argparse.ArgumentParser:
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
    simulate_command.add_parser(sub)
    fix_command.add_parser(sub)
    merge_command.add_parser(sub, raw, EXIT_CODES)
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
                       help=f"output format ({', '.join(REPORTER_BY_NAME)}), optionally with a "
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
    check.add_argument("--fail-on", choices=FAIL_ON, default=None,
                       help="the least severity that makes the exit code 1 (default: error)")
    check.add_argument("--exit-zero", action="store_true", default=None,
                       help="exit 0 whatever is found (usage and internal errors still exit 2)")
    base = check.add_mutually_exclusive_group()
    base.add_argument("--baseline", metavar="FILE",
                      help="accept the findings listed in FILE: they are shown, marked as "
                           "baselined, and only new findings decide the exit code")
    base.add_argument("--no-baseline", action="store_true",
                      help="ignore the baseline named in [tool.lsdae]")
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



COMMANDS = {"check": cmd_check, "pre-commit": cmd_precommit, "rules": cmd_rules,
            "explain": cmd_explain, "simulate": simulate_command.run,
            "fix": fix_command.run, "merge": merge_command.run}


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if getattr(args, "verbose", False) else logging.ERROR,
                        format="lsdae: %(levelname)s: %(message)s")
    try:
        return COMMANDS[args.command](args)
    except UsageError as exc:
        print(f"lsdae: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except CatalogueError as exc:
        print(f"lsdae: the rule catalogue is broken: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:  # outside a run of checks (those write what they finished)
        print("lsdae: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # never a bare traceback
        logging.getLogger(__name__).debug("internal error", exc_info=True)
        print(f"lsdae: internal error: {type(exc).__name__}: {exc} (run with -v for details)",
              file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
