"""Sustained growth against allocator noise (conformance.numerics.growth)."""
from __future__ import annotations

import numpy as np
import pytest

from conformance.numerics.growth import MIN_SAMPLES, attribute, growth

CALLS = np.arange(0, 50_001, 1250, dtype=float)     # 41 samples, as a quick path run takes
BASE = 45 << 20                                      # 45 MiB resident before the run
PAGE = 4096


def _pages(values: np.ndarray) -> np.ndarray:
    """Resident sizes come in whole pages."""
    return np.floor(values / PAGE) * PAGE


def test_a_leak_is_measured_in_every_late_quarter():
    found = growth(CALLS, _pages(BASE + 200.0 * CALLS))
    assert found is not None
    assert abs(found.slope - 200) < 2 and all(abs(q - 200) < 5 for q in found.quarters)
    assert found.sustained_slope > 190
    assert abs(found.total - 200 * 25_000) < 0.01 * 200 * 25_000
    assert found.samples == len(CALLS) - len(CALLS) // 2


def test_a_single_allocator_step_is_not_sustained():
    rss = BASE + np.where(CALLS > 40_000, 2 << 20, 0)   # one 2 MiB top-up of the heap, late
    found = growth(CALLS, rss)
    assert found is not None and found.slope > 64       # the plain fit would call it a leak
    assert found.sustained_slope < 1                     # one quarter shows nothing


def test_warm_up_that_settles_is_not_growth():
    rss = BASE + np.minimum(CALLS, 20_000) * 300.0       # a cache that fills, then stops
    found = growth(CALLS, _pages(rss))
    assert found is not None and abs(found.slope) < 1 and found.total < PAGE * 2


def test_noise_of_a_few_pages_stays_far_below_any_leak():
    rng = np.random.default_rng(1)
    rss = BASE + PAGE * rng.integers(-3, 4, len(CALLS))
    found = growth(CALLS, rss)
    assert found is not None and abs(found.slope) < 5 and found.sustained_slope < 10


def test_too_few_samples_give_no_judgement():
    assert growth(CALLS[:MIN_SAMPLES - 1], CALLS[:MIN_SAMPLES - 1]) is None
    assert growth([], []) is None


def test_each_late_quarter_reports_the_growth_its_own_slope_makes():
    found = growth(CALLS, _pages(BASE + 200.0 * CALLS))
    assert found is not None
    assert all(abs(t - 200 * 12_500) < 0.02 * 200 * 12_500 for t in found.quarter_totals)
    assert abs(sum(found.quarter_totals) - found.total) < 0.02 * found.total


def test_a_step_in_a_short_run_leaves_the_other_quarter_a_creep_of_a_few_pages():
    # a large model's quick path: about 750 calls; a page every ~45 calls (tens of bytes per
    # call, above the quick threshold of 64) and one 2.7 MiB step of the heap late
    calls = np.arange(0, 750, 18, dtype=float)
    rss = _pages(BASE + 90.0 * calls) + np.where(calls > 570, 2.7 * (1 << 20), 0)
    found = growth(calls, rss)
    assert found is not None and found.sustained_slope > 64
    assert min(found.quarter_totals) < 8 * PAGE and max(found.quarter_totals) > 1 << 20


def _rotated(samples: int, leak: dict[int, float], columns: int = 4, steps: int = 125,
             noise_pages: bool = True) -> tuple[list[list[float]], list[float]]:
    """Call counts of ``columns`` functions called once per step, the one in turn made three
    times per step between two samples, and the heap growing by ``leak[j]`` bytes per call of
    column j (plus a page now and then)."""
    rng = np.random.default_rng(1)
    counts, y = np.zeros(columns), 0.0
    rows, heap = [], []
    for k in range(samples):
        made = np.full(columns, float(steps))
        made[k % columns] += 2 * steps
        counts = counts + made
        y += sum(per * made[j] for j, per in leak.items())
        y += 4096.0 * rng.integers(0, 2) if noise_pages else 0.0
        rows.append(counts.tolist())
        heap.append(y)
    return rows, heap


def test_the_growth_is_attributed_to_the_function_whose_calls_it_follows():
    """80 bytes per call of the second function: its share is 80 (within a few bytes of page
    noise), the others' near 0, and the bytes it explains are its share times its calls."""
    rows, heap = _rotated(40, {1: 80.0})
    found = attribute(rows, heap)
    assert found is not None and found.rank == 4
    assert found.per_unit[1] == pytest.approx(80.0, abs=8.0)
    assert max(abs(v) for j, v in enumerate(found.per_unit) if j != 1) < 8.0
    late = np.asarray(rows)[20:]
    assert found.totals[1] == pytest.approx(found.per_unit[1] * (late[-1, 1] - late[0, 1]))


def test_two_leaking_functions_are_told_apart():
    rows, heap = _rotated(40, {0: 200.0, 3: 64.0}, noise_pages=False)
    found = attribute(rows, heap)
    assert found is not None
    assert found.per_unit == pytest.approx((200.0, 0.0, 0.0, 64.0), abs=1e-6)


def test_a_function_never_called_in_the_second_half_explains_nothing():
    """A column that does not change over the second half cannot be fitted: its share is 0."""
    rows, heap = _rotated(40, {1: 80.0}, noise_pages=False)
    rows = [r + [5.0] for r in rows]
    found = attribute(rows, heap)
    assert found is not None and found.per_unit[4] == 0.0 and found.rank == 4
    assert found.per_unit[1] == pytest.approx(80.0, abs=1e-6)


def test_too_few_samples_for_the_functions_give_no_attribution():
    rows, heap = _rotated(MIN_SAMPLES - 1, {1: 80.0})
    assert attribute(rows, heap) is None
    rows, heap = _rotated(10, {1: 80.0}, columns=5)   # 5 late samples, 5 columns
    assert attribute(rows, heap) is None
    rows, heap = _rotated(14, {1: 80.0}, columns=5)   # 7 late samples: enough
    assert attribute(rows, heap) is not None
