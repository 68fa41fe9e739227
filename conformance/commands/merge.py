"""``lsdae merge``: the JSON reports of ``lsdae check --shard I/N`` jobs, joined into the report
the unsharded run would have written, in every output format, with its exit code.

The shard reports must belong together: the same lsdae, rule catalogue and options, the same
input list, every shard 1..N once, none interrupted; anything else is a one-line usage error
(exit 2). The FMUs come out in the order of the original input list (each shard records the
positions of its FMUs). Exit codes follow ``lsdae check``: ``--fail-on``, ``--exit-zero`` and
``--baseline`` (applied here, to the whole report; shards are checked without one).
"""
from __future__ import annotations

import argparse
import json
import socket
from dataclasses import replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from .. import __version__
from ..report.baseline import apply as apply_baseline
from ..report.catalogue import Catalogue, default_catalogue, with_options
from .exit_codes import EXIT_OK, EXIT_USAGE, UsageError
from ..report.findings import Report, RunInfo, thaw
from ..report.reader import ReportFormatError, read_report


def run(args: argparse.Namespace) -> int:
    from . import check  # lazy: the engine and every reporter, only to merge

    shards = [_load(path) for path in args.reports]
    report, rule_options, durations = _join(shards)
    try:
        catalogue = with_options(default_catalogue(), rule_options)
    except ValueError as exc:
        raise UsageError(f"the shards' rule options do not fit this lsdae: {exc}") from None
    _same_catalogue(catalogue, shards)
    config = check._config(args)
    settings = check._settings(args, config)
    outputs = check._outputs(args)
    baseline = check._read_baseline(settings, args)
    result = apply_baseline(report, baseline, file=settings.baseline) if baseline else None
    shown = result.marked if result else report
    note = check._baseline_note(result, settings.baseline) if result else ""
    run_info = RunInfo(timestamp=datetime.now(timezone.utc).replace(microsecond=0).isoformat(),
                       hostname=socket.gethostname(), durations=tuple(durations.items()))
    if not check._write_outputs(shown, catalogue, outputs, args.color, run_info,
                                console_note=note):
        return EXIT_USAGE
    if settings.exit_zero:
        return EXIT_OK
    return check.exit_code(result.new if result else report, settings.fail_on)


class _Shard:
    """One shard report as read, with its file name for messages."""

    def __init__(self, file: str, report: Report):
        self.file = file
        self.report = report
        self.info: dict[str, Any] = _thawed(report.shard)

    @property
    def label(self) -> str:
        return f"{self.file} (shard {self.info.get('index')}/{self.info.get('count')})"


def _thawed(value: Any) -> dict[str, Any]:
    out = thaw(value)
    return out if isinstance(out, dict) else {}


def _load(file: str) -> _Shard:
    try:
        data = json.loads(Path(file).read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read {file}: {exc.strerror or exc}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise UsageError(f"{file} is not JSON: {exc}") from None
    try:
        report = read_report(data)
    except ReportFormatError as exc:
        raise UsageError(f"{file}: {exc}") from None
    shard = _Shard(file, report)
    if not shard.info:
        raise UsageError(f"{file} is not a shard report (it was written without --shard I/N)")
    if report.tool_version != __version__:
        raise UsageError(f"{file} was written by lsdae {report.tool_version}; this is lsdae "
                         f"{__version__}: merge with the version that checked")
    if report.interrupted:
        raise UsageError(f"{shard.label} was interrupted ({len(report.not_checked)} FMUs not "
                         "checked): run that shard again")
    if "baseline" in dict(report.options):
        raise UsageError(f"{shard.label} has a baseline applied; a shard report must not "
                         "(give the baseline to lsdae merge)")
    positions = shard.info.get("positions")
    if (not isinstance(positions, list) or len(positions) != len(report.fmus)
            or not isinstance(shard.info.get("count"), int)
            or not isinstance(shard.info.get("inputs"), int)):
        raise UsageError(f"{file}: the shard section is damaged")
    return shard


def _join(shards: list[_Shard]) -> tuple[Report, dict[str, Any], dict[str, float]]:
    """The whole report, the rule options and the durations by path; UsageError when the
    shards do not belong together."""
    first = shards[0]
    for key, what in (("count", "the number of shards"),
                      ("inputs_digest", "the FMUs given (paths, order or sizes)"),
                      ("settings", "the lsdae version, rule catalogue or options")):
        for shard in shards[1:]:
            if shard.info.get(key) != first.info.get(key):
                raise UsageError(f"{shard.label} does not belong with {first.label}: "
                                 f"{what} differ")
    for shard in shards[1:]:
        if shard.report.options != first.report.options:
            raise UsageError(f"{shard.label} does not belong with {first.label}: the options "
                             "differ")
    count = first.info["count"]
    by_index: dict[Any, _Shard] = {}
    for shard in shards:
        index = shard.info.get("index")
        if index in by_index:
            raise UsageError(f"shard {index}/{count} is given twice: {by_index[index].file} and "
                             f"{shard.file}")
        by_index[index] = shard
    missing = [str(i) for i in range(1, count + 1) if i not in by_index]
    if missing or len(by_index) != count:
        raise UsageError(f"shard{'s' if len(missing) > 1 else ''} {', '.join(missing) or '?'} "
                         f"of {count} missing: give the JSON report of every shard")
    placed: dict[int, tuple[_Shard, Any, float]] = {}
    for shard in shards:
        durations = shard.info.get("durations") or [0.0] * len(shard.report.fmus)
        for position, fmu, seconds in zip(shard.info["positions"], shard.report.fmus,
                                          durations):
            if position in placed:
                raise UsageError(f"an FMU is in two shards: {fmu.path} in {shard.label} and "
                                 f"{placed[position][1].path} in {placed[position][0].label}")
            placed[position] = (shard, fmu, float(seconds))
    if sorted(placed) != list(range(first.info["inputs"])):
        raise UsageError(f"the shards hold {len(placed)} FMUs at positions that are not those "
                         f"of the {first.info['inputs']} FMUs given: the reports are damaged")
    report = replace(first.report, fmus=tuple(placed[p][1] for p in sorted(placed)), shard=())
    durations_by_path = {fmu.path: seconds for _, fmu, seconds in placed.values()}
    rule_options = first.info.get("rule_options") or {}
    return report, rule_options if isinstance(rule_options, dict) else {}, durations_by_path


def _same_catalogue(catalogue: Catalogue, shards: list[_Shard]) -> None:
    from ..run.fleet import catalogue_fingerprint  # lazy: fleet imports the result cache's writer

    if catalogue_fingerprint(catalogue) != shards[0].info.get("catalogue"):
        raise UsageError(f"{shards[0].label} was checked with another rule catalogue than this "
                         "lsdae's (another installation or rules/): merge where the shards ran")
