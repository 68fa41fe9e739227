"""The parsed modelDescription.xml as frozen dataclasses, with source lines.

Parsing is lenient: whatever the XSD says about a document, we build as much of the model as we
can, so the semantic rules still run and report. Values that are missing or malformed become
``None`` (the schema stage reports them). Defaults from the FMI 3.0 prose (MV-11, MV-20) are
applied here once, so every check sees the effective causality, variability and initial. The
ModelStructure elements are :class:`~conformance.unknowns.Unknown`, as in the manifest.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from operator import attrgetter
from typing import Iterator, Mapping, NamedTuple

from lxml import etree

from .definitions import NO_DEFINITIONS, Definitions, read_definitions
from .unknowns import Unknown, parse_unknown, parse_vr, path_template

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


def _float(text: str | None) -> float | None:
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None


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
        index = {var.vr: var for var in self.variables if var.vr is not None}
        if len(index) != sum(var.vr is not None for var in self.variables):
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


# type, causality, variability, initial as written (None: attribute absent)
_Kind = tuple[str, str | None, str | None, str | None]


def _effective(kinds: dict[_Kind, tuple[str, str, str | None, str | None, str, str | None]],
               key: _Kind) -> tuple[str, str, str | None, str | None, str, str | None]:
    """The attributes that classify a variable (type, causality with its default, declared
    variability and initial) followed by its effective variability and initial, memoised in
    ``kinds``: a
    document holds few distinct classes, and its variables share these strings (lxml returns a
    fresh string for every attribute read)."""
    found = kinds.get(key)
    if found is None:
        type_, causality, declared_var, declared_init = key
        if causality is None:
            causality = "local"
        variability = declared_var or default_variability(type_, causality)
        found = kinds[key] = (type_, causality, declared_var, declared_init, variability,
                              declared_init or default_initial(causality, variability))
    return found


_SHARED_LIMIT = 4096   # distinct start values (and VariableDetails) shared per document


def _variables(container: etree._Element | None) -> list[Variable]:
    """The variables of ``<ModelVariables>``, in document order.

    One loop without a call per variable but the attribute reads: a modelDescription may hold
    hundreds of thousands of variables (reports/bench/static.md).
    """
    out: list[Variable] = []
    append = out.append
    new = tuple.__new__  # skips the NamedTuple's Python-level __new__
    kinds: dict[_Kind, tuple[str, str, str | None, str | None, str, str | None]] = {}
    shared: dict[VariableDetails, VariableDetails] = {}
    starts: dict[str, str] = {}   # "0", "1", "false"...: a start value is one string per document
    for el in (container if container is not None else ()):
        tag = el.tag
        if not isinstance(tag, str):
            continue
        type_ = tag if tag[0] != "{" else etree.QName(el).localname
        if type_ not in VARIABLE_TYPES:
            continue
        get = el.get
        key = (type_, get("causality"), get("variability"), get("initial"))
        found = kinds.get(key)
        type_, causality, declared_var, declared_init, variability, initial = (
            found if found is not None else _effective(kinds, key))
        basics = (get("name"), get("valueReference"), get("start"), get("derivative"),
                  get("description"))
        name, raw_vr, start, derivative, description = basics
        if start is not None:
            if (known := starts.get(start)) is not None:
                start = known
            elif len(starts) < _SHARED_LIMIT:
                starts[start] = start
        if raw_vr is not None and len(raw_vr) < 10 and raw_vr.isdigit() and raw_vr.isascii():
            vr: int | None = int(raw_vr)
            raw_vr = None
        else:
            vr = parse_vr(raw_vr)
            if vr is not None:
                raw_vr = None
        details = NO_DETAILS
        # attributes beyond the ones read above, or children: read the details (most have none)
        if len(el) or raw_vr is not None or (
                len(el.attrib) > 8 - key.count(None) - basics.count(None)):
            start, details = _details(el, start, raw_vr, shared)
        append(new(Variable, (
            "" if name is None else name, vr, type_, causality, variability, initial,
            declared_var, declared_init, start,
            parse_vr(derivative) if derivative is not None else None,
            el.sourceline, description, details,
        )))
    return out




def _details(el: etree._Element, start: str | None, raw_vr: str | None,
             shared: dict[VariableDetails, VariableDetails]
             ) -> tuple[str | None, VariableDetails]:
    """The start value (it may come from <Start> children) and the details of a variable;
    equal details are one tuple, shared through ``shared`` (one dict per document)."""
    get = el.get
    dims: tuple[Dimension, ...] = ()
    aliases: tuple[str, ...] = ()
    alias_units: tuple[tuple[str, str], ...] = ()
    if len(el):
        start, dims, aliases, alias_units = _children_of_variable(el, start)
    previous = get("previous")
    details = VariableDetails(
        dims, get("nominal"), get("min"), get("max"), get("reinit", "false") in ("true", "1"),
        get("clocks"), parse_vr(previous) if previous is not None else None, raw_vr, aliases,
        get("declaredType"), get("unit"), get("displayUnit"), alias_units)
    found = shared.get(details)
    if found is None:
        found = details if details != NO_DETAILS else NO_DETAILS
        if len(shared) < _SHARED_LIMIT:
            shared[details] = found
    return start, found


def _children_of_variable(el: etree._Element, start: str | None) -> tuple[
        str | None, tuple[Dimension, ...], tuple[str, ...], tuple[tuple[str, str], ...]]:
    """Read <Start>, <Alias> and <Dimension> children: the start value, the dimensions, the
    alias names and the (alias name, displayUnit) pairs."""
    starts: list[str] = []
    dims: list[Dimension] = []
    aliases: list[str] = []
    alias_units: list[tuple[str, str]] = []
    for child in el:
        if not isinstance(child.tag, str):
            continue
        tag = etree.QName(child).localname
        if tag == "Start":
            starts.append(child.get("value", ""))
        elif tag == "Alias":
            aliases.append(child.get("name", ""))
            if (shown := child.get("displayUnit")) is not None:
                alias_units.append((aliases[-1], shown))
        elif tag == "Dimension":
            raw = child.get("valueReference")
            vr = parse_vr(raw)
            dims.append(Dimension(child.get("start"), vr, child.sourceline,
                                  raw if vr is None else None))
    if starts and start is None:
        start = " ".join(starts)
    return start, tuple(dims), tuple(aliases), tuple(alias_units)


def _children(el: etree._Element | None, name: str) -> list[etree._Element]:
    if el is None:
        return []
    return [c for c in el if isinstance(c.tag, str) and etree.QName(c).localname == name]


def _first(el: etree._Element, name: str) -> etree._Element | None:
    found = _children(el, name)
    return found[0] if found else None


def read_model_description(tree: etree._ElementTree, *, file: str = MODEL_DESCRIPTION
                           ) -> ModelDescription:
    """Build a :class:`ModelDescription` from a parsed tree; never raises on odd content."""
    root = tree.getroot()
    me_el = _first(root, "ModelExchange")
    me = None
    if me_el is not None:
        me = ModelExchange(me_el.get("modelIdentifier"), tuple(sorted(me_el.attrib.items())),
                           me_el.sourceline)
    variables = _variables(_first(root, "ModelVariables"))
    structure = []
    ms = _first(root, "ModelStructure")
    if ms is not None:
        where = path_template("/fmiModelDescription/ModelStructure")
        counters: dict[str, list] = {}   # kind -> [the kind's shared string, elements so far]
        shared: dict[str, tuple[str, ...]] = {}
        for el in ms:
            tag = el.tag
            if not isinstance(tag, str):
                continue
            kind = tag if tag[0] != "{" else etree.QName(el).localname
            counter = counters.get(kind)
            if counter is None:
                counter = counters[kind] = [kind, 0]
            counter[1] += 1
            structure.append(parse_unknown(el, counter[0], file, where, counter[1],
                                           shared=shared))
    return ModelDescription(
        file=file, fmi_version=root.get("fmiVersion"), model_name=root.get("modelName"),
        instantiation_token=root.get("instantiationToken"),
        naming_convention=root.get("variableNamingConvention", "flat"),
        model_exchange=me, variables=tuple(variables), structure=tuple(structure),
        line=root.sourceline, has_co_simulation=_first(root, "CoSimulation") is not None,
        has_scheduled_execution=_first(root, "ScheduledExecution") is not None,
        default_experiment=_default_experiment(_first(root, "DefaultExperiment")),
        definitions=read_definitions(root),
    )


def _default_experiment(el: etree._Element | None) -> DefaultExperiment | None:
    if el is None:
        return None
    return DefaultExperiment(_float(el.get("startTime")), _float(el.get("stopTime")),
                             _float(el.get("tolerance")), _float(el.get("stepSize")))
