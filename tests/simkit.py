"""Simulation settings for tests: the catalogue's defaults (simulation-failed), some overridden."""
from __future__ import annotations

from typing import Any

from conformance.report.catalogue import default_catalogue
from conformance.numerics.settings import Settings


def sim_settings(**overrides: Any) -> Settings:
    """Settings from the catalogue's ``simulation-failed`` options, ``overrides`` applied."""
    options = dict(default_catalogue()["simulation-failed"].option_values)
    return Settings.from_options({**options, **overrides})
