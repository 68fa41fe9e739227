"""A scene FMU loaded in this process with lsdae's own session (benchmarks only).

The checker always loads binaries in a worker process; the benchmarks load them here so that
what they time is the numerics, not process start-up.
"""
from __future__ import annotations

import shutil
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import read_model_description


class LoadedFmu:
    """The unpacked FMU, its model and manifest, the variable layout and the loaded library."""

    def __init__(self, path: Path, *, prefix: str = "lsdae-bench-"):
        from conformance.runtime.callrecord import CallRecord
        from conformance.runtime.layout import Layout
        from conformance.runtime.library import Library

        self.dir = tempfile.mkdtemp(prefix=prefix)
        with zipfile.ZipFile(path) as zf:
            zf.extractall(self.dir)
        self.model = read_model_description(etree.parse(f"{self.dir}/modelDescription.xml"))
        self.manifest = read_manifest(etree.parse(f"{self.dir}/{MANIFEST}"), draft="alpha1")
        self.layout = Layout.build(self.model, self.manifest)
        self.library = Library(self.dir, self.layout, CallRecord())

    def nominal(self, name: str) -> float:
        vr = next(vr for vr, n in self.layout.names.items() if n == name)
        return float(self.layout.scale(vr))

    def close(self) -> None:
        self.library.free_all()
        shutil.rmtree(self.dir, ignore_errors=True)
