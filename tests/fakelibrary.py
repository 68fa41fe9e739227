"""A stand-in for ``conformance.runtime.library.Library`` over a pure-Python fake binary, and
SimpleDAE's XML, for tests that drive real ``Instance`` objects without loading a binary
(tests/probes/test_first_cause.py, tests/runtime/test_state_machine.py)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from lxml import etree

from conformance.runtime.layout import Layout
from tests.fixtures import SCENES_DIR


@dataclass
class FakeLibrary:
    """What an ``Instance`` asks of its library: the layout, the fake binary, names, logging."""

    layout: Layout
    fmu: Any
    resource_path: None = None
    instances: list = field(default_factory=list)
    fatal: bool = False
    log: list = field(default_factory=list)
    count: int = 0

    def logger(self, name: str) -> Callable[..., None]:
        return lambda env, status, category, message: None

    def next_name(self, mode: str) -> str:
        self.count += 1
        return f"fake-{mode}-{self.count}"

    def fmu_for_instance(self) -> Any:
        return self.fmu


def simple_dae_xml(name: str, edits: tuple[tuple[str, str], ...] = ()) -> etree._ElementTree:
    """SimpleDAE's ``name`` (modelDescription.xml or fmi-ls-manifest.xml), each (old, new) of
    ``edits`` applied once."""
    text = (SCENES_DIR / "SimpleDAE" / name).read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return etree.ElementTree(etree.fromstring(text.encode()))
