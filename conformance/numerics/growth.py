"""Sustained growth of a quantity sampled along a run: resident memory against FMI calls.

A leak grows the resident set by about the same amount on every call, for as long as the run
lasts. Everything else that moves it is bounded: the allocator takes memory in steps (a page, an
arena, a top-up of the heap), and caches and warm-up allocations grow early and then stop. So
the growth is measured where a bounded effect has settled and a leak has not:

* only the second half of the samples counts (warm-up is over);
* its least-squares slope, in units of y per unit of x, and the growth that slope makes across
  the second half are both reported, so the rule can require a rate and a total;
* the third and fourth quarters are fitted on their own as well, each with the growth its slope
  makes across it: a single step of the allocator lands in one of them, a leak raises both. In a
  short run (a large model's path makes a few hundred calls) the quarter without the step still
  creeps by a page now and then, which is a slope of tens of bytes per call but a growth of a
  few pages: the growth, not the slope alone, tells it from a leak.

Plain functions of arrays, like the rest of ``numerics``; the rule compares with its thresholds.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

MIN_SAMPLES = 8    # fewer samples than this in the run: no judgement


@dataclass(frozen=True)
class Growth:
    """The growth of y with x over the second half of a run.

    ``slope``: least-squares dy/dx over the second half; ``total``: ``slope`` times the span of
    x there; ``quarters``: the slopes of the third and of the fourth quarter, each fitted alone;
    ``quarter_totals``: each of those slopes times its quarter's span of x;
    ``rise``: the last y minus the first y of the second half; ``samples``: how many samples
    the second half holds.
    """

    slope: float
    total: float
    quarters: tuple[float, float]
    quarter_totals: tuple[float, float]
    rise: float
    samples: int

    @property
    def sustained_slope(self) -> float:
        """The smallest of the three slopes: what the run shows at least everywhere late."""
        return min(self.slope, *self.quarters)


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y on x (0 when x does not vary)."""
    dx = x - x.mean()
    denominator = float(dx @ dx)
    return float(dx @ (y - y.mean())) / denominator if denominator > 0 else 0.0


def growth(x: Sequence[float], y: Sequence[float]) -> Growth | None:
    """The growth of ``y`` with ``x`` (both of length n, x increasing), or None when there are
    fewer than ``MIN_SAMPLES`` samples."""
    xs = np.asarray(x, dtype=float)
    ys = np.asarray(y, dtype=float)
    n = min(len(xs), len(ys))
    if n < MIN_SAMPLES:
        return None
    xs, ys = xs[:n], ys[:n]
    half = n // 2
    late_x, late_y = xs[half:], ys[half:]
    quarter = half + (n - half) // 2
    slope = _slope(late_x, late_y)
    third, fourth = slice(half, quarter + 1), slice(quarter, n)
    quarters = (_slope(xs[third], ys[third]), _slope(xs[fourth], ys[fourth]))
    spans = (float(xs[quarter] - xs[half]), float(xs[-1] - xs[quarter]))
    return Growth(
        slope=slope, total=slope * float(late_x[-1] - late_x[0]), quarters=quarters,
        quarter_totals=(quarters[0] * spans[0], quarters[1] * spans[1]),
        rise=float(late_y[-1] - late_y[0]), samples=n - half)


@dataclass(frozen=True)
class Attribution:
    """The growth of y attributed to the columns of X (the calls of each FMI function) over the
    second half of a run: ``per_unit[j]``, the least-squares dy per unit of column j, and
    ``totals[j]``, that times column j's increase across the second half; ``rank``: the rank of
    the centred columns there (below their number, some could not be told apart)."""

    per_unit: tuple[float, ...]
    totals: tuple[float, ...]
    rank: int


def attribute(counts: Sequence[Sequence[float]], y: Sequence[float]) -> Attribution | None:
    """Least squares of ``y`` on the columns of ``counts`` (n samples by k columns, each
    non-decreasing) with an intercept, over the second half of the samples: how much of y's
    growth each column explains. None when the second half holds no more samples than
    columns (nothing could be told apart)."""
    xs = np.asarray(counts, dtype=float)
    ys = np.asarray(y, dtype=float)
    n = min(len(xs), len(ys))
    if n < MIN_SAMPLES or xs.ndim != 2:
        return None
    half = n // 2
    late_x, late_y = xs[half:n], ys[half:n]
    if late_x.shape[0] <= late_x.shape[1] + 1:
        return None
    dx = late_x - late_x.mean(axis=0)
    dy = late_y - late_y.mean()
    scale = np.abs(dx).max(axis=0)
    scale[scale == 0] = 1.0
    coef, _, rank, _ = np.linalg.lstsq(dx / scale, dy, rcond=None)
    per_unit = coef / scale
    span = late_x[-1] - late_x[0]
    return Attribution(tuple(float(v) for v in per_unit),
                       tuple(float(v) for v in per_unit * span), int(rank))
