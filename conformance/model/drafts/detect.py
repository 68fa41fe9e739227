"""Which fmi-ls-dae draft a manifest follows: draft ids, labels, the namespace, recognition.

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

A root that is none of the known shapes gives ``draft-unrecognised``; what a legacy shape must
change is :mod:`conformance.model.drafts.migrate`'s business.
"""
from __future__ import annotations

from typing import Iterator

from lxml import etree

from ...report.findings import Location, Violation, evidence
from .elements import children_named, residual_elements, written_name
from .names import (  # noqa: F401  (re-exported: the draft names belong with recognition)
    ALL_DRAFTS, ALPHA1, ALPHA1_DESCRIPTION, ALPHA1_NAME, ALPHA1_VERSION, ATTRIBUTES_ONLY, AUTO,
    DRAFT_LABELS, FLAT_INDEX, FORMULATION, LEGACY_DRAFTS, LS_DAE_ROOT, LS_NAMESPACE, UNKNOWN,
    parse_draft_option,
)

_ROOTS = {
    "fmiDAEManifest": ALPHA1,
    "fmi-ls-dae": LS_DAE_ROOT,
    "fmi-dae": ATTRIBUTES_ONLY,
}
_SHARED_ROOT = "fmiLayeredStandardManifest"


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
    residuals = residual_elements(root)
    if any(children_named(r, "Formulation") for r in residuals):
        return FORMULATION
    if residuals:
        return FLAT_INDEX
    return FORMULATION


def unrecognised_violations(root: etree._Element, *, file: str) -> Iterator[Violation]:
    """One ``draft-unrecognised`` violation when the root is none of the known shapes."""
    if detect_draft(root) != UNKNOWN:
        return
    written = written_name(root)
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
