"""Static checks: which form of DAE the manifest describes (DAE406, DAE407).

1.0.0-alpha.1 exposes the semi-explicit form ``der(x) = f(x, w, u, t)``, ``0 = g(x, w, u, t)``
(§2.2, DAE-52): the FMU computes the state derivatives, the importer sets the algebraic
variables. One exporter writes the fully implicit form ``0 = F(der(x), x, w, t)`` instead: a
residual for every unknown, the derivatives set by the importer, and no
``<ContinuousStateDerivative>`` in the manifest. :func:`fully_implicit` recognises it (as many
residual elements as states plus algebraic variables, and no state derivative listed), so that
``fully-implicit-form`` names it with the rewrite, and ``residual-count-mismatch`` stays silent
instead of sending the vendor to delete residuals.

A semi-explicit manifest that lists no ``<ContinuousStateDerivative>`` although the model has
states is read differently by importers (``state-derivatives-unlisted``).
"""
from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.manifest import Manifest
from ..model.description import ModelDescription
from .algebraic import element_count


class Counts(NamedTuple):
    states: int
    algebraic: int
    residuals: int


def _elements(model: ModelDescription, vrs) -> int | None:
    total = 0
    for vr in vrs:
        var = model.by_vr.get(vr) if vr is not None else None
        size = element_count(model, var) if var is not None else None
        if size is None:
            return None
        total += size
    return total


def counts(model: ModelDescription, manifest: Manifest) -> Counts | None:
    """States (from modelDescription), algebraic and residual elements; None when a size is
    not known statically or an entry does not resolve (other rules report those)."""
    states = _elements(model, model.state_vrs())
    algebraic = _elements(model, [a.vr for a in manifest.algebraic])
    residuals = _elements(model, [r.vr for r in manifest.residuals])
    if states is None or algebraic is None or residuals is None:
        return None
    return Counts(states, algebraic, residuals)


def _derivative_dependencies(model: ModelDescription, manifest: Manifest) -> list[str]:
    """Names of state derivatives that residual dependencies list (knowns of the implicit form)."""
    derivatives = {u.vr for u in model.unknowns("ContinuousStateDerivative")}
    return sorted({model.by_vr[vr].name for r in manifest.residuals
                   for vr in (r.dependencies or ()) if vr in derivatives and vr in model.by_vr})


def fully_implicit(model: ModelDescription | None, manifest: Manifest | None) -> Counts | None:
    """The counts when the manifest describes the fully implicit form, else None: no
    <ContinuousStateDerivative>, and as many residual elements as states plus algebraic
    variables. Without algebraic variables that count is as well a semi-explicit manifest with
    a residual too many; only residuals that depend on a state derivative then tell."""
    if model is None or manifest is None or manifest.unknowns("ContinuousStateDerivative"):
        return None
    found = counts(model, manifest)
    if found is None or found.states == 0 or found.residuals != found.states + found.algebraic:
        return None
    if found.algebraic == 0 and not _derivative_dependencies(model, manifest):
        return None
    return found


def _where(manifest: Manifest) -> Location:
    if manifest.residuals:
        first = manifest.residuals[0]
        return Location(file=manifest.file, line=first.line, path=first.path)
    return Location(file=manifest.file, line=manifest.root_line)


def fully_implicit_form(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-52, D-06: 1.0.0-alpha.1 excludes the fully implicit form 0 = F(der(x), x, w, t)."""
    found = fully_implicit(ctx.model, ctx.manifest)
    if found is None:
        return
    manifest = ctx.manifest
    assert manifest is not None and ctx.model is not None
    uses_derivatives = _derivative_dependencies(ctx.model, manifest)
    yield Violation(
        f"the manifest describes the fully implicit form 0 = F(der(x), x, w, t): "
        f"{found.residuals} residuals for {found.states} states and {found.algebraic} "
        "algebraic variables, and no <ContinuousStateDerivative>; fmi-ls-dae 1.0.0-alpha.1 "
        "§2.2 supports only the semi-explicit form der(x) = f(x, w, t), 0 = g(x, w, t). "
        "Rewrite it as the standard does: add one algebraic variable v_i per state "
        "derivative, let each der(x_i) be computed as v_i and list it as "
        "<ContinuousStateDerivative>, and keep the residuals F(v, x, w, t) = 0, which then "
        "determine v and w together (as many residuals as algebraic variables)",
        _where(manifest),
        evidence(states=found.states, algebraic_variables=found.algebraic,
                 residuals=found.residuals, residual_dependencies_on_derivatives=uses_derivatives),
        subject=manifest.root_name)


def state_derivatives_unlisted(ctx: CheckContext) -> Iterator[Violation]:
    """Q-02: a semi-explicit manifest without <ContinuousStateDerivative> for a model with
    states leaves importers to guess."""
    model, manifest = ctx.model, ctx.manifest
    if model is None or manifest is None or manifest.unknowns("ContinuousStateDerivative"):
        return
    if fully_implicit(model, manifest) is not None:
        return  # fully-implicit-form says what it is
    states = model.state_vrs()
    if not states:
        return
    names = [model.by_vr[vr].name for vr in states if vr in model.by_vr]
    yield Violation(
        f"the manifest's <ModelStructure> lists no <ContinuousStateDerivative>, although the "
        f"model has {len(states)} continuous state(s); in DAE mode the manifest's structure "
        "replaces modelDescription's, and importers disagree on what an empty list means: "
        "one reads the manifest as the fully implicit form and refuses the FMU, another "
        "builds a DAE without states. List every <ContinuousStateDerivative> (with its "
        "DAE-mode dependencies) in the manifest",
        _where(manifest), evidence(states=names[:20], state_count=len(states)),
        subject=manifest.root_name)


CHECKS: dict[str, Check] = {
    "DAE406": fully_implicit_form,
    "DAE407": state_derivatives_unlisted,
}
