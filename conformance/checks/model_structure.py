"""Static checks: the core FMI 3.0 ModelStructure rules that DAE use depends on (DAE510-DAE515).

The ModelStructure of modelDescription.xml must resolve (DAE510) and list exactly the outputs,
state derivatives and initial unknowns that the variables call for (DAE511-DAE513); a DAE FMU
is advised to provide directional derivatives (DAE514); an output that is itself a state and
leaves itself out of its dependencies meets an open question of FMI 3.0 (DAE515, information). Each check is one linear pass over the
ModelStructure, reusing the per-model analysis of :mod:`.model_analysis`. Unresolved value
references are reported only by ``model-structure-unknown-vr``; the other rules skip them.
"""
from __future__ import annotations

from collections.abc import Iterator
from functools import partial
from itertools import chain
from operator import attrgetter, is_not, itemgetter

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import ModelDescription, Variable
from ..model.unknowns import Unknown
from .model_analysis import analyse, unknown_loc, var_loc


def _unknown_subject(model: ModelDescription, u: Unknown) -> str:
    var = model.by_vr.get(u.vr) if u.vr is not None else None
    return var.name if var is not None else f"{u.kind} valueReference={u.vr}"


def model_structure_unknown_vr(ctx: CheckContext) -> Iterator[Violation]:
    """DAE510 MV-03: every valueReference and dependency in the core ModelStructure resolves."""
    if (model := ctx.model) is None:
        return
    by_vr = model.by_vr
    structure = model.structure
    if all(map(by_vr.__contains__, filter(_given, map(attrgetter("vr"), structure)))) and all(
            map(by_vr.__contains__, chain.from_iterable(filter(None, map(
                attrgetter("dependencies"), structure))))):
        return  # the usual case: everything resolves, decided in C
    for u in structure:
        if u.vr is not None and u.vr not in by_vr:
            yield Violation(
                "ModelStructure element naming a valueReference that no variable has: "
                "{subject}; list only existing variables",
                unknown_loc(u), evidence(kind=u.kind, value_reference=u.vr),
                subject=f"{u.kind} valueReference={u.vr}")
        missing = [d for d in (u.dependencies or ()) if d not in by_vr]
        if missing:
            yield Violation(
                "dependencies naming value references that no variable has, in the "
                "ModelStructure element of {subject}; list only existing variables",
                unknown_loc(u), evidence(kind=u.kind, missing=sorted(set(missing))),
                subject=_unknown_subject(model, u))


_given = partial(is_not, None)  # a value reference that is not None (a test in C)


def _listed(model: ModelDescription, kind: str) -> Iterator[tuple[Unknown, Variable]]:
    """Resolved elements of one ModelStructure kind (unresolved ones are DAE510's)."""
    by_vr = model.by_vr
    for u in analyse(model).unknowns(kind):
        var = by_vr.get(u.vr) if u.vr is not None else None
        if var is not None:
            yield u, var


def _set_mismatch(model: ModelDescription, kind: str, expected: dict[int, str],
                  allowed_extra: set[int], messages: tuple[str, str, str],
                  event_indicators: frozenset[int] = frozenset()) -> Iterator[Violation]:
    """Compare a ModelStructure list with the set it must equal; yield extra/duplicate/missing.

    A duplicate is the rules' part ``duplicate``; an extra entry that is one of
    ``event_indicators`` is the part ``event-indicator-listed`` (of InitialUnknown)."""
    not_member, duplicate, missing = messages
    unknowns = analyse(model).unknowns(kind)
    vrs = list(filter(model.by_vr.__contains__, map(attrgetter("vr"), unknowns)))
    listed = set(vrs)
    if (len(listed) == len(vrs) and listed.issuperset(expected)
            and listed.difference(expected) <= allowed_extra):
        return  # the usual case: each listed once, all expected, decided in C
    seen: set[int] = set()
    for u, var in _listed(model, kind):
        vr = var.vr
        if vr in seen:
            yield Violation(duplicate, unknown_loc(u), evidence(kind=kind, value_reference=vr),
                            subject=var.name, part="duplicate")
            continue
        seen.add(vr)  # type: ignore[arg-type]
        if vr not in expected and vr not in allowed_extra:
            yield Violation(not_member, unknown_loc(u),
                            evidence(kind=kind, value_reference=vr, causality=var.causality,
                                     variability=var.variability, initial=var.initial),
                            subject=var.name,
                            part="event-indicator-listed" if vr in event_indicators else None)
    for vr, reason in expected.items():
        if vr not in seen:
            var = model.by_vr[vr]
            yield Violation(missing, var_loc(model, var),
                            evidence(kind=kind, value_reference=vr, reason=reason),
                            subject=var.name)


def model_structure_output_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """DAE511 MS-02: the <Output> elements are exactly the outputs, each listed once."""
    if (model := ctx.model) is None:
        return
    expected = {v.vr: "causality=output" for v in analyse(model).by_causality["output"]
                if v.vr is not None and model.by_vr[v.vr] is v}
    yield from _set_mismatch(model, "Output", expected, set(), (
        "<Output> naming a variable whose causality is not \"output\": {subject}; list only "
        "outputs under <Output>",
        "<Output> listed twice: {subject}; list every output exactly once",
        "output missing from the <Output> list: {subject}; add "
        "<Output valueReference=\"...\"/> for every output",
    ))


def model_structure_derivative_missing(ctx: CheckContext) -> Iterator[Violation]:
    """DAE512 MS-03: every state derivative is listed as <ContinuousStateDerivative>.

    A variable counts as a state derivative when it and the variable its ``derivative`` names are
    continuous floats, local or output, and not both outputs (MV-30 allows linking an output to
    the output it is the derivative of without making either a state), and when no listed
    derivative already covers that state.

    Only Model Exchange must list them: a Co-Simulation or Scheduled Execution FMU may leave
    the list out (FMI 3.0 §2.4.8, InitialUnknown: "if a Co-Simulation FMU does not define the
    ContinuousStateDerivative elements, ...").
    """
    if (model := ctx.model) is None or model.model_exchange is None:
        return
    by_vr = model.by_vr
    listed: set[int] = set()
    covered: set[int] = set()   # states that a listed derivative already names
    for u, der in _listed(model, "ContinuousStateDerivative"):
        listed.add(u.vr)  # type: ignore[arg-type]
        if der.derivative is not None:
            covered.add(der.derivative)
    for var in analyse(model).derivatives:
        if var.vr in listed or var.derivative in covered:
            continue
        state = by_vr.get(var.derivative)  # type: ignore[arg-type]
        if state is None or not (var.is_float and state.is_float):
            continue
        if var.variability != "continuous" or state.variability != "continuous":
            continue
        causalities = (var.causality, state.causality)
        if not set(causalities) <= {"local", "output"} or causalities == ("output", "output"):
            continue
        covered.add(var.derivative)
        yield Violation(
            "state derivative not listed as <ContinuousStateDerivative>: {subject}; Model "
            "Exchange must list every state derivative in the ModelStructure",
            var_loc(model, var),
            evidence(value_reference=var.vr, state=state.name, state_value_reference=state.vr),
            subject=var.name)


_REASONS = {initial: (f"derivative with initial={initial}", f"state with initial={initial}")
            for initial in ("approx", "calculated")}


def model_structure_initial_unknown_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """DAE513 MS-05: InitialUnknown = (a) outputs, (b) calculatedParameters, (c) states/derivatives
    whose initial is approx or calculated; (d) clocked variables may be added."""
    if (model := ctx.model) is None:
        return
    by_vr = model.by_vr
    analysis = analyse(model)
    expected: dict[int, str] = {}
    for var in analysis.by_causality["output"]:
        if (var.vr is not None and by_vr[var.vr] is var and var.clocks is None
                and var.type != "Clock" and var.initial in ("approx", "calculated")):
            expected[var.vr] = f"output with initial={var.initial}"
    for var in analysis.by_causality["calculatedParameter"]:
        if var.vr is not None and by_vr[var.vr] is var:
            expected[var.vr] = "calculatedParameter"
    ders = list(map(itemgetter(1), _listed(model, "ContinuousStateDerivative")))
    for der, state in zip(ders, map(by_vr.get, map(attrgetter("derivative"), ders))):
        # by_vr.get(None) is None; the reasons are formatted once per (role, initial)
        if der.initial in _REASONS and der.vr is not None:
            expected.setdefault(der.vr, _REASONS[der.initial][0])
        if state is not None and state.initial in _REASONS and state.vr is not None:
            expected.setdefault(state.vr, _REASONS[state.initial][1])
    yield from _set_mismatch(model, "InitialUnknown", expected, analysis.clocked_vrs, (
        "<InitialUnknown> naming neither an output, calculated parameter, state or state "
        "derivative with initial approx or calculated, nor a clocked variable: {subject}; "
        "remove it",
        "<InitialUnknown> listed twice: {subject}; list every initial unknown exactly once",
        "missing from the <InitialUnknown> list: {subject}; outputs, calculated parameters, "
        "states and derivatives with initial approx or calculated must be listed, add it",
    ), frozenset(u.vr for u in analysis.unknowns("EventIndicator") if u.vr is not None))


def directional_derivatives_missing(ctx: CheckContext) -> Iterator[Violation]:
    """DAE514 CF-05, DAE-50: a DAE FMU should provide directional derivatives for dg/dw."""
    model = ctx.model
    if model is None or not ctx.dae_layer or model.model_exchange is None:
        return
    me = model.model_exchange
    if me.flag("providesDirectionalDerivatives"):
        return
    yield Violation(
        "the DAE FMU {subject} does not set providesDirectionalDerivatives=\"true\" on "
        "<ModelExchange>; importers must then approximate the residual Jacobian by finite "
        "differences, so implement fmi3GetDirectionalDerivative and set the flag",
        Location(file=model.file, line=me.line, path="/fmiModelDescription/ModelExchange"),
        evidence(model_identifier=me.model_identifier,
                 provides_adjoint_derivatives=me.flag("providesAdjointDerivatives")),
        subject=me.model_identifier)


def output_state_self_dependency(ctx: CheckContext) -> Iterator[Violation]:
    """DAE515 MS-20, MS-10: an <Output> that is itself a continuous state, with a dependencies
    list that leaves itself out. A state is a known and the output is that known: whether the
    list should name it is open (Reference-FMUs issue 657; FMI's development text adds that
    importers must not rely on self-dependencies). Information, naming the question."""
    if (model := ctx.model) is None:
        return
    states = set(model.state_vrs())
    for u in model.unknowns("Output"):
        if u.vr in states and u.dependencies is not None and u.vr not in u.dependencies:
            var = model.by_vr.get(u.vr)
            listed = " ".join(map(str, u.dependencies))
            yield Violation(
                "the output {subject} is itself a continuous state and its dependencies "
                f'("{listed}") do not name it; FMI 3.0 does not say whether they should '
                "(open question, Reference-FMUs issue 657): importers must not rely on a "
                "self-dependency, and lsdae does not probe this output's own entry",
                unknown_loc(u),
                evidence(value_reference=u.vr, dependencies=list(u.dependencies),
                         open_question="Reference-FMUs issue 657: should an output that is a "
                                       "state depend on itself?"),
                subject=var.name if var is not None else str(u.vr))


CHECKS: dict[str, Check] = {
    "DAE510": model_structure_unknown_vr,
    "DAE511": model_structure_output_mismatch,
    "DAE512": model_structure_derivative_missing,
    "DAE513": model_structure_initial_unknown_mismatch,
    "DAE514": directional_derivatives_missing,
    "DAE515": output_state_self_dependency,
}
