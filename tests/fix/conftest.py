from __future__ import annotations

from pathlib import Path

from conformance.run.engine import EngineOptions, check_fmu
from conformance.fixes.fixers import FIXERS

STATIC = EngineOptions(probes=False)
FIXABLE = sorted({code for codes, _ in FIXERS.values() for code in codes})


def codes(path: Path) -> set[str]:
    return {f.code for f in check_fmu(path, options=STATIC).findings}
