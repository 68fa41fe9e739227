"""The fmi-ls-dae drafts by name: ids, labels, the namespace, the ``--draft`` option.

Plain constants, no XML: the command line and ``lsdae rules`` read them without loading lxml.
How a manifest is recognised as one of them is :mod:`conformance.model.drafts.detect`'s business.
"""
from __future__ import annotations

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

_OPTION_ALIASES = {
    "alpha.1": ALPHA1, "alpha-1": ALPHA1, "1.0.0-alpha.1": ALPHA1, "a1": ALPHA1,
    "fmi-ls-dae": LS_DAE_ROOT, "ls-dae": LS_DAE_ROOT,
    "fmi-dae": ATTRIBUTES_ONLY, "attributes": ATTRIBUTES_ONLY,
    "flat": FLAT_INDEX,
}


def parse_draft_option(text: str) -> str:
    """Parse ``--draft``: ``auto`` or a draft id (a few spellings accepted), else ``ValueError``."""
    key = text.strip().lower().replace("_", "-")
    if key == AUTO or key in ALL_DRAFTS:
        return key
    if key in _OPTION_ALIASES:
        return _OPTION_ALIASES[key]
    raise ValueError(f"unknown draft {text!r}; use one of: {', '.join((AUTO,) + ALL_DRAFTS)}")
