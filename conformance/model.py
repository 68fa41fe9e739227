"""The parsed modelDescription.xml as frozen dataclasses, with source lines.

Parsing is lenient: whatever the XSD says about a document, we build as much of the model as we
can, so the semantic rules still run and report. Values that are missing or malformed become
``None`` (the schema stage reports them). Defaults from the FMI 3.0 prose (MV-11, MV-20) are
applied here once, so every check sees the effective causality, variability and initial.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator, Mapping

from lxml import etree

MODEL_DESCRIPTION = "modelDescription.xml"

FLOAT_TYPES = frozenset({"Float32", "Float64"})
VARIABLE_TYPES = frozenset({
    "Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64",
    "UInt64", "Boolean", "String", "Binary", "Enumeration", "Clock",
})
STRUCTURE_KINDS = ("Output", "ContinuousStateDerivative", "ClockedState", "InitialUnknown",
                   "EventIndicator")


@dataclass(frozen=True, slots=True)
class Dimension:
    start: str | None
    vr: int | None
    line: int | None


@dataclass(frozen=True, slots=True)
class Variable:
    """One variable of ``<ModelVariables>`` with FMI defaults applied."""

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
    dimensions: tuple[Dimension, ...] = ()
    nominal: str | None = None
    minimum: str | None = None
    maximum: str | None = None
    description: str | None = None
    reinit: bool = False
    clocks: str | None = None
    previous: int | None = None
    raw_vr: str | None = None     # the attribute text, when it did not parse as an integer
    aliases: tuple[str, ...] = ()  # names of <Alias> children

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
class Unknown:
    """An element of a ModelStructure (core or manifest): Output, Residual, ..."""

    kind: str
    vr: int | None
    dependencies: tuple[int, ...] | None      # None: attribute absent ("depends on all")
    dependencies_kind: tuple[str, ...] | None
    line: int | None
    file: str
    path: str
    bad_tokens: tuple[str, ...] = ()          # dependency tokens that are not integers
    index: str | None = None                  # legacy `index` attribute
    formulations: int = 0                     # legacy: number of <Formulation> children


@dataclass(frozen=True, slots=True)
class ModelExchange:
    model_identifier: str | None
    attributes: tuple[tuple[str, str], ...]
    line: int | None

    def flag(self, name: str) -> bool:
        return dict(self.attributes).get(name, "false").strip() in ("true", "1")


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
    by_vr: Mapping[int, Variable] = field(default_factory=dict, init=False, repr=False,
                                          compare=False, hash=False)

    def __post_init__(self) -> None:
        index: dict[int, Variable] = {}
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


def parse_uint(text: str | None) -> int | None:
    if text is None:
        return None
    text = text.strip()
    return int(text) if text.isdigit() else None


def parse_unknown(el: etree._Element, kind: str, file: str, path: str,
                  attrs: Mapping[str, str] | None = None) -> Unknown:
    """Read valueReference / dependencies / dependenciesKind of a structure element."""
    a = el.attrib if attrs is None else attrs
    deps_text = a.get("dependencies")
    deps: tuple[int, ...] | None = None
    bad: list[str] = []
    if deps_text is not None:
        values = []
        for token in deps_text.split():
            if token.isdigit():
                values.append(int(token))
            else:
                bad.append(token)
        deps = tuple(values)
    kinds_text = a.get("dependenciesKind")
    kinds = tuple(kinds_text.split()) if kinds_text is not None else None
    return Unknown(kind=kind, vr=parse_uint(a.get("valueReference")), dependencies=deps,
                   dependencies_kind=kinds, line=el.sourceline, file=file, path=path,
                   bad_tokens=tuple(bad), index=a.get("index"))


def _variable(el: etree._Element) -> Variable | None:
    type_ = etree.QName(el).localname if isinstance(el.tag, str) else ""
    if type_ not in VARIABLE_TYPES:
        return None
    a = el.attrib
    causality = a.get("causality", "local")
    declared_var = a.get("variability")
    variability = declared_var or default_variability(type_, causality)
    declared_init = a.get("initial")
    start = a.get("start")
    dims = []
    aliases = []
    for child in el:
        if not isinstance(child.tag, str):
            continue
        tag = etree.QName(child).localname
        if tag == "Start" and start is None:
            start = " ".join(c.get("value", "") for c in el if isinstance(c.tag, str)
                             and etree.QName(c).localname == "Start")
        elif tag == "Alias":
            aliases.append(child.get("name", ""))
        elif tag == "Dimension":
            dims.append(Dimension(child.get("start"), parse_uint(child.get("valueReference")),
                                  child.sourceline))
    raw_vr = a.get("valueReference")
    vr = parse_uint(raw_vr)
    return Variable(
        name=a.get("name", ""), vr=vr, type=type_, causality=causality,
        variability=variability,
        initial=declared_init or default_initial(causality, variability),
        declared_variability=declared_var, declared_initial=declared_init, start=start,
        derivative=parse_uint(a.get("derivative")), line=el.sourceline,
        dimensions=tuple(dims), nominal=a.get("nominal"), minimum=a.get("min"),
        maximum=a.get("max"), description=a.get("description"),
        reinit=a.get("reinit", "false") in ("true", "1"), clocks=a.get("clocks"),
        previous=parse_uint(a.get("previous")),
        raw_vr=raw_vr if vr is None else None, aliases=tuple(aliases),
    )


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
    variables = []
    mv = _first(root, "ModelVariables")
    for el in (mv if mv is not None else ()):
        var = _variable(el)
        if var is not None:
            variables.append(var)
    structure = []
    ms = _first(root, "ModelStructure")
    if ms is not None:
        counters: dict[str, int] = {}
        for el in ms:
            if not isinstance(el.tag, str):
                continue
            kind = etree.QName(el).localname
            counters[kind] = counters.get(kind, 0) + 1
            path = f"/fmiModelDescription/ModelStructure/{kind}[{counters[kind]}]"
            structure.append(parse_unknown(el, kind, file, path))
    return ModelDescription(
        file=file, fmi_version=root.get("fmiVersion"), model_name=root.get("modelName"),
        instantiation_token=root.get("instantiationToken"),
        naming_convention=root.get("variableNamingConvention", "flat"),
        model_exchange=me, variables=tuple(variables), structure=tuple(structure),
        line=root.sourceline, has_co_simulation=_first(root, "CoSimulation") is not None,
    )
