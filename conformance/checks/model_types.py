"""Static checks: declared types, units and display units resolve (DAE530-DAE532).

A variable's ``declaredType`` names an element of ``<TypeDefinitions>``; a ``unit`` (on a
variable or a type definition) names a ``<Unit>`` of ``<UnitDefinitions>``; a ``displayUnit`` (on
a variable, an ``<Alias>`` or a type definition) names a ``<DisplayUnit>`` of the unit in effect,
and needs a unit to be in effect (FMI 3.0.2 §2.4.3, §2.4.4, §2.4.7.5; digest MD-05, MV-02).

The unit in effect for a variable is its own ``unit``, else the ``unit`` of its declared type.
Each fault is reported once, where it is written: an undefined unit on a type definition at the
type, not again at every variable of that type; a display unit is not checked against a unit
that is itself undefined, nor against the unit of a type that is itself undefined.

Cost: the definitions are a few dozen elements; the variables are scanned once, and only those
that carry one of the three attributes (usually none, or a few) are looked at again.
"""
from __future__ import annotations

from collections.abc import Iterator

from .context import Check, CheckContext
from ..model.definitions import TypeDefinition, UnitDefinition
from ..report.findings import Location, Violation, evidence
from ..model.description import ModelDescription, Variable
from .model_analysis import analyse, var_loc

_SHOWN = 8  # defined names listed in the evidence
_ON_VARIABLE = "{subject}"
_ON_ALIAS = "the alias {subject}"
_ON_TYPE = "the type definition {subject}"


def _typed(ctx: CheckContext) -> list[Variable]:
    """The variables with a declaredType, unit, displayUnit or alias displayUnit (memoised)."""
    def compute() -> list[Variable]:
        assert ctx.model is not None
        if not any(d.declared_type is not None or d.unit is not None
                   or d.display_unit is not None or d.alias_display_units
                   for d in analyse(ctx.model).details):
            return []  # the usual case: decided from the model's few distinct details
        return [v for v in ctx.model.variables
                if v.declared_type is not None or v.unit is not None
                or v.display_unit is not None or v.alias_display_units]
    return ctx.memo("model_types.typed", compute)


def _types(model: ModelDescription) -> dict[str, TypeDefinition]:
    found: dict[str, TypeDefinition] = {}
    for t in model.definitions.types:
        found.setdefault(t.name, t)
    return found


def _units(model: ModelDescription) -> dict[str, UnitDefinition]:
    found: dict[str, UnitDefinition] = {}
    for u in model.definitions.units:
        found.setdefault(u.name, u)
    return found


def _type_loc(model: ModelDescription, t: TypeDefinition) -> Location:
    return Location(file=model.file, line=t.line, path=t.path)


def declared_type_undefined(ctx: CheckContext) -> Iterator[Violation]:
    """DAE530 MD-05: every declaredType names a type of <TypeDefinitions>."""
    if (model := ctx.model) is None:
        return
    types = _types(model)
    for var in _typed(ctx):
        if var.declared_type is None or var.declared_type in types:
            continue
        yield Violation(
            "declaredType naming no element of <TypeDefinitions>, on {subject}; define the type "
            "(e.g. <Float64Type name=\"...\"/>) or correct the name",
            var_loc(model, var),
            evidence(declared_type=var.declared_type, type=var.type,
                     defined_types=sorted(types)[:_SHOWN], value_reference=var.vr),
            subject=var.name)


def unit_undefined(ctx: CheckContext) -> Iterator[Violation]:
    """DAE531 MD-05: every unit (of a variable or a type) names a <Unit> of <UnitDefinitions>."""
    if (model := ctx.model) is None:
        return
    units = _units(model)
    message = ("unit naming no <Unit> of <UnitDefinitions>, on {where}; define "
               "<Unit name=\"...\"> under <UnitDefinitions> or correct the name")
    for t in model.definitions.types:
        if t.unit is not None and t.unit not in units:
            yield Violation(message.format(where=_ON_TYPE), _type_loc(model, t),
                            evidence(unit=t.unit, type_definition=t.name,
                                     defined_units=sorted(units)[:_SHOWN]),
                            subject=t.name, part="type-definition-unit")
    for var in _typed(ctx):
        if var.unit is not None and var.unit not in units:
            yield Violation(message.format(where=_ON_VARIABLE), var_loc(model, var),
                            evidence(unit=var.unit, defined_units=sorted(units)[:_SHOWN],
                                     value_reference=var.vr),
                            subject=var.name)


def display_unit_undefined(ctx: CheckContext) -> Iterator[Violation]:
    """DAE532 MD-05, MV-02: a displayUnit needs a unit in effect and names one of its
    <DisplayUnit> elements (on type definitions, variables and aliases)."""
    if (model := ctx.model) is None:
        return
    units, types = _units(model), _types(model)
    for t in model.definitions.types:
        if t.display_unit is not None:
            yield from _display_unit(model, units, t.display_unit, t.unit, t.name, _ON_TYPE,
                                     _type_loc(model, t), evidence(type_definition=t.name),
                                     part="type-definition")
    for var in _typed(ctx):
        if var.display_unit is None and not var.alias_display_units:
            continue
        unit, unit_from = var.unit, "variable"
        if unit is None and var.declared_type is not None:
            declared = types.get(var.declared_type)
            if declared is None:
                continue  # declared-type-undefined: the unit in effect cannot be known
            unit, unit_from = declared.unit, f"type {declared.name}"
        shown = [(var.name, var.display_unit, False)] if var.display_unit is not None else []
        shown.extend((alias, display, True) for alias, display in var.alias_display_units)
        for name, display, is_alias in shown:
            yield from _display_unit(
                model, units, display, unit, name, _ON_ALIAS if is_alias else _ON_VARIABLE,
                var_loc(model, var),
                evidence(alias=is_alias, variable=var.name, unit_from=unit_from,
                         value_reference=var.vr),
                part="alias" if is_alias else None)


def _display_unit(model: ModelDescription, units: dict[str, UnitDefinition], display: str,
                  unit: str | None, subject: str, where: str, location: Location,
                  context: tuple, part: str | None) -> Iterator[Violation]:
    """``part``: the catalogue part of a display unit its unit lacks ("type-definition",
    "alias", or None for a variable's); without a unit it is "no-unit", an alias's "alias"."""
    if unit is None:
        yield Violation(
            f"displayUnit without a unit, on {where}; a display unit converts from a unit, so "
            "add the unit attribute (or remove displayUnit)",
            location, evidence(dict(context), display_unit=display), subject=subject,
            part="no-unit" if part != "alias" else part)
        return
    definition = units.get(unit)
    if definition is None or display in definition.display_units:
        return  # an undefined unit is unit-undefined's
    yield Violation(
        f"displayUnit naming no <DisplayUnit> of its unit, on {where}; add <DisplayUnit "
        "name=\"...\"> to that <Unit> or correct the name",
        location,
        evidence(dict(context), display_unit=display, unit=unit,
                 defined_display_units=list(definition.display_units[:_SHOWN])),
        subject=subject, part=part)


CHECKS: dict[str, Check] = {
    "DAE530": declared_type_undefined,
    "DAE531": unit_undefined,
    "DAE532": display_unit_undefined,
}
