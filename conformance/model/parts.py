"""The parts of a parsed modelDescription.xml: variables, the Model Exchange interface, the
DefaultExperiment and the :class:`ModelDescription` that holds them, with the FMI 3.0 defaults
of variability and initial (MV-11, MV-20). Immutable; :mod:`conformance.model.description` reads them from
the XML. A variable keeps its rarely set attributes in one shared :class:`VariableDetails`,
read through properties, so that 500k variables stay small.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from operator import attrgetter
from typing import Iterator, Mapping, NamedTuple

from .definitions import NO_DEFINITIONS, Definitions
from .unknowns import Unknown

MODEL_DESCRIPTION = "modelDescription.xml"

FLOAT_TYPES = frozenset({"Float32", "Float64"})
VARIABLE_TYPES = frozenset({
    "Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64",
    "UInt64", "Boolean", "String", "Binary", "Enumeration", "Clock",
})
STRUCTURE_KINDS = ("Output", "ContinuousStateDerivative", "ClockedState", "InitialUnknown",
                   "EventIndicator")


class Dimension(NamedTuple):
    start: str | None
    vr: int | None
    line: int | None
    raw_vr: str | None = None     # the attribute text, when it did not parse as a valueReference


class VariableDetails(NamedTuple):
    """The attributes and children of a variable that most variables do not have.

    Kept apart so that a variable without any holds one shared :data:`NO_DETAILS`, and
    variables with the same ones (unit, declaredType, min, max...) share one tuple: a field of
    :class:`Variable` costs 8 bytes per variable, 4 MB at 500k variables (issue 11).
    """

    dimensions: tuple[Dimension, ...] = ()
    nominal: str | None = None
    minimum: str | None = None
    maximum: str | None = None
    reinit: bool = False
    clocks: str | None = None
    previous: int | None = None
    raw_vr: str | None = None     # the attribute text, when it did not parse as an integer
    aliases: tuple[str, ...] = ()  # names of <Alias> children
    declared_type: str | None = None
    unit: str | None = None
    display_unit: str | None = None
    alias_display_units: tuple[tuple[str, str], ...] = ()  # (alias name, displayUnit) where given


NO_DETAILS = VariableDetails()


class Variable(NamedTuple):
    """One variable of ``<ModelVariables>`` with FMI defaults applied.

    Immutable like the rest of the model; a NamedTuple rather than a frozen dataclass because a
    modelDescription may hold 100,000 of them and construction cost matters (see reports/bench).
    The fields of :class:`VariableDetails` read as attributes of the variable too.
    """

    name: str
    vr: int | None
    type: str
    causality: str
    variability: str
    initial: str | None          # effective (default applied); None where not allowed
    declared_variability: str | None
    declared_initial: str | None
    start: str | None            # attribute, or <Start value> children joined by spaces
    derivative: int | None
    line: int | None
    description: str | None = None
    details: VariableDetails = NO_DETAILS

    dimensions = property(attrgetter("details.dimensions"))
    nominal = property(attrgetter("details.nominal"))
    minimum = property(attrgetter("details.minimum"))
    maximum = property(attrgetter("details.maximum"))
    reinit = property(attrgetter("details.reinit"))
    clocks = property(attrgetter("details.clocks"))
    previous = property(attrgetter("details.previous"))
    raw_vr = property(attrgetter("details.raw_vr"))
    aliases = property(attrgetter("details.aliases"))
    declared_type = property(attrgetter("details.declared_type"))
    unit = property(attrgetter("details.unit"))
    display_unit = property(attrgetter("details.display_unit"))
    alias_display_units = property(attrgetter("details.alias_display_units"))

    @property
    def is_float(self) -> bool:
        return self.type in FLOAT_TYPES

    @property
    def path(self) -> str:
        return f"/fmiModelDescription/ModelVariables/{self.type}[@name='{self.name}']"

    @property
    def label(self) -> str:
        return f"'{self.name}' (valueReference {self.vr})" if self.vr is not None else f"'{self.name}'"


@dataclass(frozen=True, slots=True)
class ModelExchange:
    model_identifier: str | None
    attributes: tuple[tuple[str, str], ...]
    line: int | None

    def flag(self, name: str) -> bool:
        return dict(self.attributes).get(name, "false").strip() in ("true", "1")


class DefaultExperiment(NamedTuple):
    """``<DefaultExperiment>``: the exporter's suggested run (None where absent or malformed)."""

    start_time: float | None = None
    stop_time: float | None = None
    tolerance: float | None = None
    step_size: float | None = None


@dataclass(frozen=True)
class ModelDescription:
    """The parts of modelDescription.xml the DAE rules need."""

    file: str
    fmi_version: str | None
    model_name: str | None
    instantiation_token: str | None
    naming_convention: str
    model_exchange: ModelExchange | None
    variables: tuple[Variable, ...]
    structure: tuple[Unknown, ...]
    line: int | None = None
    has_co_simulation: bool = False
    has_scheduled_execution: bool = False
    default_experiment: DefaultExperiment | None = None
    definitions: Definitions = NO_DEFINITIONS
    by_vr: Mapping[int, Variable] = field(default_factory=dict, init=False, repr=False,
                                          compare=False, hash=False)

    def __post_init__(self) -> None:
        vrs = list(map(attrgetter("vr"), self.variables))   # one pass at C speed
        index = dict(zip(vrs, self.variables))
        index.pop(None, None)
        if len(index) != len(vrs) - vrs.count(None):
            index = {}
            for var in self.variables:
                if var.vr is not None:
                    index.setdefault(var.vr, var)  # duplicates are a finding, the first one wins
        object.__setattr__(self, "by_vr", index)

    def unknowns(self, kind: str) -> Iterator[Unknown]:
        return (u for u in self.structure if u.kind == kind)

    def state_vrs(self) -> tuple[int, ...]:
        """Value references of the continuous states, in ContinuousStateDerivative order."""
        out = []
        for u in self.unknowns("ContinuousStateDerivative"):
            der = self.by_vr.get(u.vr) if u.vr is not None else None
            if der is not None and der.derivative is not None:
                out.append(der.derivative)
        return tuple(out)


def default_variability(type_: str, causality: str) -> str:
    """FMI 3.0 MV-11: the variability a variable has when the attribute is absent."""
    if type_ == "Clock":
        return "discrete"
    if causality in ("parameter", "structuralParameter", "calculatedParameter"):
        return "fixed"
    return "continuous" if type_ in FLOAT_TYPES else "discrete"


def default_initial(causality: str, variability: str) -> str | None:
    """FMI 3.0 MV-20: the default of ``initial`` (None where the attribute is not allowed)."""
    if causality == "independent":
        return None
    if variability == "constant":
        return "exact" if causality in ("output", "local") else None
    if variability in ("fixed", "tunable"):
        if causality in ("parameter", "structuralParameter"):
            return "exact"
        if causality in ("calculatedParameter", "local"):
            return "calculated"
        return None
    if causality == "input":
        return "exact"
    if causality in ("output", "local"):
        return "calculated"
    return None
