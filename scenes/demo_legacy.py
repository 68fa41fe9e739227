"""Write a legacy-shaped copy of HelloWorldDAE for `make demo`, to show draft detection and the
migration hints: the same binary, with the manifest in the Formulation shape (draft-shapes B).

Usage: python -m scenes.demo_legacy DEMO_DIR   (DEMO_DIR holds HelloWorldDAE.fmu)
"""
from __future__ import annotations

import sys
import zipfile
from pathlib import Path

from conformance.model.manifest import MANIFEST

FORMULATION_MANIFEST = """<?xml version="1.0" encoding="UTF-8"?>
<fmiLayeredStandardManifest
  xmlns="http://fmi-standard.org/fmi-ls-manifest"
  xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"
  fmi-ls:fmi-ls-version="0.1"
  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI">
  <EnableDAE valueReference="1"/>
  <AlgebraicVariables>
    <AlgebraicVariable valueReference="4"/>
    <AlgebraicVariable valueReference="5"/>
  </AlgebraicVariables>
  <ModelStructure>
    <ContinuousStateDerivative valueReference="3" dependencies="4"/>
    <Residual>
      <Formulation index="1" valueReference="6" dependencies="2 4 5"/>
    </Residual>
    <Residual>
      <Formulation index="1" valueReference="7" dependencies="2 4 5"/>
    </Residual>
  </ModelStructure>
</fmiLayeredStandardManifest>
"""


def write_legacy(demo: Path) -> Path:
    source = demo / "HelloWorldDAE.fmu"
    target = demo / "HelloWorldDAE-formulation-draft.fmu"
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = FORMULATION_MANIFEST.encode() if item.filename == MANIFEST else zin.read(item)
            zout.writestr(item, data)
    return target


if __name__ == "__main__":
    print(write_legacy(Path(sys.argv[1])))
