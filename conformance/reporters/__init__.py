"""Reporters: one module per output format, each ``render(report, catalogue, **kw) -> str``.

Reporters see only the frozen :class:`~conformance.report.findings.Report`, the catalogue and the
:class:`~conformance.report.findings.RunInfo`, never the engine. ``REPORTER_BY_NAME`` is the one place
formats are registered; docs/formats.md describes them.

A format's module is imported when its renderer is first looked up, so a run that writes JSON
does not load the HTML, SARIF and JUnit writers (and ``lsdae --version`` none of them).
"""
from __future__ import annotations

import importlib
from typing import Callable, Iterator, MutableMapping

Reporter = Callable[..., str]

#: format name -> the module (in this package) whose ``render`` writes it, in the order of --help.
FORMAT_MODULES: dict[str, str] = {
    "console": "console",
    "json": "json_report",
    "junit": "junit",
    "sarif": "sarif",
    "github": "github",
    "markdown": "markdown",
    "html": "html",
}
FORMATS: tuple[str, ...] = tuple(FORMAT_MODULES)


class _Registry(MutableMapping[str, Reporter]):
    """The renderers by format name, each module imported on first use (tests may replace one)."""

    def __init__(self) -> None:
        self._loaded: dict[str, Reporter] = {}

    def __getitem__(self, name: str) -> Reporter:
        if name not in self._loaded:
            if name not in FORMAT_MODULES:
                raise KeyError(name)
            module = importlib.import_module(f"{__name__}.{FORMAT_MODULES[name]}")
            self._loaded[name] = module.render
        return self._loaded[name]

    def __setitem__(self, name: str, render: Reporter) -> None:
        if name not in FORMAT_MODULES:
            raise KeyError(f"{name!r} is not a registered format")
        self._loaded[name] = render

    def __delitem__(self, name: str) -> None:
        self._loaded.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(FORMATS)

    def __len__(self) -> int:
        return len(FORMATS)

    def __contains__(self, name: object) -> bool:
        return name in FORMAT_MODULES


REPORTER_BY_NAME: MutableMapping[str, Reporter] = _Registry()
