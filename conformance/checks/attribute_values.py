"""Static checks: the numeric attributes of Float variables (DAE520-DAE522).

A NaN or infinite ``start`` or ``nominal``, an empty range (``min = INF``, ``max = -INF``, NaN),
a ``nominal`` of zero or below, and ``min > max`` are faults of the XML that importers inherit:
tolerances ``atol = nominal * rtol`` become zero or negative, start values poison the first
step. The reading is :mod:`conformance.model.attributes`, shared with the probes' layout, so that no
probe samples from (or blames the binary for) a value flagged here.
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from operator import attrgetter

from ..model.attributes import (
    MIN_ABOVE_MAX,
    NOMINAL_NOT_POSITIVE,
    NOT_FINITE,
    Problem,
    attribute_problems,
)
from .context import Check, CheckContext
from ..report.findings import Violation, evidence
from ..model.description import FLOAT_TYPES, ModelDescription, Variable, VariableDetails
from .model_analysis import analyse, var_loc

_ADVICE = {
    NOT_FINITE: "write a finite number (leave min or max out for no bound)",
    NOMINAL_NOT_POSITIVE: "give a positive nominal (the typical magnitude of the variable) or "
                          "leave it out (nominal 1)",
    MIN_ABOVE_MAX: "no value lies in the range: swap or correct the bounds",
}


def _problems(model: ModelDescription) -> dict[str, list[tuple[Variable, Problem]]]:
    """Every problem of every Float variable, by rule, in document order: one pass shared by
    the three rules."""
    floats = [var for var in model.variables if var.type in FLOAT_TYPES]
    if not _any_problem(floats, analyse(model).details):
        return {}
    found: dict[str, list[tuple[Variable, Problem]]] = {}
    for var in floats:
        if var.start is None and var.nominal is None and var.minimum is None \
                and var.maximum is None:
            continue
        for problem in attribute_problems(var.start, var.nominal, var.minimum, var.maximum):
            found.setdefault(problem.rule, []).append((var, problem))
    return found


def _any_problem(floats: list[Variable], details: Iterable[VariableDetails]) -> bool:
    """Whether a variable may have a problem, decided per distinct start, nominal and (min, max)
    text: a document repeats few, and the faults of each part are independent of the others'.
    Nominal, min and max come from the model's distinct details (of every variable, not only
    the floats: an extra suspect only costs the exact pass)."""
    starts = set(map(attrgetter("start"), floats))
    nominals = {d.nominal for d in details}
    ranges = {(d.minimum, d.maximum) for d in details}
    return (any(any(attribute_problems(start, None, None, None)) for start in starts)
            or any(any(attribute_problems(None, nominal, None, None)) for nominal in nominals)
            or any(any(attribute_problems(None, None, lo, hi)) for lo, hi in ranges))


def _violations(ctx: CheckContext, rule: str) -> Iterator[Violation]:
    if (model := ctx.model) is None:
        return
    found = ctx.memo("attribute-problems", lambda: _problems(model)).get(rule, ())
    # DAE521: a variable no derivative attribute names is no continuous state (it has no
    # fmi3GetNominalsOfContinuousStates value): part "not-a-state"
    states: set[int | None] = set()
    if found and rule == NOMINAL_NOT_POSITIVE:
        states.update(v.derivative for v in analyse(model).derivatives)
    for var, problem in found:
        shown = "min > max" if rule == MIN_ABOVE_MAX else problem.attribute
        yield Violation(
            f"{{subject}}: {shown} = {problem.text!r}; {_ADVICE[rule]}",
            var_loc(model, var),
            evidence(attribute=problem.attribute, value=problem.text, type=var.type),
            subject=var.name,
            part="not-a-state" if rule == NOMINAL_NOT_POSITIVE and var.vr not in states
            else None)


def float_attribute_not_finite(ctx: CheckContext) -> Iterator[Violation]:
    """DAE520: start, nominal, min and max of a Float variable are numbers."""
    return _violations(ctx, NOT_FINITE)


def nominal_not_positive(ctx: CheckContext) -> Iterator[Violation]:
    """DAE521: a nominal value is positive."""
    return _violations(ctx, NOMINAL_NOT_POSITIVE)


def min_greater_than_max(ctx: CheckContext) -> Iterator[Violation]:
    """DAE522: min <= max."""
    return _violations(ctx, MIN_ABOVE_MAX)


CHECKS: dict[str, Check] = {
    "DAE520": float_attribute_not_finite,
    "DAE521": nominal_not_positive,
    "DAE522": min_greater_than_max,
}
