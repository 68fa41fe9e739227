"""Shared fixtures: the hand-built sample report and the engine's report on fixture cases."""
from __future__ import annotations

import pytest

from tests.reporters.samples import engine_report


@pytest.fixture(scope="session")
def engine(tmp_path_factory):
    return engine_report(tmp_path_factory.mktemp("engine"))
