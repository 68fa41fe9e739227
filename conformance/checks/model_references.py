"""Static checks: lists and references in modelDescription.xml that must agree (DAE535-DAE537).

- the core ModelStructure's ``dependenciesKind`` has one entry per ``dependencies`` entry
  (MS-30; the manifest has its own rule, ``dependencies-kind-length``);
- a ``<Dimension>`` gives its size either by ``start`` or by the ``valueReference`` of a UInt64
  constant or structural parameter, and every initial size is positive (MV-41; such a variable
  without a start value is ``start-missing``'s);
- every entry of a ``clocks`` attribute names a Clock variable (MV-03, MV-51).

A ``<Dimension>`` that refers to the manifest's enable parameter is left to
``enable-parameter-not-scalar``, which says what to do about it. Tokens that are not unsigned
integers are the schema stage's to report. Each check is one pass over the structure or the
variables, looking again only at the few elements that carry the attribute.
"""
from __future__ import annotations

from collections.abc import Iterator
from operator import attrgetter
from typing import NamedTuple

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import Dimension, ModelDescription, Variable
from .model_analysis import analyse, enable_vrs, unknown_loc, var_loc


def _uint(text: str) -> int | None:
    """An unsigned integer token, or None: not digits, or longer than any UInt64 (which the
    schema stage reports; int() of thousands of digits would raise)."""
    text = text.strip()
    return int(text) if text.isascii() and text.isdigit() and len(text) <= 20 else None


def _is_zero(text: str) -> bool:
    text = text.strip()
    return bool(text) and set(text) == {"0"}


def _unknown_subject(model: ModelDescription, vr: int | None, kind: str) -> str:
    var = model.by_vr.get(vr) if vr is not None else None
    return var.name if var is not None else f"{kind} valueReference={vr}"


def model_structure_dependencies_kind_length(ctx: CheckContext) -> Iterator[Violation]:
    """DAE535 MS-30: dependenciesKind only with dependencies, and with as many entries."""
    if (model := ctx.model) is None:
        return
    for u in model.structure:
        if u.dependencies_kind is None:
            continue
        subject = _unknown_subject(model, u.vr, u.kind)
        if u.dependencies is None:
            yield Violation(
                "dependenciesKind without dependencies, on the ModelStructure element of "
                "{subject}; list the dependencies the kinds describe, or remove dependenciesKind",
                unknown_loc(u), evidence(kind=u.kind, kinds=len(u.dependencies_kind)),
                subject=subject)
            continue
        n_deps = len(u.dependencies) + len(u.bad_tokens)
        if n_deps != len(u.dependencies_kind):
            yield Violation(
                "dependenciesKind with a different number of entries than dependencies, on the "
                "ModelStructure element of {subject}; give exactly one kind per dependency",
                unknown_loc(u),
                evidence(kind=u.kind, dependencies=n_deps, kinds=len(u.dependencies_kind)),
                subject=subject)


class _Fault(NamedTuple):
    """A <Dimension> fault's message and catalogue part (None: the rule's own case)."""

    message: str
    part: str | None = None


_DIMENSION_FAULTS = {
    "both": _Fault("<Dimension> with both start and valueReference, in {subject}; give the size "
                   "one way: start for a constant size, valueReference for a size set by a "
                   "variable", part="both"),
    "neither": _Fault("<Dimension> with neither start nor valueReference, in {subject}; give "
                      "the size as start=\"n\" or as the valueReference of a UInt64 structural "
                      "parameter", part="neither"),
    "zero": _Fault("<Dimension> whose initial size is zero, in {subject}; initial array sizes "
                   "must be positive (set min=\"0\" on the structural parameter to let the "
                   "array vanish later)"),
    "unknown-vr": _Fault("<Dimension> valueReference naming no variable, in {subject}; point it "
                         "at a UInt64 structural parameter or constant", part="unknown-vr"),
    "target": _Fault("<Dimension> valueReference naming a variable that is not a UInt64 "
                     "constant or structural parameter, in {subject}; sizes come from UInt64 "
                     "structural parameters or constants", part="target"),
}


def _dimension_fault(model: ModelDescription, dim: Dimension, enable: frozenset[int]
                     ) -> tuple[str, Variable | None] | None:
    """Why a <Dimension> breaks MV-41 (and the variable it refers to), or None."""
    if dim.start is not None:
        if dim.vr is not None or dim.raw_vr is not None:
            return "both", None
        return ("zero", None) if _is_zero(dim.start) else None
    if dim.vr is None:
        # a valueReference that is no UInt32 is the schema stage's to report
        return ("neither", None) if dim.raw_vr is None else None
    target = model.by_vr.get(dim.vr)
    if target is None:
        return "unknown-vr", None
    if dim.vr in enable:
        return None  # enable-parameter-not-scalar
    if target.type != "UInt64" or not (target.variability == "constant"
                                       or target.causality == "structuralParameter"):
        return "target", target
    # Without a start value the size is unknown, but start-missing already reports that.
    return ("zero", target) if target.start is not None and _is_zero(target.start) else None


def dimension_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE536 MV-41: each <Dimension> gives a positive initial size, by start or by a UInt64
    constant or structural parameter."""
    if (model := ctx.model) is None or not analyse(model).has_arrays:
        return
    enable = enable_vrs(ctx)
    for var in filter(attrgetter("dimensions"), model.variables):
        for dim in var.dimensions:
            found = _dimension_fault(model, dim, enable)
            if found is None:
                continue
            fault, target = found
            message, part = _DIMENSION_FAULTS[fault]
            yield Violation(
                message,
                Location(file=model.file, line=dim.line or var.line, path=var.path),
                evidence(fault=fault, start=dim.start, dimension_value_reference=dim.vr,
                         target=target.name if target is not None else None,
                         target_type=target.type if target is not None else None,
                         target_causality=target.causality if target is not None else None,
                         target_variability=target.variability if target is not None else None,
                         target_start=target.start if target is not None else None),
                subject=var.name, part=part)


def clocks_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE537 MV-03, MV-51: every entry of ``clocks`` names a Clock variable."""
    if (model := ctx.model) is None or not any(d.clocks for d in analyse(model).details):
        return  # no variable has a clocks attribute: decided from the model's distinct details
    by_vr = model.by_vr
    for var in filter(attrgetter("clocks"), model.variables):
        for token in var.clocks.split():
            vr = _uint(token)
            if vr is None:
                continue  # the schema stage reports it
            target = by_vr.get(vr)
            if target is None:
                yield Violation(
                    "clocks entry naming no variable, on {subject}; list the value references "
                    "of the Clock variables this variable is clocked by",
                    var_loc(model, var), evidence(clock_value_reference=vr, clocks=var.clocks),
                    subject=var.name)
            elif target.type != "Clock":
                yield Violation(
                    "clocks entry naming a variable that is not a Clock, on {subject}; list "
                    "only the value references of <Clock> variables",
                    var_loc(model, var),
                    evidence(clock_value_reference=vr, target=target.name,
                             target_type=target.type, clocks=var.clocks),
                    subject=var.name)


CHECKS: dict[str, Check] = {
    "DAE535": model_structure_dependencies_kind_length,
    "DAE536": dimension_invalid,
    "DAE537": clocks_invalid,
}
