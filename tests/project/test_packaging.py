"""The wheel ships every subpackage, the rule catalogue and our XSDs, and nothing else."""
from __future__ import annotations

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]


def test_every_subpackage_is_listed_for_the_wheel():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "conformance").rglob("__init__.py")}
    assert found - listed == set(), "add these to [tool.setuptools] packages"
    assert config["package-dir"] == {"conformance._rules": "rules",
                                     "conformance._schemas": "schemas"}
    data = config["package-data"]
    assert "*.toml" in data["conformance._rules"] and "*.xsd" in data["conformance._schemas"]


def test_development_packages_are_not_shipped():
    """scenes/ (the C test FMUs and their builder), tests/, bench/ and scripts/ stay out."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "find" not in config.get("packages", {}), "an explicit list keeps scenes/ out"
    outside = [p for p in config["packages"] if p.split(".")[0] != "conformance"]
    assert outside == [], "only conformance.* belongs in the wheel"
    assert (ROOT / "scenes" / "build.py").is_file()
