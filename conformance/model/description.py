"""Reading modelDescription.xml into its parts (:mod:`conformance.model.parts`), with source lines.

Parsing is lenient: whatever the XSD says about a document, we build as much of the model as we
can, so the semantic rules still run and report. Values that are missing or malformed become
``None`` (the schema stage reports them). Defaults from the FMI 3.0 prose (MV-11, MV-20) are
applied here once, so every check sees the effective causality, variability and initial. The
ModelStructure elements are :class:`~conformance.model.unknowns.Unknown`, as in the manifest.
"""
from __future__ import annotations

from operator import itemgetter

from lxml import etree

from .definitions import read_definitions
from .parts import (  # noqa: F401  (the model's parts, read here, imported from here)
    FLOAT_TYPES, MODEL_DESCRIPTION, NO_DETAILS, STRUCTURE_KINDS, VARIABLE_TYPES,
    DefaultExperiment, Dimension, ModelDescription, ModelExchange, Variable, VariableDetails,
    default_initial, default_variability,
)
from .unknowns import parse_vr, path_template, read_structure
from .unknowns import Unknown  # noqa: F401 (re-exported with the model's parts)

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

# the attributes every variable is read for, in the order _variables unpacks them
_READ = ("causality", "variability", "initial", "name", "valueReference", "start", "derivative",
         "description")


def _shape(keys: list[str]) -> tuple[itemgetter, bool]:
    """How to read the attributes of a variable whose attribute names are ``keys``, in document
    order: a getter of the values of :data:`_READ` from ``el.values() + [None]`` (an absent
    attribute reads the trailing None), and whether it has attributes beyond them."""
    index = {key: i for i, key in enumerate(keys)}
    return itemgetter(*(index.get(name, -1) for name in _READ)), len(set(keys) - set(_READ)) > 0


def _variables(container: etree._Element | None) -> list[Variable]:
    """The variables of ``<ModelVariables>``, in document order.

    One loop without a call per variable but the attribute reads: a modelDescription may hold
    hundreds of thousands of variables (reports/bench/static.md). A variable's attributes are
    read in two calls (``keys()``, ``values()``) rather than one call per attribute; the
    variables of a document have few distinct attribute lists, each read through one getter.
    """
    out: list[Variable] = []
    append = out.append
    new = tuple.__new__  # skips the NamedTuple's Python-level __new__
    kinds: dict[_Kind, tuple[str, str, str | None, str | None, str, str | None]] = {}
    shapes: dict[tuple[str, ...], tuple[itemgetter, bool]] = {}
    shared: dict[VariableDetails, VariableDetails] = {}
    starts: dict[str, str] = {}   # "0", "1", "false"...: a start value is one string per document
    last_keys = None
    for el in (container if container is not None else ()):
        tag = el.tag
        if not isinstance(tag, str):
            continue
        type_ = tag if tag[0] != "{" else etree.QName(el).localname
        if type_ not in VARIABLE_TYPES:
            continue
        keys = el.keys()
        if keys != last_keys:
            found_shape = shapes.get(shape_key := tuple(keys))
            if found_shape is None:
                found_shape = shapes[shape_key] = _shape(keys)
            read, extra = found_shape
            last_keys = keys
        values = el.values()
        values.append(None)
        (causality, variability, initial, name, raw_vr, start, derivative,
         description) = read(values)
        key = (type_, causality, variability, initial)
        found = kinds.get(key)
        type_, causality, declared_var, declared_init, variability, initial = (
            found if found is not None else _effective(kinds, key))
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
        if extra or len(el) or raw_vr is not None:
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
        structure = read_structure(ms, file, path_template("/fmiModelDescription/ModelStructure"))
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


def _float(text: str | None) -> float | None:
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None
