"""Which fmi-ls-dae draft a manifest follows, and how to migrate it to 1.0.0-alpha.1.

Draft ids (stable, used in the catalogue's ``drafts`` field and by ``--draft``):

- ``alpha1``: 1.0.0-alpha.1 / the 2026 paper. Root ``fmiDAEManifest`` (no namespace),
  ``EnableDAEParameter``, flat ``Residual``. Normative.
- ``formulation``: spring/summer 2026 drafts and the Reference-FMUs: root
  ``fmiLayeredStandardManifest`` (ls namespace or unqualified), ``EnableDAE`` (or none, or a root
  attribute ``enableDAEModeVariable``), ``<Residual><Formulation index=.. valueReference=../></Residual>``.
- ``ls-dae-root``: summer 2026 exporters: root ``fmi-ls:fmi-ls-dae`` in the ls namespace,
  Formulation residuals.
- ``flat-index``: the first manifest chapter: root ``fmiLayeredStandardManifest`` with flat
  ``<Residual valueReference=.. index=..>``.
- ``attributes-only``: April 2026 draft schema: root ``fmi-dae`` with ``isDaeFmu``, no content.

Recognition looks at the root's local name (in no namespace or the ls namespace) and, for the
shared root ``fmiLayeredStandardManifest``, at the form of the residuals: any
``<Residual><Formulation/></Residual>`` means ``formulation``; flat residuals (with or without
``index``) mean ``flat-index``; no residuals at all mean ``formulation``, the common case.

A legacy manifest gives one ``legacy-draft-shape`` warning whose message and evidence carry
concrete migration hints, naming the value references found in the file. A root that is none
of the known shapes gives ``draft-unrecognised``.
"""
from __future__ import annotations

from typing import Iterator, Sequence

from lxml import etree

from .findings import Location, Violation, evidence

ALPHA1 = "alpha1"
FORMULATION = "formulation"
LS_DAE_ROOT = "ls-dae-root"
FLAT_INDEX = "flat-index"
ATTRIBUTES_ONLY = "attributes-only"
UNKNOWN = "unknown"

ALL_DRAFTS = (ALPHA1, FORMULATION, LS_DAE_ROOT, FLAT_INDEX, ATTRIBUTES_ONLY)
LEGACY_DRAFTS = (FORMULATION, LS_DAE_ROOT, FLAT_INDEX, ATTRIBUTES_ONLY)

LS_NAMESPACE = "http://fmi-standard.org/fmi-ls-manifest"

AUTO = "auto"

#: Human labels, for messages and reports.
DRAFT_LABELS: dict[str, str] = {
    ALPHA1: "fmi-ls-dae 1.0.0-alpha.1 (September 2026, the 2026 paper)",
    FORMULATION: "Formulation draft (spring/summer 2026, Reference-FMUs)",
    LS_DAE_ROOT: "fmi-ls-dae root draft (summer 2026 exporters)",
    FLAT_INDEX: "flat-index draft (first manifest chapter)",
    ATTRIBUTES_ONLY: "attributes-only draft (April 2026 schema, root fmi-dae)",
    UNKNOWN: "unrecognised manifest shape",
}

#: The alpha.1 header values.
ALPHA1_NAME = "org.fmi-standard.fmi-ls-dae"
ALPHA1_VERSION = "1.0.0-alpha.1"
ALPHA1_DESCRIPTION = "Layered standard for DAE support in FMI."

#: alpha.1 order of the manifest ModelStructure children.
MODEL_STRUCTURE_ORDER = (
    "Output", "ContinuousStateDerivative", "ClockedState", "InitialUnknown",
    "EventIndicator", "Residual", "Invariant",
)

_ROOTS = {
    "fmiDAEManifest": ALPHA1,
    "fmi-ls-dae": LS_DAE_ROOT,
    "fmi-dae": ATTRIBUTES_ONLY,
}
_SHARED_ROOT = "fmiLayeredStandardManifest"

_OPTION_ALIASES = {
    "alpha.1": ALPHA1, "alpha-1": ALPHA1, "1.0.0-alpha.1": ALPHA1, "a1": ALPHA1,
    "fmi-ls-dae": LS_DAE_ROOT, "ls-dae": LS_DAE_ROOT,
    "fmi-dae": ATTRIBUTES_ONLY, "attributes": ATTRIBUTES_ONLY,
    "flat": FLAT_INDEX,
}

# How many residuals get a hint of their own before the rest are summarised.
_MAX_SPELLED_OUT = 3
# How many value references a summary lists before "and N more".
_MAX_LISTED = 12


# --------------------------------------------------------------------------------------------
# Recognition


def detect_draft(root: etree._Element) -> str:
    """The draft id the manifest ``root`` follows, or :data:`UNKNOWN`."""
    qname = etree.QName(root)
    if qname.namespace not in (None, LS_NAMESPACE):
        return UNKNOWN
    if qname.localname in _ROOTS:
        return _ROOTS[qname.localname]
    if qname.localname != _SHARED_ROOT:
        return UNKNOWN
    residuals = _residuals(root)
    if any(_children(r, "Formulation") for r in residuals):
        return FORMULATION
    if residuals:
        return FLAT_INDEX
    return FORMULATION


def parse_draft_option(text: str) -> str:
    """Parse ``--draft``: ``auto`` or a draft id (a few spellings accepted), else ``ValueError``."""
    key = text.strip().lower().replace("_", "-")
    if key == AUTO or key in ALL_DRAFTS:
        return key
    if key in _OPTION_ALIASES:
        return _OPTION_ALIASES[key]
    raise ValueError(f"unknown draft {text!r}; use one of: {', '.join((AUTO,) + ALL_DRAFTS)}")


# --------------------------------------------------------------------------------------------
# Violations


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
    written = _written_name(root)
    higher = [r.sourceline for r in _residuals(root) if len(_children(r, "Formulation")) > 1]
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
    )


def unrecognised_violations(root: etree._Element, *, file: str) -> Iterator[Violation]:
    """One ``draft-unrecognised`` violation when the root is none of the known shapes."""
    if detect_draft(root) != UNKNOWN:
        return
    written = _written_name(root)
    namespace = etree.QName(root).namespace
    where = f" in the namespace {namespace}" if namespace else " in no namespace"
    message = (
        f"the manifest root <{written}>{where} is none of the known fmi-ls-dae shapes; "
        f"fmi-ls-dae {ALPHA1_VERSION} expects <fmiDAEManifest> in no namespace, with the "
        "fmi-ls: attributes in the namespace " + LS_NAMESPACE
    )
    yield Violation(
        message=message,
        location=Location(file=file, line=root.sourceline, path="/" + written),
        evidence=evidence(
            root=written,
            namespace=namespace,
            known_roots=("fmiDAEManifest", _SHARED_ROOT, "fmi-ls-dae", "fmi-dae"),
        ),
        subject=written,
        rule="draft-unrecognised",
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
    written = _written_name(root)
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
        descendants = [e for e in _elements(root) if e is not root]
        prefixed = [e for e in descendants if e.prefix and etree.QName(e).namespace == namespace]
        if prefixed and len(prefixed) == len(descendants):
            hint += f", and drop the `{root.prefix}:` prefix from every child element"
        elif prefixed:
            names = sorted({_written_name(e) for e in prefixed})
            hint += f", and drop the `{root.prefix}:` prefix from " + ", ".join(f"`<{n}>`" for n in names)
    return hint


def _enable_hint(root: etree._Element) -> str | None:
    parameter = _children(root, "EnableDAEParameter")
    legacy = _children(root, "EnableDAE")
    attribute = root.get("enableDAEModeVariable")
    parts: list[str] = []
    if legacy:
        element = legacy[0]
        vr = element.get("valueReference", "…")
        rename = (
            f"rename `<{_written_name(element)}>` to `<EnableDAEParameter>` "
            f"(`<EnableDAEParameter valueReference=\"{vr}\"/>`)"
        )
        first = _first_child(root)
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
        for block in _children(root, "AlgebraicVariables")
        for v in _children(block, "AlgebraicVariable")
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
    for residual in _residuals(root):
        formulations = _children(residual, "Formulation")
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
    indexed = [r for r in _residuals(root) if r.get("index") is not None]
    if not indexed:
        return None
    vrs = _listing([r.get("valueReference", "?") for r in indexed])
    return f"drop `index` from `<Residual>` (value references {vrs})"


def _order_hint(root: etree._Element) -> str | None:
    kinds = [
        etree.QName(child).localname
        for structure in _children(root, "ModelStructure")
        for child in _element_children(structure)
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


def _element_children(element: etree._Element) -> list[etree._Element]:
    return [c for c in element if isinstance(c.tag, str)]


def _children(element: etree._Element, local: str) -> list[etree._Element]:
    return [c for c in _element_children(element) if etree.QName(c).localname == local]


def _first_child(element: etree._Element) -> etree._Element | None:
    children = _element_children(element)
    return children[0] if children else None


def _elements(root: etree._Element) -> Iterator[etree._Element]:
    return (e for e in root.iter() if isinstance(e.tag, str))


def _residuals(root: etree._Element) -> list[etree._Element]:
    return [r for s in _children(root, "ModelStructure") for r in _children(s, "Residual")]


def _written_name(element: etree._Element) -> str:
    local = etree.QName(element).localname
    return f"{element.prefix}:{local}" if element.prefix else local


def _listing(items: Sequence[str]) -> str:
    if len(items) <= _MAX_LISTED:
        return ", ".join(items)
    return ", ".join(items[:_MAX_LISTED]) + f" and {len(items) - _MAX_LISTED} more"


def _is_true(value: str | None) -> bool:
    return value is not None and value.strip() in ("true", "1")
