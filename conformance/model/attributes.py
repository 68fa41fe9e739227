"""The numeric attributes of a Float variable: what is wrong with them, and what may be used.

One reading serves both stages, so that a probe never samples from a value the static stage
flags: :func:`attribute_problems` lists the faults (``float-attribute-not-finite``,
``nominal-not-positive``, ``min-greater-than-max``), and :func:`usable_nominal`,
:func:`usable_bounds` and :func:`usable_start` give the values a probe may scale by, stay within
and start from, leaving every flagged value out (nominal 1, no bound, start 0).

``min = -INF`` and ``max = INF`` mean "no bound" and are fine; ``min = INF``, ``max = -INF``,
NaN anywhere and an infinite ``start`` or ``nominal`` are not. Text that does not parse as a
number is the schema stage's finding, not these rules'.
"""
from __future__ import annotations

import math
from typing import Iterator, NamedTuple

NOT_FINITE = "float-attribute-not-finite"
NOMINAL_NOT_POSITIVE = "nominal-not-positive"
MIN_ABOVE_MAX = "min-greater-than-max"


class Problem(NamedTuple):
    """One fault of a variable's attributes: the rule name, the attribute and its text."""

    rule: str
    attribute: str
    text: str


def _number(text: str | None) -> float | None:
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def attribute_problems(start: str | None, nominal: str | None, minimum: str | None,
                       maximum: str | None) -> Iterator[Problem]:
    """The faults of a Float variable's ``start``, ``nominal``, ``min`` and ``max`` texts."""
    for part in (start.split() if start else ()):
        value = _number(part)
        if value is not None and not math.isfinite(value):
            yield Problem(NOT_FINITE, "start", start)  # type: ignore[arg-type]
            break
    nom = _number(nominal)
    if nom is not None and not math.isfinite(nom):
        yield Problem(NOT_FINITE, "nominal", nominal)  # type: ignore[arg-type]
    elif nom is not None and nom <= 0:
        yield Problem(NOMINAL_NOT_POSITIVE, "nominal", nominal)  # type: ignore[arg-type]
    lo, hi = _number(minimum), _number(maximum)
    if lo is not None and (math.isnan(lo) or lo == math.inf):
        yield Problem(NOT_FINITE, "min", minimum)  # type: ignore[arg-type]
        lo = None
    if hi is not None and (math.isnan(hi) or hi == -math.inf):
        yield Problem(NOT_FINITE, "max", maximum)  # type: ignore[arg-type]
        hi = None
    if lo is not None and hi is not None and lo > hi:
        yield Problem(MIN_ABOVE_MAX, "min", f"{minimum} > {maximum}")


def declared_nominal(nominal: str | None) -> float | None:
    """The declared nominal when it is a positive finite number, else None."""
    value = _number(nominal)
    return value if value is not None and math.isfinite(value) and value > 0 else None


def usable_nominal(nominal: str | None) -> float:
    """The nominal a probe may scale by: the declared one when positive and finite, else 1."""
    value = declared_nominal(nominal)
    return 1.0 if value is None else value


def usable_bounds(minimum: str | None, maximum: str | None) -> tuple[float, float]:
    """(min, max) a probe stays within; a flagged bound, or both when min > max, is left out."""
    lo, hi = _number(minimum), _number(maximum)
    lo = lo if lo is not None and not math.isnan(lo) and lo != math.inf else -math.inf
    hi = hi if hi is not None and not math.isnan(hi) and hi != -math.inf else math.inf
    return (lo, hi) if lo <= hi else (-math.inf, math.inf)


def usable_start(start: str | None, default: float) -> float:
    """The first start value when it is finite, else ``default``."""
    parts = start.split() if start else ()
    value = _number(parts[0]) if parts else None
    return value if value is not None and math.isfinite(value) else default


def start_flagged(start: str | None) -> bool:
    """Whether the static stage flags the start value (a probe must not blame the binary)."""
    return any(p.attribute == "start" for p in attribute_problems(start, None, None, None))
