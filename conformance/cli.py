"""Command line: argument parsing and wiring only; computes the exit code.

Exit codes: 0 no finding at the ``--fail-on`` severity (default error) or above, 1 at least one
(findings accepted by ``--baseline`` do not count), 2 usage or internal error.
"""
from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Sequence

from . import __version__
from .baseline import Baseline, BaselineError, BaselineResult
from .baseline import apply as apply_baseline
from .baseline import load as load_baseline
from .baseline import write as write_baseline
from .catalogue import Catalogue, CatalogueError, RuleSpec, default_catalogue
from .config import ENDURANCE_LEVELS, FAIL_ON, ConfigError, load_config
from .drafts.detect import ALL_DRAFTS, DRAFT_LABELS
from .engine import EngineOptions
from .findings import Report, RunInfo, Severity
from .parallel import check_all
from .precommit import fmu_roots
from .progress import make_progress
from .reporters import REPORTER_BY_NAME
from .ruledocs import render_markdown
from . import simulate_command

EXIT_OK, EXIT_FINDINGS, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    pass


def _split(values: Sequence[str] | None) -> tuple[str, ...]:
    out: list[str] = []
    for value in values or ():
        out.extend(v.strip() for v in value.split(",") if v.strip())
    return tuple(out)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="lsdae", description="Conformance checker for fmi-ls-dae FMUs.")
    parser.add_argument("--version", action="version", version=f"lsdae {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    check = sub.add_parser("check", help="check FMUs (.fmu files or unpacked folders)")
    check.add_argument("paths", nargs="+", metavar="PATH")
    _check_arguments(check)

    hook = sub.add_parser("pre-commit", help="check the FMUs that changed files belong to "
                                             "(the pre-commit hook's entry point)")
    hook.add_argument("paths", nargs="*", metavar="FILE",
                      help=".fmu files, and modelDescription.xml or fmi-ls-dae manifests of "
                           "unpacked FMU folders")
    _check_arguments(hook)

    rules = sub.add_parser("rules", help="list the rules")
    rules.add_argument("--format", choices=("text", "markdown"), default="text")

    explain = sub.add_parser("explain", help="show one rule in full")
    explain.add_argument("rule", metavar="CODE-or-name")
    simulate_command.add_parser(sub)
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
                       help="write the (single) format without a file here")
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
    check.add_argument("--seed", type=int, default=0,
                       help="seed for the probes' sampled points (recorded in the report)")
    check.add_argument("--endurance", choices=ENDURANCE_LEVELS, default=None,
                       help="endurance probes: thousands of calls on one instance, memory "
                            "growth, instance independence (default: quick; long: a longer "
                            "budget; off: skip them)")
    check.add_argument("--config", type=Path, metavar="PYPROJECT",
                       help="read [tool.lsdae] from this file instead of the nearest pyproject")
    check.add_argument("--color", choices=("auto", "always", "never"), default="auto")
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


def _config(args: argparse.Namespace) -> dict:
    try:
        return load_config(args.config).values
    except ConfigError as exc:
        raise UsageError(str(exc)) from None


def _options(args: argparse.Namespace, config: dict | None = None) -> EngineOptions:
    config = _config(args) if config is None else config
    severity = dict(config.get("severity", {}))
    for item in args.severity or ():
        code, sep, level = item.partition("=")
        if not sep:
            raise UsageError(f"--severity takes RULE=LEVEL, not {item!r}")
        severity[code.strip()] = level.strip()
    for level in severity.values():
        try:
            Severity.parse(level)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    return EngineOptions(
        select=_split(args.select) or tuple(config.get("select", ())),
        ignore=_split(args.ignore) or tuple(config.get("ignore", ())),
        severity=tuple(severity.items()),
        draft=args.draft or config.get("draft", "auto"),
        probes=not args.no_probes and bool(config.get("probes", True)),
        probes_only=args.probes_only, seed=args.seed,
        endurance=args.endurance or config.get("endurance", "quick"),
    )


def _outputs(args: argparse.Namespace) -> list[tuple[str, str | None]]:
    specs = args.format or ["console"]
    outputs: list[tuple[str, str | None]] = []
    for spec in specs:
        name, sep, file = spec.partition(":")
        if name not in REPORTER_BY_NAME:
            raise UsageError(f"unknown format {name!r} (choose from {', '.join(REPORTER_BY_NAME)})")
        outputs.append((name, file if sep else None))
    bare = [i for i, (_, f) in enumerate(outputs) if f is None]
    if args.output:
        if len(bare) != 1:
            raise UsageError("-o needs exactly one --format without its own file")
        outputs[bare[0]] = (outputs[bare[0]][0], args.output)
    return outputs


def _use_color(choice: str, file: str | None) -> bool:
    if choice == "always":
        return True
    if choice == "never" or file is not None or os.environ.get("NO_COLOR"):
        return False
    return sys.stdout.isatty()


@dataclass(frozen=True)
class _RunSettings:
    """What decides the exit code and how the run goes, from the command line or the config."""

    fail_on: str
    exit_zero: bool
    baseline: str | None
    jobs: int


def _settings(args: argparse.Namespace, config: dict) -> _RunSettings:
    baseline = None if args.no_baseline else (args.baseline or config.get("baseline"))
    jobs = args.jobs if args.jobs is not None else config.get("jobs", 1)
    return _RunSettings(
        fail_on=args.fail_on or config.get("fail-on", "error"),
        exit_zero=bool(args.exit_zero if args.exit_zero is not None
                       else config.get("exit-zero", False)),
        baseline=baseline, jobs=jobs or os.cpu_count() or 1)


def _read_baseline(settings: _RunSettings, args: argparse.Namespace) -> Baseline | None:
    if settings.baseline is None or args.write_baseline:
        return None  # a baseline being written replaces the one being read
    try:
        return load_baseline(Path(settings.baseline))
    except BaselineError as exc:
        hint = f"; create it with --write-baseline {settings.baseline}" \
            if not Path(settings.baseline).exists() else ""
        raise UsageError(f"{exc}{hint}") from None


def exit_code(report: Report, fail_on: str) -> int:
    """1 when a finding reaches the ``--fail-on`` severity, else 0."""
    if fail_on == "never":
        return EXIT_OK
    return EXIT_FINDINGS if report.has_at_least(Severity.parse(fail_on)) else EXIT_OK


def cmd_check(args: argparse.Namespace) -> int:
    catalogue = default_catalogue()
    config = _config(args)
    options = _options(args, config)
    settings = _settings(args, config)
    outputs = _outputs(args)
    baseline = _read_baseline(settings, args)
    durations: dict[str, float] = {}
    started = datetime.now(timezone.utc).replace(microsecond=0).isoformat()
    progress = make_progress(args.progress, total=len(args.paths), probes=options.probes)
    try:
        report = check_all(args.paths, options=options, catalogue=catalogue,
                           jobs=settings.jobs, progress=progress, durations=durations)
    except ValueError as exc:  # a bad --select/--ignore pattern
        raise UsageError(str(exc)) from None
    run = RunInfo(timestamp=started, hostname=socket.gethostname(),
                  durations=tuple(durations.items()))
    result = None
    if args.write_baseline:
        try:
            baseline = write_baseline(report, Path(args.write_baseline))
        except BaselineError as exc:
            raise UsageError(str(exc)) from None
        result = apply_baseline(report, baseline, file=args.write_baseline)
    elif baseline is not None:
        result = apply_baseline(report, baseline, file=settings.baseline)
    shown = result.marked if result else report
    note = _baseline_note(result, args.write_baseline or settings.baseline) if result else ""
    if not _write_outputs(shown, catalogue, outputs, args.color, run, console_note=note):
        return EXIT_USAGE
    if settings.exit_zero:
        return EXIT_OK
    return exit_code(result.new if result else report, settings.fail_on)


def _baseline_note(result: BaselineResult, file: str | None) -> str:
    counts = result.summary()
    note = (f"baseline {file}: {counts['baselined']} finding"
            f"{'' if counts['baselined'] == 1 else 's'} accepted, {counts['new']} new")
    if counts["stale"]:
        note += f", {counts['stale']} fixed since (rewrite it with --write-baseline)"
    return note + "\n"


def _write_outputs(report: Report, catalogue: Catalogue, outputs: list[tuple[str, str | None]],
                   color: str, run: RunInfo, *, console_note: str = "") -> bool:
    """Render and write every output; each on its own, so one failing never loses the others."""
    ok = True
    for name, file in outputs:
        try:
            text = REPORTER_BY_NAME[name](report, catalogue, color=_use_color(color, file),
                                          run=run)
        except Exception as exc:
            logging.getLogger(__name__).debug("reporter %s failed", name, exc_info=True)
            print(f"lsdae: internal error in the {name} reporter: {type(exc).__name__}: {exc}",
                  file=sys.stderr)
            ok = False
            continue
        if name == "console":
            text += console_note
        if file is None or file == "-":
            sys.stdout.write(text)
            continue
        try:
            Path(file).parent.mkdir(parents=True, exist_ok=True)
            Path(file).write_text(text, encoding="utf-8")
        except OSError as exc:
            print(f"lsdae: cannot write {file}: {exc}", file=sys.stderr)
            ok = False
    return ok


def cmd_precommit(args: argparse.Namespace) -> int:
    """``lsdae pre-commit FILES``: check the FMUs the changed files belong to."""
    args.paths = fmu_roots(args.paths)
    if not args.paths:
        return EXIT_OK
    return cmd_check(args)


def _rule_line(rule: RuleSpec) -> str:
    return f"{rule.code}  {rule.name:<40} {str(rule.severity):<8} {rule.summary}"


def cmd_rules(args: argparse.Namespace) -> int:
    catalogue = default_catalogue()
    if args.format == "markdown":
        sys.stdout.write(render_markdown(catalogue))
    else:
        for rule in catalogue:
            print(_rule_line(rule))
    return EXIT_OK


def explain_text(rule: RuleSpec) -> str:
    drafts = ", ".join("all drafts" if d == "*" else DRAFT_LABELS.get(d, d) for d in rule.drafts)
    parts = [
        f"{rule.code} {rule.name}  ({rule.severity}, {rule.stage} stage)",
        "", rule.summary, "",
        f"Applies to: {drafts}",
        f"Spec:       {rule.spec}",
    ]
    if rule.aliases:
        parts.append(f"Aliases:    {', '.join(rule.aliases)}")
    parts += ["", "Why it matters:", _indent(rule.rationale), "", "Fails:", _indent(rule.bad),
              "", "Passes:", _indent(rule.good)]
    if rule.options:
        parts += ["", "Options:"] + [f"    {k} = {v!r}" for k, v in rule.options]
    return "\n".join(parts) + "\n"


def _indent(text: str) -> str:
    return "\n".join(f"    {line}" if line else "" for line in text.splitlines())


def cmd_explain(args: argparse.Namespace, catalogue: Catalogue | None = None) -> int:
    catalogue = catalogue or default_catalogue()
    rule = catalogue.get(args.rule)
    if rule is None:
        raise UsageError(f"no rule {args.rule!r} (see `lsdae rules`)")
    sys.stdout.write(explain_text(rule))
    return EXIT_OK


COMMANDS = {"check": cmd_check, "pre-commit": cmd_precommit, "rules": cmd_rules,
            "explain": cmd_explain, "simulate": simulate_command.run}


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
    except KeyboardInterrupt:
        print("lsdae: interrupted", file=sys.stderr)
        return EXIT_USAGE
    except Exception as exc:  # never a bare traceback
        logging.getLogger(__name__).debug("internal error", exc_info=True)
        print(f"lsdae: internal error: {type(exc).__name__}: {exc} (run with -v for details)",
              file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
