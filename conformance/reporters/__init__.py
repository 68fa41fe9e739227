"""Reporters: one module per output format, each ``render(report, catalogue, **kw) -> str``.

Reporters see only the frozen :class:`~conformance.findings.Report`, the catalogue and the
:class:`~conformance.findings.RunInfo`, never the engine. ``REPORTER_BY_NAME`` is the one place
formats are registered; docs/formats.md describes them.
"""
from __future__ import annotations

from typing import Callable

from . import console, github, html, json_report, junit, markdown, sarif

Reporter = Callable[..., str]

REPORTER_BY_NAME: dict[str, Reporter] = {
    "console": console.render,
    "json": json_report.render,
    "junit": junit.render,
    "sarif": sarif.render,
    "github": github.render,
    "markdown": markdown.render,
    "html": html.render,
}
