"""The one pass over modelDescription.xml that the core FMI 3.0 rules (DAE501-DAE514) share.

The variable rules (:mod:`.model_variables`) and the ModelStructure rules (:mod:`.model_structure`)
read the same per-model analysis: a verdict per attribute signature (MV-10..12, MV-20, MV-21), the
independent variables, the variables with a derivative attribute, outputs and calculated
parameters, clocked value references and the ModelStructure elements by kind. It is computed once
per model with dicts and sets, so a model with 100,000 variables costs milliseconds.
"""
from __future__ import annotations

import weakref
from operator import attrgetter
from typing import Optional

from .context import CheckContext
from ..report.findings import Location
from ..model.description import FLOAT_TYPES, ModelDescription, Variable, VariableDetails
from ..model.unknowns import Unknown

CAUSALITIES = frozenset({"structuralParameter", "parameter", "calculatedParameter", "input",
                         "output", "local", "independent"})
VARIABILITIES = frozenset({"constant", "fixed", "tunable", "discrete", "continuous"})
INITIALS = frozenset({"exact", "approx", "calculated"})

# MV-10: legal variabilities per causality (independent is MV-13, checked by its own rule).
ALLOWED_VARIABILITY: dict[str, frozenset[str]] = {
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


def allowed_initial(causality: str, variability: str) -> frozenset[str]:
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


def enable_vrs(ctx: CheckContext) -> frozenset[int]:
    """Value references of the manifest's enable parameter(s): the enable rules (DAE2xx)
    explain their causality, variability, start and use in a <Dimension> better than the
    generic core rules, which leave them alone."""
    if ctx.manifest is None or ctx.model is None:
        return frozenset()
    model, enables = ctx.model, ctx.manifest.enables
    vrs = {ref.vr for ref in enables if ref.vr is not None}
    if any(ref.vr is None for ref in enables):  # an old draft names it: look the name up
        names = {v.name: v.vr for v in model.variables}
        vrs.update(names.get(ref.name or "") for ref in enables if ref.vr is None)
    return frozenset(vr for vr in vrs if vr is not None)


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
    if v not in ALLOWED_VARIABILITY[c]:
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
    if declared_initial is not None and declared_initial not in allowed_initial(c, v):
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
    """One pass over a model shared by the rules of :mod:`.model_variables` and
    :mod:`.model_structure`.

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
        # The distinct sets of rarely given attributes (nominal, min, max, clocks, unit, ...):
        # the reader shares one VariableDetails among variables with the same ones, so a model
        # holds few, and a rule on those attributes decides a clean model from these alone.
        self.details: set[VariableDetails] = set(map(attrgetter("details"), model.variables))
        self.has_arrays = any(d.dimensions for d in self.details)  # a variable has <Dimension>
        memo: dict[tuple, Verdict] = {}
        # One loop with few attribute reads per variable: it runs 500k times in a large model.
        outputs, calculated = self.by_causality["output"], self.by_causality["calculatedParameter"]
        variables = model.variables
        any_clocks = any(d.clocks is not None for d in self.details)
        for var in variables:
            causality = var.causality
            if var.derivative is not None:
                self.derivatives.append(var)
            if causality == "output":
                outputs.append(var)
            elif causality == "calculatedParameter":
                calculated.append(var)
            elif causality == "independent":
                self.independents.append(var)
            clocked = any_clocks and var.clocks is not None
            key = (var.type, causality, var.variability, var.declared_initial, var.initial,
                   clocked, var.start is not None)
            verdict = memo.get(key)
            if verdict is None:
                verdict = memo[key] = _verdict(*key)
            if verdict is not _CLEAN:
                self.verdicts.append((var, verdict))
            if (clocked or key[0] == "Clock") and var.vr is not None:
                self.clocked_vrs.add(var.vr)
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


def derivatives_listed_well(model: ModelDescription) -> bool:
    """Whether :func:`.model_variables.derivative_invalid`'s ContinuousStateDerivative loop has
    nothing to say (in C): each names a distinct existing float state, and both are continuous."""
    listed = analyse(model).unknowns("ContinuousStateDerivative")
    ders = list(filter(None, map(model.by_vr.get, map(attrgetter("vr"), listed))))
    state_vrs = list(map(attrgetter("derivative"), ders))
    states = list(map(model.by_vr.get, state_vrs))  # by_vr.get(None) is None
    return (all(states) and len(set(state_vrs)) == len(state_vrs)
            and FLOAT_TYPES.issuperset(map(attrgetter("type"), states))
            and set(map(attrgetter("variability"), ders + states)) <= {"continuous"})
