"""Whether an FMU uses the fmi-ls-dae layer, and how to say so when it does not.

A finding about the DAE layer applies only to an FMU that declares the layer. An FMU declares it
with anything under ``extra/org.fmi-standard.fmi-ls-dae/`` (the layered standard's folder,
LS-01; a manifest there counts in any draft shape, readable or not) or with a variable named as
the drafts name the enable switch (D-07: ``enableDAEModeParameter``, ``enableDAEModeVariable``,
and ``ODE_DAE_Switch`` of the LS-int SimpleDAE example). A Boolean structural parameter with
another name is not a declaration: FMI 3.0 allows it in any FMU (MV-42).

Every other FMU is an ordinary FMI 3.0 FMU of its interface types. It gets one info finding
(``manifest-missing``) worded for those types, the core FMI rules, and nothing else: the rules
that need the layer (catalogue ``needs = ["dae-layer"]`` or ``["manifest"]``) are skipped with
:data:`NOT_A_DAE_FMU` as the reason.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from ..report.findings import Location, Violation, evidence
from .manifest import MANIFEST
from .description import ModelDescription

LAYER_FOLDER = "extra/org.fmi-standard.fmi-ls-dae/"
ENABLE_PARAMETER_NAMES = frozenset({"enableDAEModeParameter", "enableDAEModeVariable",
                                    "ODE_DAE_Switch"})
DAE_LAYER = "dae-layer"
NOT_A_DAE_FMU = "the FMU does not use the fmi-ls-dae layer (no manifest, no enable parameter)"
_LAYER_NEEDS = frozenset({DAE_LAYER, "manifest"})


def layer_declaration(model: ModelDescription | None, names: Iterable[str]) -> str | None:
    """What declares the layer (a file of the layer's folder, or a variable), or None."""
    files = sorted(n for n in names if n.startswith(LAYER_FOLDER) and n != LAYER_FOLDER)
    if MANIFEST in files:
        return MANIFEST
    if files:
        return files[0]
    if model is not None:
        for var in model.variables:
            if var.name in ENABLE_PARAMETER_NAMES:
                return f"variable '{var.name}'"
    return None


def interface_types(model: ModelDescription | None) -> tuple[str, ...]:
    """The interface types the modelDescription declares, in the standard's order."""
    if model is None:
        return ()
    present = (("Model Exchange", model.model_exchange is not None),
               ("Co-Simulation", model.has_co_simulation),
               ("Scheduled Execution", model.has_scheduled_execution))
    return tuple(name for name, there in present if there)


def describe_fmu(model: ModelDescription | None) -> str:
    """'a Co-Simulation FMU', 'a Model Exchange and Co-Simulation FMU', ..., or 'an FMU'."""
    kinds = interface_types(model)
    if not kinds:
        return "an FMU"
    joined = kinds[0] if len(kinds) == 1 else f"{', '.join(kinds[:-1])} and {kinds[-1]}"
    return f"a {joined} FMU"


def manifest_missing(model: ModelDescription | None, names: Sequence[str]) -> Violation:
    """The ``manifest-missing`` finding, worded true for the FMU's interface types."""
    declaration = layer_declaration(model, names)
    if declaration is None:
        message = (f"no fmi-ls-dae manifest ({MANIFEST}): {describe_fmu(model)} that does not "
                   "use the DAE layer; the DAE rules are skipped")
    else:
        message = (f"no {MANIFEST}, although {declaration} declares the fmi-ls-dae layer: the "
                   "DAE rules that need the manifest are skipped")
    # files of the layer's folder, but not the manifest alpha.1 requires there
    folder = declaration is not None and declaration.startswith(LAYER_FOLDER)
    return Violation(message, Location(file=MANIFEST),
                     evidence(interface_types=list(interface_types(model)),
                              layer_declared_by=declaration),
                     part="layer-folder-without-manifest" if folder else None)


def skip_reason(needs: Sequence[str], have: Mapping[str, bool]) -> str | None:
    """Why a rule with these ``needs`` cannot run (None: it can).

    A rule that needs the manifest or the layer is a layer rule: on an FMU (with a readable
    modelDescription) that does not declare the layer, its reason is :data:`NOT_A_DAE_FMU`.
    """
    missing = [n for n in needs if not have.get(n, False)]
    if not missing:
        return None
    if "model-description" in missing:
        return "no model-description"
    if not have.get(DAE_LAYER, False) and _LAYER_NEEDS.intersection(needs):
        return NOT_A_DAE_FMU
    return f"no {missing[0]}"
