"""``<TypeDefinitions>`` and ``<UnitDefinitions>`` of modelDescription.xml, as named tuples.

Read once by :func:`conformance.model.description.read_model_description` into
:attr:`ModelDescription.definitions <conformance.model.description.ModelDescription.definitions>`; the rules
that resolve a variable's ``declaredType``, ``unit`` and ``displayUnit``
(:mod:`conformance.checks.model_types`) look names up here. Like the rest of the model, reading is
lenient: an element without a ``name`` is kept with the empty name, and what the XSD forbids is
the schema stage's to report.
"""
from __future__ import annotations

from typing import NamedTuple

from lxml import etree

#: The elements of ``<TypeDefinitions>`` (the variable type followed by ``Type``).
TYPE_ELEMENTS = frozenset({
    "Float32Type", "Float64Type", "Int8Type", "UInt8Type", "Int16Type", "UInt16Type", "Int32Type",
    "UInt32Type", "Int64Type", "UInt64Type", "BooleanType", "StringType", "BinaryType",
    "EnumerationType", "ClockType",
})


class TypeDefinition(NamedTuple):
    """One element of ``<TypeDefinitions>``."""

    name: str
    kind: str                    # the variable type it is for: "Float64", "Enumeration", ...
    unit: str | None
    display_unit: str | None
    line: int | None

    @property
    def path(self) -> str:
        return f"/fmiModelDescription/TypeDefinitions/{self.kind}Type[@name='{self.name}']"


class UnitDefinition(NamedTuple):
    """One ``<Unit>`` of ``<UnitDefinitions>`` with the names of its ``<DisplayUnit>`` children."""

    name: str
    display_units: tuple[str, ...]
    line: int | None

    @property
    def path(self) -> str:
        return f"/fmiModelDescription/UnitDefinitions/Unit[@name='{self.name}']"


class Definitions(NamedTuple):
    """The type and unit definitions of a model, in document order."""

    types: tuple[TypeDefinition, ...] = ()
    units: tuple[UnitDefinition, ...] = ()


NO_DEFINITIONS = Definitions()


def _local(el: etree._Element) -> str | None:
    tag = el.tag
    if not isinstance(tag, str):
        return None  # a comment or processing instruction
    return tag if tag[0] != "{" else etree.QName(el).localname


def read_definitions(root: etree._Element) -> Definitions:
    """Read the ``<TypeDefinitions>`` and ``<UnitDefinitions>`` children of ``root``."""
    types: list[TypeDefinition] = []
    units: list[UnitDefinition] = []
    for section in root:
        tag = _local(section)
        if tag == "TypeDefinitions":
            for el in section:
                kind = _local(el)
                if kind is not None and kind in TYPE_ELEMENTS:
                    types.append(TypeDefinition(el.get("name", ""), kind[:-4], el.get("unit"),
                                                el.get("displayUnit"), el.sourceline))
        elif tag == "UnitDefinitions":
            for el in section:
                if _local(el) == "Unit":
                    shown = tuple(d.get("name", "") for d in el if _local(d) == "DisplayUnit")
                    units.append(UnitDefinition(el.get("name", ""), shown, el.sourceline))
    return Definitions(tuple(types), tuple(units))
