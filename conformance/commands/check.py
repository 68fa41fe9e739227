"""``lsdae check`` and ``lsdae pre-commit``: options from the command line and the config, the
run, the baseline, the outputs and the exit code."""
from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..report.baseline import Baseline, BaselineError, BaselineResult
from ..report.baseline import apply as apply_baseline
from ..report.baseline import load as load_baseline
from ..report.baseline import write as write_baseline
from ..report.catalogue import Catalogue, default_catalogue, with_options
from .config import ConfigError, load_config
from ..run.engine import EngineOptions
from .exit_codes import EXIT_FINDINGS, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, UsageError
from ..report.findings import Report, RunInfo, Severity
from ..run.fleet import plan as fleet_plan
from ..run.parallel import check_all
from .precommit import fmu_roots
from ..run.progress import make_progress
from ..reporters import REPORTER_BY_NAME

INTERNAL_ERROR = "internal-error"   # lsdae failed on an FMU: exit 2, whatever its severity


def _split(values: Sequence[str] | None) -> tuple[str, ...]:
    out: list[str] = []
    for value in values or ():
        out.extend(v.strip() for v in value.split(",") if v.strip())
    return tuple(out)


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
        probe_workers=_probe_workers(getattr(args, "probe_workers", None)),
    )


def _probe_workers(chosen: str | None) -> int:
    """``--probe-workers``: 1 or 2, or 0 for auto (the default, and commands without it)."""
    return 0 if chosen in (None, "auto") else int(chosen)


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
    """1 when a finding reaches the ``--fail-on`` severity, else 0; 2 when lsdae itself failed
    on an FMU (``internal-error``, a warning: a limit of lsdae's, never a verdict on the FMU, but
    an FMU nobody checked must not pass)."""
    if fail_on == "never":
        return EXIT_OK
    if any(f.name == INTERNAL_ERROR for f in report.all_findings()):
        return EXIT_USAGE
    return EXIT_FINDINGS if report.has_at_least(Severity.parse(fail_on)) else EXIT_OK


def rule_options(args: argparse.Namespace, config: dict) -> dict[str, dict[str, Any]]:
    """[tool.lsdae.rule-options], then --rule-option RULE.OPTION=VALUE (the command line wins);
    a value is read as TOML (``1e-4``, ``true``, ``"text"``)."""
    out = {rule: dict(values) for rule, values in config.get("rule-options", {}).items()}
    for item in getattr(args, "rule_option", None) or ():
        key, sep, text = item.partition("=")
        rule, dot, name = key.strip().rpartition(".")
        if not sep or not dot or not rule or not name:
            raise UsageError(f"--rule-option takes RULE.OPTION=VALUE, not {item!r}")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()  # a bare word: a string
        out.setdefault(rule, {})[name.strip()] = value
    return out


def _catalogue(args: argparse.Namespace, config: dict) -> Catalogue:
    try:
        return with_options(default_catalogue(), rule_options(args, config))
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def cmd_check(args: argparse.Namespace) -> int:
    config = _config(args)
    catalogue = _catalogue(args, config)
    options = _options(args, config)
    settings = _settings(args, config)
    outputs = _outputs(args)
    baseline = None if args.shard else _read_baseline(settings, args)  # merge applies it
    durations: dict[str, float] = {}
    started = datetime.now(timezone.utc).replace(microsecond=0).isoformat()
    try:  # --shard and --cache-dir: which FMUs this run checks (conformance/run/fleet.py)
        fleet = fleet_plan(args.paths, shard=args.shard, cache_dir=args.cache_dir,
                           options=options, catalogue=catalogue,
                           rule_options=rule_options(args, config))
        progress = make_progress(args.progress, total=len(fleet.todo), probes=options.probes)
        report = fleet.finish(check_all(fleet.todo, options=options, catalogue=catalogue,
                                        jobs=settings.jobs, progress=progress,
                                        durations=durations), durations)
    except ValueError as exc:  # a bad --select/--ignore pattern or --shard
        raise UsageError(str(exc)) from None
    run = RunInfo(timestamp=started, hostname=socket.gethostname(),
                  durations=tuple(durations.items()))
    if report.interrupted:
        print(f"lsdae: interrupted: {len(report.fmus)} of {len(fleet.selected)} FMUs checked; "
              "the reports are written for those", file=sys.stderr)
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
    if report.interrupted:
        return EXIT_INTERRUPTED
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
