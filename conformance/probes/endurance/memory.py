"""memory-grows (DAE761): the worker's resident memory, sampled along the path run of
:mod:`.run`, must not grow with the FMI calls; :func:`conformance.numerics.growth.growth`
measures the growth and this rule decides. Part of the endurance family (:mod:`.sustained`,
which registers it)."""
from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

from ...numerics.growth import growth
from ...report.findings import Violation, evidence
from ..instruments.api import ProbeContext, ProbeSkipped
from ..instruments.common import root_location
from .run import level_of, path_run

RUN_CODES = ("DAE760", "DAE761")    # the probes that judge the path run
KIB = 1024


def memory_grows(ctx: ProbeContext, *, bytes_per_call_quick: float, bytes_per_call_long: float,
                 min_growth_kib: float) -> Iterator[Violation]:
    """The worker's resident memory does not grow with the FMI calls of the path run: the
    least-squares slope over the second half of the samples, and each of its quarters alone,
    stay below ``bytes_per_call_<level>``, or the growth over that half below
    ``min_growth_kib``, or the growth across either quarter below a quarter of it (a leak grows
    each quarter by about half the total; an allocator step grows one)."""
    bytes_per_call = bytes_per_call_quick if level_of(ctx) == "quick" else bytes_per_call_long
    run = path_run(ctx, RUN_CODES)
    if run.memory_note:
        raise ProbeSkipped(run.memory_note)
    if run.out_of_time():
        raise ProbeSkipped(run.out_of_time())
    if run.stopped == "memory":
        yield _stopped_for_memory(ctx, run, bytes_per_call, min_growth_kib)
        return
    found = growth([c for c, _ in run.samples], [r for _, r in run.samples])
    if found is None:
        raise ProbeSkipped(f"the path run ended after {run.calls:,} FMI calls ({run.stopped}): "
                           f"too few memory samples ({len(run.samples)}) to judge")
    if (found.sustained_slope < bytes_per_call or found.total < min_growth_kib * KIB
            or min(found.quarter_totals) < min_growth_kib * KIB / 4):
        return
    span = run.samples[-1][0] - run.samples[len(run.samples) // 2][0]
    yield Violation(
        f"the worker's resident memory grows by {found.slope:,.0f} bytes per FMI call along "
        f"the path ({found.total / (1 << 20):,.1f} MiB over the last {span:,} of "
        f"{run.calls:,} calls on one instance): the FMU allocates without freeing",
        root_location(ctx),
        evidence(bytes_per_call=round(found.slope), quarter_slopes=[round(q) for q in
                                                                      found.quarters],
                 quarter_growth_kib=[round(q / KIB) for q in found.quarter_totals],
                 growth_kib=round(found.total / KIB), threshold_bytes_per_call=bytes_per_call,
                 min_growth_kib=min_growth_kib, calls=run.calls, stopped=run.stopped,
                 level=run.settings.level, samples=_growth_samples(run.samples),
                 sample_unit="[FMI calls, KiB grown since the first sample]",
                 method="least squares over the second half of the samples; each of its "
                        "quarters must show the rate too"))


def _stopped_for_memory(ctx: ProbeContext, run: Any, bytes_per_call: float,
                        min_growth_kib: float) -> Violation:
    """The path run stopped because memory grew by ``max_growth_mib``: the growth measured up
    to the stop is the finding, however few the samples (a fast leak takes few calls)."""
    (first_calls, first_rss), (calls, rss) = run.samples[0], run.samples[-1]
    grown = rss - first_rss
    per_call = grown / max(1, calls - first_calls)
    return Violation(
        f"the worker's resident memory grew by {grown / (1 << 20):,.1f} MiB in "
        f"{calls - first_calls:,} FMI calls on one instance along the path (about "
        f"{per_call:,.0f} bytes per call), and the path run was stopped there, at "
        f"max_growth_mib = {run.settings.max_growth_mib:g} MiB: the FMU allocates without "
        "freeing", root_location(ctx),
        evidence(bytes_per_call=round(per_call), growth_kib=round(grown / KIB),
                 threshold_bytes_per_call=bytes_per_call, min_growth_kib=min_growth_kib,
                 max_growth_mib=run.settings.max_growth_mib, calls=run.calls,
                 stopped=run.stopped, level=run.settings.level,
                 samples=_growth_samples(run.samples),
                 sample_unit="[FMI calls, KiB grown since the first sample]",
                 method="growth from the first sample to the stop, over the calls between"))


def _growth_samples(samples: Sequence[tuple[int, int]]) -> list[list[int]]:
    """The samples as growth since the first, in KiB: the worker's own size differs from run
    to run, its growth along the path hardly."""
    base = samples[0][1] if samples else 0
    return [[calls, (rss - base) // KIB] for calls, rss in samples]


PROBES = {
    "DAE761": memory_grows,
}
