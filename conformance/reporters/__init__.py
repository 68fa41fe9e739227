"""Reporters: one module per output format, each ``render(report, catalogue, **kw) -> str``.

Reporters see only the frozen :class:`~conformance.findings.Report` and the catalogue, never the
engine. ``REPORTER_BY_NAME`` is the one place formats are registered.
"""
from __future__ import annotations

from typing import Callable

from . import console, json_report

Reporter = Callable[..., str]

REPORTER_BY_NAME: dict[str, Reporter] = {
    "console": console.render,
    "json": json_report.render,
}
