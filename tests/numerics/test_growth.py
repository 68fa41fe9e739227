"""Sustained growth against allocator noise (conformance.numerics.growth)."""
from __future__ import annotations

import numpy as np

from conformance.numerics.growth import MIN_SAMPLES, growth

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
