"""Suite-wide options: ``--fuzz N`` scales the mutation test (``make fuzz``)."""
from __future__ import annotations

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--fuzz", type=int, default=0, metavar="N",
                     help="run the mutation test with N times its examples and a random seed")


@pytest.fixture
def fuzz(request: pytest.FixtureRequest) -> int:
    return int(request.config.getoption("--fuzz"))
