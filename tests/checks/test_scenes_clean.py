"""The regular scene FMUs, built with their binaries, pass every static rule with no finding."""
from __future__ import annotations

import pytest

from conformance.run.engine import EngineOptions, check_fmu
from scenes.build import build_scene, scene_names


@pytest.mark.parametrize("name", ["SimpleDAE", "Robertson", "HelloWorldDAE", "EventDAE"])
def test_scene_is_clean(name):
    assert name in scene_names()
    report = check_fmu(build_scene(name), options=EngineOptions(probes=False))
    assert report.draft == "alpha1"
    assert report.findings == (), "\n".join(
        f"{f.severity} {f.code} {f.name}: {f.message}" for f in report.findings)
    static_skips = [(code, reason) for code, reason in report.rules_skipped
                    if not reason.startswith("probes turned off")]
    assert static_skips == []
