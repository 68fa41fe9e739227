"""How a manifest of a legacy draft migrates to fmi-ls-dae 1.0.0-alpha.1.

A legacy manifest gives one ``legacy-draft-shape`` warning whose message and evidence carry
concrete migration hints, naming the value references found in the file; alpha.1 manifests and
unrecognised roots give none (those are :mod:`conformance.model.drafts.detect`'s business).
"""
from __future__ import annotations

from typing import Iterator, Sequence

from lxml import etree

from ...report.findings import Location, Violation, evidence
from .detect import (
    ALPHA1_DESCRIPTION,
    ALPHA1_NAME,
    ALPHA1_VERSION,
    ATTRIBUTES_ONLY,
    DRAFT_LABELS,
    FLAT_INDEX,
    LEGACY_DRAFTS,
    LS_NAMESPACE,
)
from .elements import (
    all_elements,
    children_named,
    element_children,
    first_child,
    residual_elements,
    written_name,
)

#: alpha.1 order of the manifest ModelStructure children.
MODEL_STRUCTURE_ORDER = (
    "Output", "ContinuousStateDerivative", "ClockedState", "InitialUnknown",
    "EventIndicator", "Residual", "Invariant",
)

# How many residuals get a hint of their own before the rest are summarised.
_MAX_SPELLED_OUT = 3
# How many value references a summary lists before "and N more".
_MAX_LISTED = 12


# --------------------------------------------------------------------------------------------
# Violations


#: The cause a legacy manifest's shape names (``Violation.cause``): legacy-draft-shape, and the
#: header texts the shape implies, which its migration sets (one defect, one finding).
LEGACY_SHAPE_CAUSE = "legacy draft shape"


def legacy_violations(root: etree._Element, draft: str, *, file: str) -> Iterator[Violation]:
    """One ``legacy-draft-shape`` violation for a manifest of a legacy draft; nothing otherwise."""
    if draft not in LEGACY_DRAFTS:
        return
    hints = migration_hints(root, draft)
    label = DRAFT_LABELS[draft]
    lead = f"the manifest follows the {label}, not fmi-ls-dae {ALPHA1_VERSION}"
    if draft == ATTRIBUTES_ONLY:
        lead += (
            "; it declares the FMU a DAE-FMU but names no algebraic variables, residuals or "
            "enable parameter, so an importer has nothing to use"
        )
        if not _is_true(root.get("isDaeFmu")):
            lead += " (and isDaeFmu is false, so it does not even claim DAE support)"
    message = f"{lead}. To migrate: " + "; ".join(hints) if hints else lead
    written = written_name(root)
    higher = [r.sourceline for r in residual_elements(root)
              if len(children_named(r, "Formulation")) > 1]
    yield Violation(
        message=message,
        location=Location(file=file, line=root.sourceline, path="/" + written),
        evidence=evidence(
            draft=draft,
            draft_label=label,
            root=written,
            hints=tuple(hints),
            higher_index_residual_lines=tuple(higher),
        ),
        subject=draft,
        rule="legacy-draft-shape",
        cause=LEGACY_SHAPE_CAUSE,
    )


# --------------------------------------------------------------------------------------------
# Migration hints


def migration_hints(root: etree._Element, draft: str) -> tuple[str, ...]:
    """Concrete steps that turn this manifest into a 1.0.0-alpha.1 one; empty for alpha1/unknown."""
    if draft not in LEGACY_DRAFTS:
        return ()
    hints: list[str | None] = [_root_hint(root, draft)]
    if draft == ATTRIBUTES_ONLY:
        hints.append(_enable_hint(root))
        hints.append(
            "add `<AlgebraicVariables>` with one `<AlgebraicVariable valueReference=\"…\"/>` per "
            "algebraic variable, and a `<ModelStructure>` listing the DAE-mode "
            "`<ContinuousStateDerivative>`/`<InitialUnknown>` elements and one flat "
            "`<Residual valueReference=\"…\" dependencies=\"…\"/>` per residual"
        )
    else:
        hints.append(_enable_hint(root))
        hints.append(_nominal_hint(root))
        if draft == FLAT_INDEX:
            hints.append(_flat_index_hint(root))
        else:
            hints.extend(_formulation_hints(root))
        hints.append(_order_hint(root))
    hints.extend(_header_hints(root))
    return tuple(h for h in hints if h)


def _root_hint(root: etree._Element, draft: str) -> str:
    written = written_name(root)
    hint = f"rename the root `<{written}>` to `<fmiDAEManifest>`"
    namespace = etree.QName(root).namespace
    if draft == ATTRIBUTES_ONLY:
        value = root.get("isDaeFmu")
        if value is not None:
            hint += f" and drop `isDaeFmu=\"{value}\"` (alpha.1 switches DAE mode at run time " \
                    "through the enable parameter)"
    if namespace is not None and root.prefix is None:
        hint += (
            f" and remove the default namespace declaration `xmlns=\"{namespace}\"`, so that the "
            "manifest elements are in no namespace (keep `xmlns:fmi-ls` for the three `fmi-ls:` "
            "attributes)"
        )
    elif namespace is not None:
        hint += ", in no namespace (no prefix)"
        descendants = [e for e in all_elements(root) if e is not root]
        prefixed = [e for e in descendants if e.prefix and etree.QName(e).namespace == namespace]
        if prefixed and len(prefixed) == len(descendants):
            hint += f", and drop the `{root.prefix}:` prefix from every child element"
        elif prefixed:
            names = sorted({written_name(e) for e in prefixed})
            hint += f", and drop the `{root.prefix}:` prefix from " + ", ".join(f"`<{n}>`" for n in names)
    return hint


def _enable_hint(root: etree._Element) -> str | None:
    parameter = children_named(root, "EnableDAEParameter")
    legacy = children_named(root, "EnableDAE")
    attribute = root.get("enableDAEModeVariable")
    parts: list[str] = []
    if legacy:
        element = legacy[0]
        vr = element.get("valueReference", "…")
        rename = (
            f"rename `<{written_name(element)}>` to `<EnableDAEParameter>` "
            f"(`<EnableDAEParameter valueReference=\"{vr}\"/>`)"
        )
        first = first_child(root)
        if first is not None and first is not element:
            rename += " and make it the root's first child"
        parts.append(rename)
    if attribute is not None:
        if parameter or legacy:
            parts.append(f"drop the root attribute `enableDAEModeVariable=\"{attribute}\"`")
        elif attribute.strip().isdigit():
            parts.append(
                f"replace the root attribute `enableDAEModeVariable=\"{attribute}\"` by "
                f"`<EnableDAEParameter valueReference=\"{attribute.strip()}\"/>` as the root's first child"
            )
        else:
            parts.append(
                f"replace the root attribute `enableDAEModeVariable=\"{attribute}\"` by "
                "`<EnableDAEParameter valueReference=\"…\"/>` as the root's first child, holding the "
                f"value reference of the variable `{attribute}` (alpha.1 names the enable parameter by "
                "value reference, not by name)"
            )
    if not parts and not parameter:
        parts.append(
            "add an `<EnableDAEParameter valueReference=\"…\"/>` as the root's first child and the "
            "Boolean structural parameter it points to in modelDescription.xml "
            "(causality=\"structuralParameter\", variability=\"fixed\" or \"tunable\", start=\"false\")"
        )
    return "; ".join(parts) if parts else None


def _nominal_hint(root: etree._Element) -> str | None:
    found = [
        (v.get("valueReference", "?"), v.get("nominal", ""))
        for block in children_named(root, "AlgebraicVariables")
        for v in children_named(block, "AlgebraicVariable")
        if v.get("nominal") is not None
    ]
    if not found:
        return None
    listed = _listing([f"valueReference {vr}: `nominal=\"{nominal}\"`" for vr, nominal in found])
    return (
        f"drop `nominal` from AlgebraicVariable ({listed}); alpha.1 takes nominal values only from "
        "the variables in modelDescription.xml"
    )


def _formulation_hints(root: etree._Element) -> list[str]:
    hints: list[str] = []
    flatten: list[etree._Element] = []
    for residual in residual_elements(root):
        formulations = children_named(residual, "Formulation")
        if len(formulations) == 1:
            flatten.append(formulations[0])
        elif len(formulations) > 1:
            vrs = ", ".join(f.get("valueReference", "?") for f in formulations)
            hints.append(
                f"the `<Residual>` at line {residual.sourceline} has {len(formulations)} Formulations "
                f"(value references {vrs}): a higher-index constraint, which has no alpha.1 form "
                "(alpha.1 covers semi-explicit index-1 DAEs only); reduce the model's index so that "
                "it is described by index-1 residuals"
            )
    spelled = flatten if len(flatten) <= _MAX_SPELLED_OUT else flatten[:1]
    for formulation in spelled:
        hints.append(_flatten_hint(formulation))
    rest = flatten[len(spelled):]
    if rest:
        vrs = _listing([f.get("valueReference", "?") for f in rest])
        hints.append(
            f"likewise flatten the other {len(rest)} `<Residual><Formulation …/></Residual>` "
            f"(value references {vrs}) and drop their `index`"
        )
    return hints


def _flatten_hint(formulation: etree._Element) -> str:
    attributes = [(k, v) for k, v in formulation.attrib.items() if isinstance(k, str)]
    before = " ".join(f'{k}="{v}"' for k, v in attributes)
    after = " ".join(f'{k}="{v}"' for k, v in attributes if k != "index")
    hint = (
        f"flatten `<Residual><Formulation {before}/></Residual>` into `<Residual {after}/>`"
    )
    if formulation.get("index") is not None:
        hint += "; drop `index`"
    return hint


def _flat_index_hint(root: etree._Element) -> str | None:
    indexed = [r for r in residual_elements(root) if r.get("index") is not None]
    if not indexed:
        return None
    vrs = _listing([r.get("valueReference", "?") for r in indexed])
    return f"drop `index` from `<Residual>` (value references {vrs})"


def _order_hint(root: etree._Element) -> str | None:
    kinds = [
        etree.QName(child).localname
        for structure in children_named(root, "ModelStructure")
        for child in element_children(structure)
        if etree.QName(child).localname in MODEL_STRUCTURE_ORDER
    ]
    rank = {kind: i for i, kind in enumerate(MODEL_STRUCTURE_ORDER)}
    if all(rank[a] <= rank[b] for a, b in zip(kinds, kinds[1:])):
        return None
    runs = [k for i, k in enumerate(kinds) if i == 0 or kinds[i - 1] != k]
    hint = (
        "put the `<ModelStructure>` children in the alpha.1 order "
        + ", ".join(MODEL_STRUCTURE_ORDER) + " (found " + ", ".join(runs) + ")"
    )
    if "Residual" in kinds:
        after = kinds[kinds.index("Residual"):]
        must_precede = [k for k in MODEL_STRUCTURE_ORDER if rank[k] < rank["Residual"] and k in after]
        if must_precede:
            hint += "; in particular move `Residual` after " + "/".join(f"`{k}`" for k in must_precede)
    return hint


def _header_hints(root: etree._Element) -> list[str]:
    hints = []
    for attribute, wanted in (
        ("fmi-ls-name", ALPHA1_NAME),
        ("fmi-ls-version", ALPHA1_VERSION),
        ("fmi-ls-description", ALPHA1_DESCRIPTION),
    ):
        value = root.get(f"{{{LS_NAMESPACE}}}{attribute}")
        unqualified = root.get(attribute)
        if value is None and unqualified is not None:
            hints.append(
                f"qualify `{attribute}` as `fmi-ls:{attribute}` (prefix bound to {LS_NAMESPACE})"
                + ("" if unqualified == wanted else f" and set it to \"{wanted}\" (found \"{unqualified}\")")
            )
        elif value is None:
            hints.append(f"add `fmi-ls:{attribute}=\"{wanted}\"`")
        elif value != wanted:
            hints.append(f"set `fmi-ls:{attribute}` to \"{wanted}\" (found \"{value}\")")
    return hints


# --------------------------------------------------------------------------------------------
# Small helpers


def _listing(items: Sequence[str]) -> str:
    if len(items) <= _MAX_LISTED:
        return ", ".join(items)
    return ", ".join(items[:_MAX_LISTED]) + f" and {len(items) - _MAX_LISTED} more"


def _is_true(value: str | None) -> bool:
    return value is not None and value.strip() in ("true", "1")
