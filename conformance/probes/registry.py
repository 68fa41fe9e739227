"""Probes by rule code: explicit, no discovery magic (like ``conformance.checks.REGISTRY``).

Each family module exposes its own ``PROBES`` dict; :func:`register` merges it here and refuses
a code registered twice. A new family adds one import and one line at the end of this file; no
family imports another. The runner emits the ``binary-*`` rules itself; they have no function.
"""
from __future__ import annotations

from typing import Mapping

from . import (basic, derivatives, dgdw, endurance, evaluation, event_indicators, handshake,
               importer_paths, initial_unknowns, simulation)
from .api import Probe

PROBES: dict[str, Probe] = {}


def register(family: Mapping[str, Probe]) -> None:
    for code, probe in family.items():
        if code in PROBES:  # pragma: no cover - a defect caught by the tests
            raise RuntimeError(f"probe {code} registered twice")
        PROBES[code] = probe


register(handshake.PROBES)
register(basic.PROBES)
register(evaluation.PROBES)
register(derivatives.PROBES)
register(dgdw.PROBES)
register(simulation.PROBES)
register(importer_paths.PROBES)
register(event_indicators.PROBES)
register(initial_unknowns.PROBES)
register(endurance.PROBES)
