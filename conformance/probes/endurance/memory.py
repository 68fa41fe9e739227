"""memory-grows (DAE761): the worker's resident memory, sampled along the path run of
:mod:`.run`, must not grow with the FMI calls; :func:`conformance.numerics.growth.growth`
measures the growth and this rule decides. Part of the endurance family (:mod:`.sustained`,
which registers it)."""
from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

from ...numerics.growth import attribute, growth
from ...report.findings import Violation, evidence
from ..instruments.api import ProbeContext, ProbeSkipped
from ..instruments.common import root_location
from .calls import INSTANCE_CYCLE
from .run import level_of, path_run

RUN_CODES = ("DAE760", "DAE761")    # the probes that judge the path run
KIB = 1024


def memory_grows(ctx: ProbeContext, *, bytes_per_call_quick: float, bytes_per_call_long: float,
                 min_growth_kib: float, min_function_growth_kib: float) -> Iterator[Violation]:
    """The worker's resident memory does not grow with the calls of any FMI function along the
    path run. First the growth itself, against all calls, over the second half of the samples:
    it must reach ``min_function_growth_kib``, and each of its quarters a quarter of it (a leak
    grows each quarter by about half the total; an allocator step grows one). Then the growth
    is fitted on each function's calls (the path run changes their mix between samples): a
    function whose calls it follows by ``bytes_per_call_<level>`` bytes each or more, for half
    ``min_function_growth_kib`` or more, is named. Where the fit cannot tell the functions
    apart (too few samples), the growth per call of any kind is judged, as before, with
    ``min_growth_kib``."""
    bytes_per_call = bytes_per_call_quick if level_of(ctx) == "quick" else bytes_per_call_long
    run = path_run(ctx, RUN_CODES)
    if run.memory_note:
        raise ProbeSkipped(run.memory_note)
    if run.out_of_time():
        raise ProbeSkipped(run.out_of_time())
    if run.stopped == "memory":
        yield _stopped_for_memory(ctx, run, bytes_per_call, min_growth_kib)
        return
    calls, rss = [c for c, _ in run.samples], [r for _, r in run.samples]
    found = growth(calls, rss)
    if found is None:
        raise ProbeSkipped(f"the path run ended after {run.calls:,} FMI calls ({run.stopped}): "
                           f"too few memory samples ({len(run.samples)}) to judge")
    span = run.samples[-1][0] - run.samples[len(run.samples) // 2][0]
    common = evidence(
        quarter_slopes=[round(q) for q in found.quarters],
        quarter_growth_kib=[round(q / KIB) for q in found.quarter_totals],
        growth_kib=round(found.total / KIB), threshold_bytes_per_call=bytes_per_call,
        min_growth_kib=min_growth_kib, min_function_growth_kib=min_function_growth_kib,
        calls=run.calls, stopped=run.stopped,
        level=run.settings.level, samples=_growth_samples(run.samples),
        sample_unit="[FMI calls, KiB grown since the first sample]")
    leak = _by_function(run, calls, rss, bytes_per_call, min_function_growth_kib * KIB)
    if leak is not None:
        name, per, total, heap, leaking, fitted = leak
        others = "; ".join(f"{n} {p:,.0f} bytes per call" for n, p, _ in leaking[1:])
        what = "the C heap in use" if heap else "the worker's resident memory"
        yield Violation(
            f"{what} grows by {per:,.0f} bytes per call of {{subject}} along the path "
            f"({total / KIB:,.0f} KiB over the last {span:,} of {run.calls:,} calls on one "
            "instance)" + (f", and by {others}" if others else "")
            + ": the FMU allocates without freeing", root_location(ctx),
            evidence(function=name, bytes_per_call=round(per),
                     functions={n: round(p) for n, p, _ in leaking}, fitted=fitted,
                     measured="C heap in use (mallinfo2)" if heap else "resident set (VmRSS)")
            + common + evidence(method=(
                "the growth over the second half of the samples, and across each of its "
                "quarters, then least squares on each function's calls (their mix changes "
                "between samples: one function in turn is made more often)")),
            subject=name)
        return
    if (found.sustained_slope < bytes_per_call or found.total < min_growth_kib * KIB
            or min(found.quarter_totals) < min_growth_kib * KIB / 4):
        return
    heap = growth(calls, run.heap) if len(run.heap) == len(run.samples) else None
    if heap is not None and heap.total < min_growth_kib * KIB:
        # the resident set grew, the C heap in use did not: the allocator keeping pages it
        # got back (large instances made and freed), not memory the FMU keeps
        return
    yield Violation(
        f"the worker's resident memory grows by {found.slope:,.0f} bytes per FMI call along "
        f"the path ({found.total / (1 << 20):,.1f} MiB over the last {span:,} of "
        f"{run.calls:,} calls on one instance): the FMU allocates without freeing",
        root_location(ctx), evidence(bytes_per_call=round(found.slope)) + common + evidence(
            method="least squares over the second half of the samples; each of its "
                   "quarters must show the rate too"))


def _by_function(run: Any, calls: list[int], rss: list[int], bytes_per_call: float,
                 least: float) -> tuple[str, float, float, bool, list, dict] | None:
    """The function whose calls the growth follows, or None: the C heap in use where it was
    sampled (the resident set elsewhere) must grow by ``least`` over the second half and by a
    quarter of it across each of its quarters; then each function's share is fitted, and
    those of ``bytes_per_call`` bytes per call or more, explaining half of ``least`` or more,
    are the leaking ones (the largest share first). (function, bytes per call, bytes it
    explains, whether the heap was measured, every leaking one, every fitted share)."""
    heap = run.heap if len(run.heap) == len(run.samples) else []
    series = heap or rss
    kept = growth(calls, series)
    if kept is None or kept.total < least or min(kept.quarter_totals) < least / 4:
        return None
    shares = attribute(run.counts, series) if run.counts and run.functions else None
    if shares is None:
        return None
    leaking = sorted(((name, per, total) for name, per, total in
                      zip(run.functions, shares.per_unit, shares.totals)
                      if per >= bytes_per_call and total >= least / 2),
                     key=lambda item: -item[2])
    if not leaking:
        return None
    name, per, total = leaking[0]
    return (name, per, total, bool(heap), leaking,
            {n: round(p) for n, p in zip(run.functions, shares.per_unit)})


def _stopped_for_memory(ctx: ProbeContext, run: Any, bytes_per_call: float,
                        min_growth_kib: float) -> Violation:
    """The path run stopped because memory grew by ``max_growth_mib``: the growth measured up
    to the stop is the finding, however few the samples (a fast leak takes few calls)."""
    (first_calls, first_rss), (calls, rss) = run.samples[0], run.samples[-1]
    grown = rss - first_rss
    per_call = grown / max(1, calls - first_calls)
    name, per = _took(run, grown)
    inside = (f"; the address space grew inside {name} above all (about {per:,.0f} bytes "
              "per call of it)" if name else "")
    return Violation(
        f"the worker's resident memory grew by {grown / (1 << 20):,.1f} MiB in "
        f"{calls - first_calls:,} FMI calls on one instance along the path (about "
        f"{per_call:,.0f} bytes per call), and the path run was stopped there, at "
        f"max_growth_mib = {run.settings.max_growth_mib:g} MiB{inside}: the FMU allocates "
        "without freeing", root_location(ctx),
        evidence(function=name or None, bytes_per_call_of_function=round(per) if name else None,
                 grown_inside_kib={n: round(g / KIB) for n, g in sorted(
                     run.grown_by.items(), key=lambda kv: -kv[1])[:5]},
                 bytes_per_call=round(per_call), growth_kib=round(grown / KIB),
                 threshold_bytes_per_call=bytes_per_call, min_growth_kib=min_growth_kib,
                 max_growth_mib=run.settings.max_growth_mib, calls=run.calls,
                 stopped=run.stopped, level=run.settings.level,
                 samples=_growth_samples(run.samples),
                 sample_unit="[FMI calls, KiB grown since the first sample]",
                 method="growth from the first sample to the stop, over the calls between; "
                        "the function: where the library measured the address space grow"),
        subject=name or None)


def _took(run: Any, grown: int) -> tuple[str, float]:
    """The function inside which the address space grew most (the library measures it around
    its calls), and the growth per call of it over the samples ("" when none was measured)."""
    if not run.grown_by:
        return "", 0.0
    fname = max(run.grown_by, key=lambda n: (run.grown_by[n], n))
    column = {"fmi3InstantiateModelExchange": INSTANCE_CYCLE}.get(fname, fname)
    if column not in run.functions or len(run.counts) < 2:
        return fname, 0.0
    k = run.functions.index(column)
    made = run.counts[-1][k] - run.counts[0][k]
    return fname, grown / made if made > 0 else 0.0


def _growth_samples(samples: Sequence[tuple[int, int]]) -> list[list[int]]:
    """The samples as growth since the first, in KiB: the worker's own size differs from run
    to run, its growth along the path hardly."""
    base = samples[0][1] if samples else 0
    return [[calls, (rss - base) // KIB] for calls, rss in samples]


PROBES = {
    "DAE761": memory_grows,
}
