"""conformance/model/attributes.py: the faults of a Float variable's start, nominal, min and max,
and the values a probe may use instead (exact problems, exact fallbacks)."""
from __future__ import annotations

import math

import pytest

from conformance.model.attributes import (
    MIN_ABOVE_MAX,
    NOMINAL_NOT_POSITIVE,
    NOT_FINITE,
    Problem,
    attribute_problems,
    declared_nominal,
    start_flagged,
    usable_bounds,
    usable_nominal,
    usable_start,
)

INF = math.inf


def test_rule_names_are_the_catalogue_names():
    assert (NOT_FINITE, NOMINAL_NOT_POSITIVE, MIN_ABOVE_MAX) == (
        "float-attribute-not-finite", "nominal-not-positive", "min-greater-than-max")


@pytest.mark.parametrize("start, nominal, minimum, maximum, expected", [
    ("1", "2", "0", "3", []),
    (None, None, None, None, []),
    ("x", "y", "z", "w", []),                                   # not numbers: the schema's
    ("0 INF 1", None, None, None, [Problem(NOT_FINITE, "start", "0 INF 1")]),
    ("NaN NaN", None, None, None, [Problem(NOT_FINITE, "start", "NaN NaN")]),   # once
    (None, "INF", None, None, [Problem(NOT_FINITE, "nominal", "INF")]),
    (None, "0", None, None, [Problem(NOMINAL_NOT_POSITIVE, "nominal", "0")]),
    (None, "-2", None, None, [Problem(NOMINAL_NOT_POSITIVE, "nominal", "-2")]),
    (None, "0.5", None, None, []),
    (None, None, "INF", None, [Problem(NOT_FINITE, "min", "INF")]),
    (None, None, "NaN", None, [Problem(NOT_FINITE, "min", "NaN")]),
    (None, None, "-INF", "INF", []),                            # no bound either side
    (None, None, None, "-INF", [Problem(NOT_FINITE, "max", "-INF")]),
    (None, None, None, "NaN", [Problem(NOT_FINITE, "max", "NaN")]),
    (None, None, "3", "2", [Problem(MIN_ABOVE_MAX, "min", "3 > 2")]),
    (None, None, "2", "2", []),                                 # equal bounds are fine
    (None, None, "INF", "-INF", [Problem(NOT_FINITE, "min", "INF"),
                                 Problem(NOT_FINITE, "max", "-INF")]),   # not also min > max
    ("INF", "-1", "3", "1", [Problem(NOT_FINITE, "start", "INF"),
                             Problem(NOMINAL_NOT_POSITIVE, "nominal", "-1"),
                             Problem(MIN_ABOVE_MAX, "min", "3 > 1")]),
])
def test_attribute_problems_exact(start, nominal, minimum, maximum, expected):
    assert list(attribute_problems(start, nominal, minimum, maximum)) == expected


@pytest.mark.parametrize("nominal, declared, usable", [
    ("2", 2.0, 2.0), ("0.5", 0.5, 0.5), ("1e-9", 1e-9, 1e-9),
    ("0", None, 1.0), ("-3", None, 1.0), ("INF", None, 1.0), ("NaN", None, 1.0),
    ("x", None, 1.0), (None, None, 1.0),
])
def test_declared_and_usable_nominal(nominal, declared, usable):
    assert declared_nominal(nominal) == declared
    assert usable_nominal(nominal) == usable


@pytest.mark.parametrize("minimum, maximum, bounds", [
    ("1", "2", (1.0, 2.0)),
    ("2", "2", (2.0, 2.0)),
    (None, "2", (-INF, 2.0)),
    ("-1", None, (-1.0, INF)),
    (None, None, (-INF, INF)),
    ("-INF", "INF", (-INF, INF)),
    ("INF", "5", (-INF, 5.0)),          # a flagged min is left out, the max kept
    ("-5", "-INF", (-5.0, INF)),        # a flagged max is left out, the min kept
    ("NaN", "NaN", (-INF, INF)),
    ("3", "2", (-INF, INF)),            # min > max: both left out
])
def test_usable_bounds(minimum, maximum, bounds):
    assert usable_bounds(minimum, maximum) == bounds


@pytest.mark.parametrize("start, value", [
    ("2.5", 2.5), ("1 2 3", 1.0), ("INF 1", 7.0), ("NaN", 7.0), ("x", 7.0), ("", 7.0),
    (None, 7.0), ("-0.5", -0.5),
])
def test_usable_start(start, value):
    assert usable_start(start, 7.0) == value


@pytest.mark.parametrize("start, flagged", [
    ("1", False), (None, False), ("x", False), ("1 -INF", True), ("NaN", True),
])
def test_start_flagged(start, flagged):
    assert start_flagged(start) is flagged
