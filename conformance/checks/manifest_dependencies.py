"""Static checks: the dependencies in the manifest's DAE-mode ModelStructure (DAE420-DAE423).

In DAE mode the manifest ``<ModelStructure>`` replaces the modelDescription's (DAE-30). These
rules check its ``dependencies`` against the knowns each element kind may have (DAE-34, MS-10,
MS-11) and its ``dependenciesKind`` (MS-30, MS-31); its Output, ContinuousStateDerivative and
InitialUnknown lists are :mod:`.manifest_lists`'s. Residual basics (DAE401-DAE419) live
elsewhere. A dependency that names no variable is reported only by dependency-unknown-vr; the
other rules skip it.
"""
from __future__ import annotations

import logging
from itertools import chain
from operator import attrgetter
from typing import Iterator

from .context import Check, CheckContext
from ..model.drafts.detect import FORMULATION, LS_DAE_ROOT
from ..report.findings import Location, Violation, evidence
from ..model.description import FLOAT_TYPES, ModelDescription, Variable
from ..model.unknowns import Unknown
from .dae_roles import DaeRoles, describe, roles_of

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
# The element kinds of FMI 3.0.2's ModelStructure, whose dependencies FMI defines (§2.4.8)
_CORE_KINDS = frozenset({"Output", "ContinuousStateDerivative", "ClockedState",
                         "InitialUnknown", "EventIndicator"})


def unknown_name(u: Unknown, model: ModelDescription) -> str:
    """The variable name of a structure element, or its value reference if it names none."""
    var = model.by_vr.get(u.vr) if u.vr is not None else None
    if var is not None:
        return var.name
    return f"valueReference {u.vr}" if u.vr is not None else u.path


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
    all_deps = chain.from_iterable(filter(None, map(attrgetter("dependencies"),
                                                    manifest.structure)))
    if all(map(by_vr.__contains__, all_deps)):
        return  # the usual case: every dependency resolves, decided in C
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
                    subject=unknown_name(u, model),
                    part="core-element-dependency" if u.kind in _CORE_KINDS else None)


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


def _is_discrete_time_state(var: Variable) -> bool:
    """Whether ``var`` may be one of FMI 3.0.2's discrete-time states x_d ("(internal)
    discrete-time variables (of any type)", §2.1), which _allowed does not count as knowns: a
    local variable with variability discrete, or a clocked state (attribute previous)."""
    return var.variability == "discrete" and (var.causality == "local"
                                              or var.previous is not None)


def _not_allowed(u: Unknown, known: Variable, vr: int, what: str, allowed: str,
                 model: ModelDescription, *, part: str | None) -> Violation:
    """The finding of a dependency of ``u`` on ``known`` (value reference ``vr``), which is not
    one of its knowns."""
    return Violation(
        f"{_tag(u)} {{subject}} depends on '{known.name}', {what}; its allowed knowns "
        f"are {allowed}",
        _loc(u), evidence(element=u.kind, known=known.name, known_value_reference=vr,
                          known_is=what, allowed=allowed),
        subject=unknown_name(u, model), part=part)


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
    roles = roles_of(ctx)
    verdicts: dict[tuple[str, int], bool] = {}  # (element kind, known) -> allowed; few distinct
    # Knowns allowed for every kind (see _allowed): algebraic variables, and states for every
    # kind but InitialUnknown. Most dependencies are these: a set test decides them, and when
    # the few other knowns of each kind (gathered in C) are all allowed, nothing is reported.
    algebraic_or_state = roles.algebraic | roles.states
    usual = {kind: roles.algebraic if kind == "InitialUnknown" else algebraic_or_state
             for kind in _CHECKED_KINDS}
    others = {kind: set(chain.from_iterable(filter(None, map(
        attrgetter("dependencies"), manifest.unknowns(kind))))).difference(usual[kind])
        for kind in _CHECKED_KINDS}
    if all((known := model.by_vr.get(vr)) is None or _allowed(kind, known, roles, ctx.draft)
           for kind, vrs in others.items() for vr in vrs):
        return
    found_ok: dict[str, set[int]] = {kind: set() for kind in _CHECKED_KINDS}  # decided allowed
    for u in manifest.structure:
        if u.kind not in _CHECKED_KINDS:
            continue  # EventIndicator/ClockedState dependencies are for debugging (MS-12)
        deps = u.dependencies
        if not deps or usual[u.kind].issuperset(deps):
            continue
        known_ok = found_ok[u.kind]
        if known_ok.issuperset(set(deps).difference(usual[u.kind])):
            continue
        for vr in dict.fromkeys(deps):
            key = (u.kind, vr)
            ok = verdicts.get(key)
            if ok is None:
                known = model.by_vr.get(vr)
                ok = verdicts[key] = known is None or _allowed(u.kind, known, roles, ctx.draft)
                if ok and vr not in usual[u.kind]:
                    known_ok.add(vr)
            if ok:
                continue
            known = model.by_vr[vr]
            what = describe(known, roles)
            if u.kind == "InitialUnknown" and known.initial is not None:
                what += f' with initial="{known.initial}"'
            allowed = _allowed_text(u.kind, ctx.draft)
            if u.kind == "InitialUnknown":
                yield _not_allowed(u, known, vr, what, allowed, model,
                                   part="initial-unknown-known")
            elif u.kind == "Residual":
                yield _not_allowed(u, known, vr, what, allowed, model, part=None)
            elif _is_discrete_time_state(known):  # an Output or ContinuousStateDerivative
                yield _not_allowed(u, known, vr, what, allowed, model,
                                   part="discrete-time-state-known")
            else:
                yield _not_allowed(u, known, vr, what, allowed, model,
                                   part="output-or-derivative-known")


# --- dependencies-kind-length / dependencies-kind-invalid ------------------------------------

_ALWAYS_ALLOWED = frozenset({"dependent"})
_KIND_SET = frozenset(KINDS)
_INITIAL_SET = frozenset(INITIAL_KINDS)

def dependencies_kind_length(ctx: CheckContext) -> Iterator[Violation]:
    """``dependenciesKind`` has one entry per ``dependencies`` entry (MS-30)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    for u in manifest.structure:
        kinds, deps = u.dependencies_kind, u.dependencies
        if kinds is None or (deps is not None and len(deps) + len(u.bad_tokens) == len(kinds)):
            continue  # the usual case
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
    # Only an element of a non-floating-point variable, or an InitialUnknown, can break a rule:
    # when no element names such a variable and every InitialUnknown's kinds (few distinct
    # tuples) are allowed, nothing is reported; decided in C.
    non_float = {v.vr for v in model.variables if v.type not in FLOAT_TYPES}
    initial_kinds = set(map(attrgetter("dependencies_kind"), manifest.unknowns("InitialUnknown")))
    if non_float.isdisjoint(map(attrgetter("vr"), manifest.structure)) and all(
            _KIND_SET.intersection(kinds) <= _INITIAL_SET for kinds in initial_kinds if kinds):
        return
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


CHECKS: dict[str, Check] = {
    "DAE420": dependency_unknown_vr,
    "DAE421": dependency_not_allowed_known,
    "DAE422": dependencies_kind_length,
    "DAE423": dependencies_kind_invalid,
}
