"""What every report must satisfy, whatever the input: text a reader can take as it is."""
from __future__ import annotations

import re

from conformance.report.findings import FmuReport, Severity

#: A template field left in text: ``{subject}``, ``{name}``, ``{0}``.
PLACEHOLDER = re.compile(r"\{[A-Za-z_0-9]*\}")


def raw_placeholders(fmu: FmuReport) -> list[str]:
    """Every finding message and every reason of a rule not run that still shows a template
    field, as ``CODE: text`` (an empty list when the report reads well)."""
    texts = [(f.code, f.message) for f in fmu.findings]
    texts += list(fmu.rules_skipped) + list(fmu.rules_not_run)
    return [f"{code}: {text}" for code, text in texts if PLACEHOLDER.search(text)]


def errors_and_warnings(fmu: FmuReport) -> dict[str, list]:
    """The findings of an error or warning, by rule code (what a verdict counts)."""
    out: dict[str, list] = {}
    for f in fmu.findings:
        if f.severity >= Severity.WARNING:
            out.setdefault(f.code, []).append(f)
    return out
