"""Where the data shipped with the package lives: the rule catalogue and our XSDs.

In a wheel, ``rules/`` and ``schemas/`` are installed as ``conformance/_rules`` and
``conformance/_schemas`` (see pyproject.toml); in a source checkout they are the top-level
folders beside the package.
"""
from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def _data_dir(installed: str, checkout: str) -> Path:
    inside = _PACKAGE / installed
    if inside.is_dir():
        return inside
    return _PACKAGE.parent / checkout


def rules_dir() -> Path:
    return _data_dir("_rules", "rules")


def schemas_dir() -> Path:
    return _data_dir("_schemas", "schemas")
