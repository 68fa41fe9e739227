"""Defect variants for the derivative probes (Jacobians, dependencies, dependenciesKind...).

Each entry must trigger exactly its rule (plus ``also``); see tests/probes/test_defects.py.
"""
from __future__ import annotations

from tests.probes.variants import Defect

DEFECTS: list[Defect] = []
