"""Static checks: the core FMI 3.0 variable rules that DAE use depends on (DAE501-DAE509).

These run on every FMU that has a modelDescription, with or without a manifest: an fmi-ls-dae FMU
must first be a correct Model Exchange FMU (LS-04), and the DAE rules build on value references,
states and the ModelStructure being right. Every check is one linear pass over the variables and
the ModelStructure with dicts and sets, so a model with 100,000 variables costs milliseconds. The
core ModelStructure rules (DAE510-DAE514) are in :mod:`.core_structure`; both modules share the
one-pass analysis :func:`analyse` defined here.

Where a more basic rule explains a problem, the later rules stay quiet: an invalid
causality/variability pair silences the ``initial`` and ``start`` rules for that variable, the
independent variable is left to its own rule, and unresolved value references are reported only
by ``model-structure-unknown-vr``.
"""
from __future__ import annotations

import weakref
from typing import Iterator, Optional

from ..context import Check, CheckContext
from ..findings import Location, Violation, evidence
from ..model import FLOAT_TYPES, ModelDescription, Unknown, Variable

CAUSALITIES = frozenset({"structuralParameter", "parameter", "calculatedParameter", "input",
                         "output", "local", "independent"})
VARIABILITIES = frozenset({"constant", "fixed", "tunable", "discrete", "continuous"})
INITIALS = frozenset({"exact", "approx", "calculated"})

# MV-10: legal variabilities per causality (independent is MV-13, checked by its own rule).
_ALLOWED_VARIABILITY: dict[str, frozenset[str]] = {
    "structuralParameter": frozenset({"fixed", "tunable"}),
    "parameter": frozenset({"fixed", "tunable"}),
    "calculatedParameter": frozenset({"fixed", "tunable"}),
    "input": frozenset({"discrete", "continuous"}),
    "output": frozenset({"constant", "discrete", "continuous"}),
    "local": VARIABILITIES,
    "independent": frozenset({"continuous"}),
}

_NONE: frozenset[str] = frozenset()
_EXACT = frozenset({"exact"})
_CALC_APPROX = frozenset({"calculated", "approx"})


def _allowed_initial(causality: str, variability: str) -> frozenset[str]:
    """MV-20: the ``initial`` values FMI 3.0 allows for a causality/variability pair."""
    if variability == "constant":
        return _EXACT if causality in ("output", "local") else _NONE
    if variability in ("fixed", "tunable"):
        if causality in ("structuralParameter", "parameter"):
            return _EXACT
        return _CALC_APPROX if causality in ("calculatedParameter", "local") else _NONE
    if causality == "input":
        return _EXACT
    return INITIALS if causality in ("output", "local") else _NONE


def var_loc(model: ModelDescription, var: Variable) -> Location:
    """Where a variable is declared in modelDescription.xml."""
    return Location(file=model.file, line=var.line, path=var.path)


def unknown_loc(u: Unknown) -> Location:
    """Where a ModelStructure element is."""
    return Location(file=u.file, line=u.line, path=u.path)


def _variability_fault(type_: str, c: str, v: str, clocked: bool) -> str | None:
    """Why a causality/variability pair breaks MV-10/MV-12, or None.

    Values the schema does not know (a misspelt causality) are the schema stage's to report, and
    the independent variable is independent-variable-invalid's.
    """
    if c == "independent" or c not in CAUSALITIES or v not in VARIABILITIES:
        return None
    if type_ == "Clock":
        if c not in ("input", "output", "local"):
            return "clock-causality"
        return "clock-variability" if v != "discrete" else None
    if v not in _ALLOWED_VARIABILITY[c]:
        return "combination"
    if v == "continuous" and type_ not in FLOAT_TYPES:
        return "continuous-non-float"
    if clocked and v not in ("discrete", "tunable"):
        return "clocked"
    return None


# What the variable rules conclude about one variable: (variability fault, initial invalid,
# start problem). The start problem is ("missing", reason), ("not-allowed", "") or None.
Verdict = tuple[Optional[str], bool, Optional[tuple[str, str]]]
_CLEAN: Verdict = (None, False, None)


def _verdict(type_: str, c: str, v: str, declared_initial: str | None, initial: str | None,
             clocked: bool, has_start: bool) -> Verdict:
    """MV-10..12, MV-20, MV-21 for one combination of attributes, most basic fault first."""
    fault = _variability_fault(type_, c, v, clocked)
    if fault is not None:
        return (fault, False, None)
    if (type_ == "Clock" or c == "independent" or c not in CAUSALITIES
            or v not in VARIABILITIES or (initial is not None and initial not in INITIALS)):
        return _CLEAN
    if declared_initial is not None and declared_initial not in _allowed_initial(c, v):
        return (None, True, None)
    if not has_start:
        if initial in ("exact", "approx"):
            return (None, False, ("missing", f"initial={initial}"))
        if c in ("parameter", "input", "structuralParameter"):
            return (None, False, ("missing", f"causality={c}"))
        if v == "constant":
            return (None, False, ("missing", "variability=constant"))
    elif initial == "calculated":
        return (None, False, ("not-allowed", ""))
    return _CLEAN


class _Analysis:
    """One pass over a model shared by all rules of this module and of :mod:`.core_structure`.

    Variables are judged per attribute signature (type, causality, variability, initial, ...),
    which a model repeats thousands of times, so the per-variable cost is one dict lookup.
    """

    def __init__(self, model: ModelDescription):
        self.verdicts: list[tuple[Variable, Verdict]] = []
        self.independents: list[Variable] = []
        self.by_kind: dict[str, list[Unknown]] = {}
        self.derivatives: list[Variable] = []             # variables with a derivative attribute
        self.by_causality: dict[str, list[Variable]] = {"output": [], "calculatedParameter": []}
        self.clocked_vrs: set[int] = set()                # clocked variables and Clocks (MS-05 d)
        memo: dict[tuple, Verdict] = {}
        for var in model.variables:
            if var.derivative is not None:
                self.derivatives.append(var)
            if var.causality in self.by_causality:
                self.by_causality[var.causality].append(var)
            if (var.clocks is not None or var.type == "Clock") and var.vr is not None:
                self.clocked_vrs.add(var.vr)
            key = (var.type, var.causality, var.variability, var.declared_initial, var.initial,
                   var.clocks is not None, var.start is not None)
            verdict = memo.get(key)
            if verdict is None:
                verdict = memo[key] = _verdict(*key)
            if verdict is not _CLEAN:
                self.verdicts.append((var, verdict))
            if var.causality == "independent":
                self.independents.append(var)
        for u in model.structure:
            self.by_kind.setdefault(u.kind, []).append(u)

    def unknowns(self, kind: str) -> list[Unknown]:
        return self.by_kind.get(kind, [])


_last: tuple[weakref.ref, _Analysis] | None = None


def analyse(model: ModelDescription) -> _Analysis:
    """The analysis of ``model``, computed once and reused while the same model is checked."""
    global _last
    cached = _last
    if cached is not None and cached[0]() is model:
        return cached[1]
    analysis = _Analysis(model)
    _last = (weakref.ref(model), analysis)
    return analysis


def model_exchange_missing(ctx: CheckContext) -> Iterator[Violation]:
    """DAE501 MD-02: fmi-ls-dae is defined for Model Exchange only."""
    if (model := ctx.model) is None or model.model_exchange is not None:
        return
    yield Violation(
        "modelDescription.xml has no <ModelExchange> element; fmi-ls-dae applies to Model "
        "Exchange FMUs only, so add <ModelExchange modelIdentifier=\"...\"/> and export the "
        "Model Exchange interface",
        Location(file=model.file, line=model.line, path="/fmiModelDescription"),
        evidence(model_name=model.model_name, has_co_simulation=model.has_co_simulation),
        subject=model.model_name)


def value_reference_duplicate(ctx: CheckContext) -> Iterator[Violation]:
    """DAE502 MV-01: no two variables share a valueReference."""
    if (model := ctx.model) is None:
        return
    with_vr = [var for var in model.variables if var.vr is not None]
    if len(with_vr) == len(model.by_vr):
        return  # the usual case: the index kept every variable
    first: dict[int, Variable] = {}
    for var in with_vr:
        owner = first.setdefault(var.vr, var)  # type: ignore[arg-type]
        if owner is not var:
            yield Violation(
                "valueReference already used by an earlier variable, reused by {subject}; give "
                "every variable its own valueReference (FMI 3.0 aliases are <Alias> children)",
                var_loc(model, var),
                evidence(value_reference=var.vr, first_variable=owner.name,
                         first_line=owner.line),
                subject=var.name)


def _alias_entries(var: Variable) -> Iterator[tuple[str, int | None]]:
    # Aliases are read by the model when it knows them; tolerate both names and objects.
    for alias in getattr(var, "aliases", ()) or ():
        name = alias if isinstance(alias, str) else getattr(alias, "name", None)
        if name:
            yield name, getattr(alias, "line", None) or var.line


def variable_name_duplicate(ctx: CheckContext) -> Iterator[Violation]:
    """DAE503 MV-02: variable names and alias names are unique across the whole model."""
    if (model := ctx.model) is None:
        return
    names = [var.name for var in model.variables]
    aliased = [var for var in model.variables if getattr(var, "aliases", None)]
    if not aliased and len(set(names)) == len(names):
        return  # the usual case
    seen: dict[str, str] = {}   # name -> the variable that first used it
    for var in model.variables:
        entries = [(var.name, var.line, False)] if var.name else []
        entries.extend((n, line, True) for n, line in _alias_entries(var))
        for name, line, is_alias in entries:
            owner = seen.get(name)
            if owner is None:
                seen[name] = var.name
                continue
            yield Violation(
                "name used by more than one variable or alias: {subject}; rename so that every "
                "variable and alias name is unique",
                Location(file=model.file, line=line, path=var.path),
                evidence(first_variable=owner, variable=var.name, alias=is_alias,
                         value_reference=var.vr),
                subject=name)


_VARIABILITY_MESSAGES = {
    "combination": "variability not allowed for the causality of {subject}; use a "
                   "combination from the FMI 3.0 causality/variability table",
    "continuous-non-float": "variability \"continuous\" on a variable that is not a "
                            "Float32/Float64: {subject}; only floats may be continuous, use "
                            "\"discrete\"",
    "clock-causality": "Clock with a causality other than input, output or local: {subject}; "
                       "give it one of those causalities",
    "clock-variability": "Clock with a variability other than discrete: {subject}; Clocks are "
                         "always discrete, remove the attribute",
    "clocked": "clocked variable neither discrete nor tunable: {subject}; a variable with a "
               "clocks attribute must be discrete or tunable",
}


def _enable_vrs(ctx: CheckContext) -> frozenset[int]:
    """Value references of the manifest's enable parameter(s): the enable rules (DAE2xx)
    explain their causality, variability and start better than the generic core rules."""
    if ctx.manifest is None or ctx.model is None:
        return frozenset()
    names = {v.name: v.vr for v in ctx.model.variables}
    vrs = {ref.vr if ref.vr is not None else names.get(ref.name or "")
           for ref in ctx.manifest.enables}
    return frozenset(vr for vr in vrs if vr is not None)


def causality_variability_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE504 MV-10, MV-11, MV-12: legal causality/variability pairs (defaults applied)."""
    if (model := ctx.model) is None:
        return
    enable = _enable_vrs(ctx)
    for var, (fault, _, _) in analyse(model).verdicts:
        if fault is None or var.vr in enable:
            continue
        yield Violation(
            _VARIABILITY_MESSAGES[fault], var_loc(model, var),
            evidence(fault=fault, type=var.type, causality=var.causality,
                     variability=var.variability,
                     variability_declared=var.declared_variability is not None,
                     allowed=sorted(_ALLOWED_VARIABILITY.get(var.causality, ()))),
            subject=var.name)


def initial_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE505 MV-20: a declared ``initial`` is allowed for the causality and variability."""
    if (model := ctx.model) is None:
        return
    for var, (_, initial_bad, _) in analyse(model).verdicts:
        if not initial_bad:
            continue
        allowed = sorted(_allowed_initial(var.causality, var.variability))
        yield Violation(
            "initial not allowed for the causality and variability of {subject}; use an "
            "allowed value (see the evidence) or remove the attribute",
            var_loc(model, var),
            evidence(initial=var.declared_initial, causality=var.causality,
                     variability=var.variability, allowed=allowed),
            subject=var.name)


def start_missing(ctx: CheckContext) -> Iterator[Violation]:
    """DAE506 MV-21: start is required for exact/approx, parameters, inputs and constants."""
    if (model := ctx.model) is None:
        return
    enable = _enable_vrs(ctx)
    for var, (_, _, problem) in analyse(model).verdicts:
        if problem is not None and problem[0] == "missing" and var.vr not in enable:
            yield Violation(
                "no start value for {subject}, which FMI 3.0 requires for inputs, parameters, "
                "constants and initial exact or approx; add a start value",
                var_loc(model, var),
                evidence(required_by=problem[1], causality=var.causality,
                         variability=var.variability, initial=var.initial),
                subject=var.name)


def start_not_allowed(ctx: CheckContext) -> Iterator[Violation]:
    """DAE507 MV-21: start is forbidden for initial=calculated."""
    if (model := ctx.model) is None:
        return
    for var, (_, _, problem) in analyse(model).verdicts:
        if problem is None or problem[0] != "not-allowed":
            continue
        yield Violation(
            "start value on {subject}, whose initial is \"calculated\"; remove the start "
            "value, or declare initial=\"approx\" if it is a guess value",
            var_loc(model, var),
            evidence(start=var.start, causality=var.causality, variability=var.variability,
                     initial_declared=var.declared_initial is not None),
            subject=var.name)


def independent_variable_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE508 MV-13: exactly one independent variable, a continuous float, no start/initial."""
    if (model := ctx.model) is None:
        return
    independents = analyse(model).independents
    if not independents:
        yield Violation(
            "modelDescription.xml has no variable with causality=\"independent\"; FMI 3.0 "
            "requires exactly one, add e.g. <Float64 name=\"time\" causality=\"independent\" "
            "variability=\"continuous\" .../>",
            Location(file=model.file, line=model.line, path="/fmiModelDescription/ModelVariables"),
            evidence(independent_variables=0))
        return
    first = independents[0]
    for var in independents[1:]:
        yield Violation(
            "causality=\"independent\" on {subject} besides the first independent variable; "
            "FMI 3.0 allows exactly one, make the others local",
            var_loc(model, var),
            evidence(first_independent=first.name, count=len(independents)),
            subject=var.name)
    problems = [text for text, bad in (
        (f"type {first.type}", not first.is_float),
        (f"variability {first.variability}", first.variability != "continuous"),
        ("start", first.start is not None), ("initial", first.declared_initial is not None),
    ) if bad]
    if problems:
        yield Violation(
            "independent variable {subject} must be a continuous Float32/Float64 without start "
            "or initial attributes; fix the attributes listed in the evidence",
            var_loc(model, first),
            evidence(problems=problems, type=first.type, variability=first.variability),
            subject=first.name)


def derivative_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE509 MV-30, MV-31: derivative targets exist and are floats, every
    ContinuousStateDerivative has one, and no state is listed twice."""
    if (model := ctx.model) is None:
        return
    by_vr = model.by_vr
    for var in analyse(model).derivatives:
        target = by_vr.get(var.derivative)  # type: ignore[arg-type]
        if target is None:
            yield Violation(
                "derivative attribute naming a valueReference that no variable has, on "
                "{subject}; point it at the variable this one is the derivative of",
                var_loc(model, var), evidence(derivative=var.derivative), subject=var.name)
        elif not target.is_float:
            yield Violation(
                "derivative attribute naming a variable that is not a Float32/Float64, on "
                "{subject}; derivatives can only be of floating-point variables",
                var_loc(model, var),
                evidence(derivative=var.derivative, target=target.name, target_type=target.type),
                subject=var.name)
    states: dict[int, tuple[Unknown, Variable]] = {}  # state vr -> first CSD naming it
    for u in analyse(model).unknowns("ContinuousStateDerivative"):
        der = by_vr.get(u.vr) if u.vr is not None else None
        if der is None:
            continue  # model-structure-unknown-vr
        if der.derivative is None:
            yield Violation(
                "<ContinuousStateDerivative> without a derivative attribute: {subject}; add "
                "derivative=\"<valueReference of its state>\"",
                var_loc(model, der),
                evidence(value_reference=der.vr, type=der.type, structure_line=u.line),
                subject=der.name)
            continue
        state = by_vr.get(der.derivative)
        if state is None or not state.is_float:
            continue  # reported above
        if der.variability != "continuous" or state.variability != "continuous":
            yield Violation(
                "<ContinuousStateDerivative> that is, or whose state is, not continuous: "
                "{subject}; states and their derivatives must be continuous floats",
                var_loc(model, der),
                evidence(derivative_variability=der.variability, state=state.name,
                         state_variability=state.variability),
                subject=der.name)
        if state.vr is None:
            continue
        earlier_u, earlier = states.setdefault(state.vr, (u, der))
        if earlier_u is not u:
            yield Violation(
                "<ContinuousStateDerivative> naming a state that an earlier one already "
                "names: {subject}; list every state exactly once",
                unknown_loc(u),
                evidence(state=state.name, earlier_derivative=earlier.name,
                         earlier_line=earlier_u.line, value_reference=der.vr),
                subject=der.name)


CHECKS: dict[str, Check] = {
    "DAE501": model_exchange_missing,
    "DAE502": value_reference_duplicate,
    "DAE503": variable_name_duplicate,
    "DAE504": causality_variability_invalid,
    "DAE505": initial_invalid,
    "DAE506": start_missing,
    "DAE507": start_not_allowed,
    "DAE508": independent_variable_invalid,
    "DAE509": derivative_invalid,
}
