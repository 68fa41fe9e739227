"""Static checks: the core FMI 3.0 variable rules that DAE use depends on (DAE501-DAE509).

These run on every FMU that has a modelDescription, with or without a manifest: an fmi-ls-dae FMU
must first be a correct Model Exchange FMU (LS-04), and the DAE rules build on value references,
states and the ModelStructure being right. Every check is one linear pass over the variables and
the ModelStructure with dicts and sets, so a model with 100,000 variables costs milliseconds. The
core ModelStructure rules (DAE510-DAE514) are in :mod:`.model_structure`; both modules share the
one-pass analysis of :mod:`.model_analysis`.

Where a more basic rule explains a problem, the later rules stay quiet: an invalid
causality/variability pair silences the ``initial`` and ``start`` rules for that variable, the
independent variable is left to its own rule, and unresolved value references are reported only
by ``model-structure-unknown-vr``.
"""
from __future__ import annotations

from operator import attrgetter
from typing import Iterator, NamedTuple

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import FLOAT_TYPES, ModelDescription, Variable
from ..model.unknowns import Unknown
from .model_analysis import (
    ALLOWED_VARIABILITY,
    allowed_initial,
    analyse,
    derivatives_listed_well,
    enable_vrs,
    unknown_loc,
    var_loc,
)


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
    vrs = list(map(attrgetter("vr"), model.variables))
    if len(vrs) - vrs.count(None) == len(model.by_vr):
        return  # the usual case: the index kept every variable
    with_vr = [var for var in model.variables if var.vr is not None]
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
    if not any(map(attrgetter("aliases"), model.variables)) and len(set(names)) == len(names):
        return  # the usual case, decided in C
    seen: dict[str, tuple[str, bool]] = {}   # name -> the variable that first used it, by alias?
    for var in model.variables:
        entries = [(var.name, var.line, False)] if var.name else []
        entries.extend((n, line, True) for n, line in _alias_entries(var))
        for name, line, is_alias in entries:
            first = seen.get(name)
            if first is None:
                seen[name] = (var.name, is_alias)
                continue
            owner, first_alias = first
            yield Violation(
                "name used by more than one variable or alias: {subject}; rename so that every "
                "variable and alias name is unique",
                Location(file=model.file, line=line, path=var.path),
                evidence(first_variable=owner, variable=var.name, alias=is_alias,
                         value_reference=var.vr),
                subject=name, part="alias-name" if is_alias or first_alias else None)


class _Fault(NamedTuple):
    """A variability fault's message and catalogue part (None: the rule's own case)."""

    message: str
    part: str | None = None


_VARIABILITY_FAULTS = {
    "combination": _Fault("variability not allowed for the causality of {subject}; use a "
                          "combination from the FMI 3.0 causality/variability table"),
    "continuous-non-float": _Fault("variability \"continuous\" on a variable that is not a "
                                   "Float32/Float64: {subject}; only floats may be continuous, "
                                   "use \"discrete\"", part="continuous-non-float"),
    "clock-causality": _Fault("Clock with a causality other than input, output or local: "
                              "{subject}; give it one of those causalities",
                              part="clock-causality"),
    "clock-variability": _Fault("Clock with a variability other than discrete: {subject}; "
                                "Clocks are always discrete, remove the attribute",
                                part="clock-variability"),
    "clocked": _Fault("clocked variable neither discrete nor tunable: {subject}; a variable "
                      "with a clocks attribute must be discrete or tunable", part="clocked"),
}


def causality_variability_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE504 MV-10, MV-11, MV-12: legal causality/variability pairs (defaults applied)."""
    if (model := ctx.model) is None:
        return
    enable = enable_vrs(ctx)
    for var, (fault, _, _) in analyse(model).verdicts:
        if fault is None or var.vr in enable:
            continue
        message, part = _VARIABILITY_FAULTS[fault]
        yield Violation(
            message, var_loc(model, var),
            evidence(fault=fault, type=var.type, causality=var.causality,
                     variability=var.variability,
                     variability_declared=var.declared_variability is not None,
                     allowed=sorted(ALLOWED_VARIABILITY.get(var.causality, ()))),
            subject=var.name, part=part)


def initial_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE505 MV-20: a declared ``initial`` is allowed for the causality and variability."""
    if (model := ctx.model) is None:
        return
    for var, (_, initial_bad, _) in analyse(model).verdicts:
        if not initial_bad:
            continue
        allowed = sorted(allowed_initial(var.causality, var.variability))
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
    enable = enable_vrs(ctx)
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
    if not problems:
        return
    # One finding lists every problem; its part is the first that applies, the MUSTs (type or
    # start, initial) before the table of allowed pairs (variability).
    if not first.is_float or first.start is not None:
        yield _independent_attributes(model, first, problems, part="type-or-start")
    elif first.declared_initial is not None:
        yield _independent_attributes(model, first, problems, part="initial")
    else:
        yield _independent_attributes(model, first, problems, part="variability")


def _independent_attributes(model: ModelDescription, first: Variable, problems: list[str],
                            part: str) -> Violation:
    return Violation(
        "independent variable {subject} must be a continuous Float32/Float64 without start "
        "or initial attributes; fix the attributes listed in the evidence",
        var_loc(model, first),
        evidence(problems=problems, type=first.type, variability=first.variability),
        subject=first.name, part=part)


def derivative_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE509 MV-30, MV-31: derivative targets exist and are floats, every
    ContinuousStateDerivative has one, and no state is listed twice."""
    if (model := ctx.model) is None:
        return
    by_vr = model.by_vr
    derivatives = analyse(model).derivatives
    targets = list(map(by_vr.get, map(attrgetter("derivative"), derivatives)))
    if all(targets) and FLOAT_TYPES.issuperset(map(attrgetter("type"), targets)):
        derivatives = []  # the usual case: every target exists and is a float, decided in C
    listed: set[int | None] = set()   # the ContinuousStateDerivatives, when a target is wrong
    if derivatives:
        listed.update(map(attrgetter("vr"), analyse(model).unknowns("ContinuousStateDerivative")))
    for var, target in zip(derivatives, targets):
        if target is None:
            yield Violation(
                "derivative attribute naming a valueReference that no variable has, on "
                "{subject}; point it at the variable this one is the derivative of",
                var_loc(model, var), evidence(derivative=var.derivative), subject=var.name)
        elif target.is_float:
            continue
        elif (var.vr not in listed and var.causality in ("input", "output")
              and target.causality in ("input", "output")):
            # an input or output linked to the input or output it is the derivative of, not
            # listed as a state derivative: no state (FMI 3.0.2 §2.4.7.5)
            yield _target_not_float(model, var, target, part="target-not-float-io-link")
        else:
            yield _target_not_float(model, var, target, part="target-not-float")
    if derivatives_listed_well(model):
        return
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
                subject=der.name, part="csd-without-derivative")
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
                subject=der.name, part="not-continuous")
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
                subject=der.name, part="state-listed-twice")


def _target_not_float(model: ModelDescription, var: Variable, target: Variable,
                      part: str) -> Violation:
    return Violation(
        "derivative attribute naming a variable that is not a Float32/Float64, on "
        "{subject}; derivatives can only be of floating-point variables",
        var_loc(model, var),
        evidence(derivative=var.derivative, target=target.name, target_type=target.type),
        subject=var.name, part=part)


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
