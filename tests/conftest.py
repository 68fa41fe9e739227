"""Suite-wide options and fixtures.

``--fuzz N`` scales the mutation test (``make fuzz``). The fixtures hand out what
:mod:`tests.fixtures` builds: small FMU folders (``fmu``), the scene FMUs of the fleet tests
(``scene_fmus``) and every rule case as an FMU (``fixture_fmus``). Under pytest-xdist the
workers share the reports of :func:`tests.checkkit.checked` through the session's folder.
"""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests import checkkit
from tests.fixtures import all_cases, build_scene, make_fmu, materialise

#: Scenes with binaries (checked with --no-probes but for the probe case) of different sizes.
FLEET_SCENES = ("HelloWorldDAE", "SimpleDAE", "VanDerPolDAE", "Robertson", "FourBar")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--fuzz", type=int, default=0, metavar="N",
                     help="run the mutation test with N times its examples and a random seed")


@pytest.fixture(scope="session", autouse=True)
def _shared_reports(tmp_path_factory: pytest.TempPathFactory) -> None:
    """The session's folder for the reports of ``checkkit.checked``; under pytest-xdist each
    worker's basetemp is a folder of the session's, whose parent both workers share."""
    base = tmp_path_factory.getbasetemp()
    checkkit.SHARED = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "checked"


@pytest.fixture
def fuzz(request: pytest.FixtureRequest) -> int:
    return int(request.config.getoption("--fuzz"))


@pytest.fixture
def fmu(tmp_path):
    """``fmu(name, **kw)`` -> the path of a fresh FMU folder under tmp_path."""
    def factory(name: str, **kw) -> Path:
        return make_fmu(tmp_path / name, **kw)
    return factory


@pytest.fixture(scope="session")
def scene_fmus() -> list[str]:
    return [str(build_scene(name)) for name in FLEET_SCENES]


@pytest.fixture(scope="session")
def fixture_fmus(tmp_path_factory) -> list[str]:
    """Every rule fixture, failing and passing, as an FMU folder or .fmu file."""
    root = tmp_path_factory.mktemp("fixtures")
    return [str(materialise(case, root / case.id.replace("/", "_"))) for case in all_cases()]
