"""Static checks, one small module per rule family.

``REGISTRY`` maps a rule code to the function that checks it: explicit, no discovery magic.
Each family module exposes its own ``CHECKS`` dict; the test suite checks that the registry and
the static part of the catalogue match one to one.
"""
from __future__ import annotations

from .context import Check
from . import (
    algebraic,
    attribute_values,
    dae_form,
    enable,
    header,
    index1,
    manifest_dependencies,
    manifest_lists,
    model_names,
    model_references,
    model_structure,
    model_types,
    model_variables,
    residual,
)

REGISTRY: dict[str, Check] = {}
for _module in (header, enable, algebraic, residual, dae_form, manifest_dependencies, manifest_lists,
                model_variables, model_structure, attribute_values, index1, model_types,
                model_names, model_references):
    for _code, _check in _module.CHECKS.items():
        if _code in REGISTRY:  # pragma: no cover - a defect caught by the tests
            raise RuntimeError(f"rule {_code} registered twice")
        REGISTRY[_code] = _check
