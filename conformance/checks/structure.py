"""Static checks: the DAE-mode model structure in the manifest (DAE420-DAE499).

In DAE mode the manifest ``<ModelStructure>`` replaces the modelDescription's (DAE-30). These
rules check its ``dependencies`` against the knowns each element kind may have (DAE-34, MS-10,
MS-11), its ``dependenciesKind`` (MS-30, MS-31), and its Output, ContinuousStateDerivative and
InitialUnknown lists against the variables (MS-02, MS-03, MS-05, D-10, D-16, Q-02, Q-06, Q-09).
Residual basics (DAE401-DAE419) live elsewhere. Each problem is reported once: a dependency that
names no variable only by dependency-unknown-vr (the other rules skip it), an Output,
ContinuousStateDerivative or InitialUnknown that names no variable by the list rule of its kind,
and a Residual that names none by residual-unknown-vr.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Iterator

from ..context import Check, CheckContext
from ..drafts.detect import FORMULATION, LS_DAE_ROOT
from ..findings import Location, Violation, evidence
from ..manifest import Manifest
from ..model import ModelDescription, Unknown, Variable

log = logging.getLogger(__name__)

KINDS = ("dependent", "constant", "fixed", "tunable", "discrete")
INITIAL_KINDS = ("dependent", "constant")
# Drafts whose residuals are fully implicit F(der(x), x, w, t): state derivatives are knowns (D-06).
IMPLICIT_DRAFTS = (FORMULATION, LS_DAE_ROOT)

_CT_KNOWNS = ("inputs, continuous states, parameters, algebraic variables and the independent "
              "variable")
_IMPLICIT_KNOWNS = ("inputs, continuous states, continuous state derivatives, parameters, "
                    "algebraic variables and the independent variable")
_INIT_KNOWNS = ("inputs, variables with initial=\"exact\", algebraic variables and the "
                "independent variable")
_CHECKED_KINDS = ("Output", "ContinuousStateDerivative", "InitialUnknown", "Residual")


@dataclass(frozen=True)
class DaeRoles:
    """What each variable is in DAE mode, by value reference.

    States and derivatives come from the manifest's ContinuousStateDerivative list, or from the
    modelDescription's when the manifest lists none (an absent list is inherited, Q-02).
    """

    algebraic: frozenset[int]
    states: frozenset[int]
    derivatives: frozenset[int]
    residuals: frozenset[int]

    @classmethod
    def of(cls, model: ModelDescription, manifest: Manifest) -> DaeRoles:
        csd = manifest.unknowns("ContinuousStateDerivative") or \
            tuple(model.unknowns("ContinuousStateDerivative"))
        derivatives = {u.vr for u in csd if u.vr is not None}
        states = set()
        for vr in derivatives:
            var = model.by_vr.get(vr)
            if var is not None and var.derivative is not None:
                states.add(var.derivative)
        return cls(
            algebraic=frozenset(a.vr for a in manifest.algebraic if a.vr is not None),
            states=frozenset(states), derivatives=frozenset(derivatives),
            residuals=frozenset(u.vr for u in manifest.residuals if u.vr is not None))


def describe(var: Variable, roles: DaeRoles) -> str:
    """A short noun phrase for what ``var`` is ("a local variable", "a state derivative", ...)."""
    vr = var.vr
    if vr in roles.algebraic:
        return "an algebraic variable"
    if vr in roles.residuals:
        return "a residual"
    if vr in roles.states:
        return "a continuous state"
    if vr in roles.derivatives:
        return "a continuous state derivative"
    if var.variability == "constant":
        return "a constant"
    return {
        "structuralParameter": "a structural parameter",
        "calculatedParameter": "a calculated parameter",
        "parameter": "a parameter",
        "input": "an input",
        "output": "an output",
        "independent": "the independent variable",
    }.get(var.causality, "a local variable")


def unknown_name(u: Unknown, model: ModelDescription) -> str:
    """The variable name of a structure element, or its value reference if it names none."""
    var = model.by_vr.get(u.vr) if u.vr is not None else None
    if var is not None:
        return var.name
    return f"valueReference {u.vr}" if u.vr is not None else u.path


def _unresolved(u: Unknown) -> Violation:
    """A list element whose own valueReference names no variable."""
    return Violation(
        f"<{u.kind}> {{subject}} names no variable in modelDescription.xml",
        _loc(u), evidence(element=u.kind, value_reference=u.vr),
        subject=f"valueReference {u.vr}" if u.vr is not None else u.path)


def _loc(u: Unknown) -> Location:
    return Location(file=u.file, line=u.line, path=u.path)


def _tag(u: Unknown) -> str:
    return "<Formulation>" if u.formulations else f"<{u.kind}>"


# --- dependency-unknown-vr ------------------------------------------------------------------

def dependency_unknown_vr(ctx: CheckContext) -> Iterator[Violation]:
    """Every manifest ModelStructure ``dependencies`` entry names a variable (MV-03, DAE-35)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    # Tokens that are not unsigned integers are left to the schema stage: fmi3Unknown types
    # dependencies as a list of xs:unsignedInt in every draft's schema.
    by_vr = model.by_vr
    for u in manifest.structure:
        deps = u.dependencies
        if not deps or all(vr in by_vr for vr in deps):
            continue
        for vr in dict.fromkeys(deps):
            if vr not in by_vr:
                yield Violation(
                    f"the dependencies of {_tag(u)} {{subject}} list valueReference {vr}, which "
                    "names no variable in modelDescription.xml",
                    _loc(u), evidence(element=u.kind, value_reference=vr),
                    subject=unknown_name(u, model))


# --- dependency-not-allowed-known ------------------------------------------------------------

def _allowed(kind: str, var: Variable, roles: DaeRoles, draft: str | None) -> bool:
    vr = var.vr
    if vr in roles.algebraic or var.causality in ("input", "independent"):
        return True
    if kind == "InitialUnknown":
        return var.initial == "exact"
    if var.causality == "parameter" or vr in roles.states:
        return True
    return kind == "Residual" and draft in IMPLICIT_DRAFTS and vr in roles.derivatives


def _allowed_text(kind: str, draft: str | None) -> str:
    if kind == "InitialUnknown":
        return _INIT_KNOWNS
    if kind == "Residual" and draft in IMPLICIT_DRAFTS:
        return _IMPLICIT_KNOWNS
    return _CT_KNOWNS


def dependency_not_allowed_known(ctx: CheckContext) -> Iterator[Violation]:
    """Each dependency is a known the element kind may have (DAE-34, MS-10, MS-11, D-06)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    roles = DaeRoles.of(model, manifest)
    verdicts: dict[tuple[str, int], bool] = {}  # (element kind, known) -> allowed; few distinct
    for u in manifest.structure:
        if u.kind not in _CHECKED_KINDS:
            continue  # EventIndicator/ClockedState dependencies are for debugging (MS-12)
        for vr in dict.fromkeys(u.dependencies or ()):
            key = (u.kind, vr)
            ok = verdicts.get(key)
            if ok is None:
                known = model.by_vr.get(vr)
                ok = verdicts[key] = known is None or _allowed(u.kind, known, roles, ctx.draft)
            if ok:
                continue
            known = model.by_vr[vr]
            what = describe(known, roles)
            if u.kind == "InitialUnknown" and known.initial is not None:
                what += f' with initial="{known.initial}"'
            allowed = _allowed_text(u.kind, ctx.draft)
            yield Violation(
                f"{_tag(u)} {{subject}} depends on '{known.name}', {what}; its allowed knowns "
                f"are {allowed}",
                _loc(u), evidence(element=u.kind, known=known.name, known_value_reference=vr,
                                  known_is=what, allowed=allowed),
                subject=unknown_name(u, model))


# --- dependencies-kind-length / dependencies-kind-invalid ------------------------------------

_ALWAYS_ALLOWED = frozenset({"dependent"})
_KIND_SET = frozenset(KINDS)

def dependencies_kind_length(ctx: CheckContext) -> Iterator[Violation]:
    """``dependenciesKind`` has one entry per ``dependencies`` entry (MS-30)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    for u in manifest.structure:
        if u.dependencies_kind is None:
            continue
        name = unknown_name(u, model)
        if u.dependencies is None:
            yield Violation(
                f"{_tag(u)} {{subject}} has dependenciesKind but no dependencies attribute; "
                "remove dependenciesKind or list the dependencies it describes",
                _loc(u), evidence(element=u.kind, kinds=len(u.dependencies_kind)), subject=name)
            continue
        n_deps = len(u.dependencies) + len(u.bad_tokens)
        if n_deps != len(u.dependencies_kind):
            yield Violation(
                f"{_tag(u)} {{subject}} has {len(u.dependencies_kind)} dependenciesKind entries "
                f"for {n_deps} dependencies; give exactly one kind per dependency",
                _loc(u), evidence(element=u.kind, dependencies=n_deps,
                                  kinds=len(u.dependencies_kind)), subject=name)


def dependencies_kind_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """Each ``dependenciesKind`` value exists and is allowed for its unknown (MS-31)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    for u in manifest.structure:
        if not u.dependencies_kind:
            continue
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        kinds = set(u.dependencies_kind)
        if kinds <= _ALWAYS_ALLOWED or (u.kind != "InitialUnknown" and kinds <= _KIND_SET
                                        and (var is None or var.is_float)):
            continue  # the common case: nothing to report, decided without a loop
        name = unknown_name(u, model)
        for kind in dict.fromkeys(u.dependencies_kind):
            if kind not in KINDS:
                continue  # the schema stage reports it: fmi3Unknown enumerates the kinds
            if var is not None and not var.is_float and kind != "dependent":
                yield Violation(
                    f"{_tag(u)} {{subject}} is a <{var.type}> and uses dependenciesKind "
                    f"'{kind}'; a non-floating-point unknown allows only 'dependent'",
                    _loc(u), evidence(element=u.kind, kind=kind, type=var.type), subject=name)
            elif u.kind == "InitialUnknown" and kind not in INITIAL_KINDS:
                yield Violation(
                    f"<InitialUnknown> {{subject}} uses dependenciesKind '{kind}'; an initial "
                    "unknown allows only 'dependent' or 'constant'",
                    _loc(u), evidence(element=u.kind, kind=kind), subject=name)


# --- initial-unknown-not-allowed -------------------------------------------------------------

def initial_unknown_not_allowed(ctx: CheckContext) -> Iterator[Violation]:
    """Manifest InitialUnknowns are core ones or algebraic variables (MS-05, D-10, Q-06)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    roles = DaeRoles.of(model, manifest)
    for u in manifest.unknowns("InitialUnknown"):
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u)
            continue
        if var.vr in roles.algebraic:
            continue
        if var.vr in roles.residuals:
            yield Violation(
                "residual {subject} is listed as <InitialUnknown>; list the algebraic variable "
                "it determines instead, not the residual",
                _loc(u), evidence(element=u.kind, is_residual=True), subject=var.name)
            continue
        not_exact = var.initial in ("approx", "calculated")
        if (var.causality == "calculatedParameter" or var.clocks is not None
                or (not_exact and var.causality == "output")
                or (not_exact and (var.vr in roles.states or var.vr in roles.derivatives))):
            continue
        what = describe(var, roles)
        if var.initial is not None:
            what += f' with initial="{var.initial}"'
        yield Violation(
            f"{{subject}} is listed as <InitialUnknown> but is {what}; initial unknowns are "
            "outputs, continuous states and state derivatives with initial=\"approx\" or "
            "\"calculated\", calculated parameters, and algebraic variables",
            _loc(u), evidence(element=u.kind, variable_is=what, causality=var.causality,
                              initial=var.initial), subject=var.name)


# --- state-derivative-mismatch ---------------------------------------------------------------

def state_derivative_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """The manifest lists the state derivatives of modelDescription.xml (DAE-15, MV-31, Q-09)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    listed = manifest.unknowns("ContinuousStateDerivative")
    if not listed:
        return  # an absent list is inherited from modelDescription.xml
    ours: dict[int, Unknown] = {}
    for u in listed:
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u)
            continue
        if var.derivative is None:
            yield Violation(
                "<ContinuousStateDerivative> {subject} has no derivative attribute, so it names "
                "no state; add derivative=\"<valueReference of the state>\" to the variable",
                _loc(u), evidence(element=u.kind, value_reference=var.vr), subject=var.name)
            continue
        ours.setdefault(var.vr, u)  # type: ignore[arg-type]
    theirs: dict[int, Unknown] = {}
    for u in model.unknowns("ContinuousStateDerivative"):
        if u.vr is not None and u.vr in model.by_vr:
            theirs.setdefault(u.vr, u)
    for vr, u in ours.items():
        if vr not in theirs:
            yield Violation(
                "{subject} is a <ContinuousStateDerivative> in the manifest but not in "
                "modelDescription.xml, so DAE and ODE mode have different state derivative "
                "vectors",
                _loc(u), evidence(value_reference=vr, in_manifest=True,
                                  in_model_description=False), subject=model.by_vr[vr].name)
    for vr, u in theirs.items():
        if vr not in ours:
            yield Violation(
                "{subject} is a <ContinuousStateDerivative> in modelDescription.xml but not in "
                "the manifest, so DAE and ODE mode have different state derivative vectors",
                _loc(u), evidence(value_reference=vr, in_manifest=False,
                                  in_model_description=True), subject=model.by_vr[vr].name)


# --- output-set-mismatch ---------------------------------------------------------------------

def output_set_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """A manifest Output list holds exactly the causality="output" variables (MS-02, D-16)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    listed = manifest.unknowns("Output")
    if not listed:
        return  # an absent Output list is inherited from modelDescription.xml
    outputs = {v.vr: v for v in model.variables if v.causality == "output" and v.vr is not None}
    roles = DaeRoles.of(model, manifest)
    seen = set()
    for u in listed:
        var = model.by_vr.get(u.vr) if u.vr is not None else None
        if var is None:
            yield _unresolved(u)
            continue
        seen.add(var.vr)
        if var.vr not in outputs:
            yield Violation(
                "<Output> {subject} is %s, not a causality=\"output\" variable; list only "
                "outputs" % describe(var, roles),
                _loc(u), evidence(element="Output", causality=var.causality), subject=var.name)
    anchor = listed[-1]
    for vr, var in outputs.items():
        if vr not in seen:
            yield Violation(
                "output {subject} is missing from the manifest's <Output> list; in DAE mode the "
                "manifest list replaces modelDescription.xml's, so add an <Output> for it",
                Location(file=anchor.file, line=anchor.line, path=anchor.path),
                evidence(value_reference=vr, variable_line=var.line), subject=var.name)


CHECKS: dict[str, Check] = {
    "DAE420": dependency_unknown_vr,
    "DAE421": dependency_not_allowed_known,
    "DAE422": dependencies_kind_length,
    "DAE423": dependencies_kind_invalid,
    "DAE424": initial_unknown_not_allowed,
    "DAE425": state_derivative_mismatch,
    "DAE426": output_set_mismatch,
}
