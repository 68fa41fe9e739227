"""What every report must satisfy, whatever the input: text a reader can take as it is."""
from __future__ import annotations

import re

from conformance.report.findings import FmuReport, Severity

#: A template field left in text: ``{subject}``, ``{name}``, ``{0}``.
PLACEHOLDER = re.compile(r"\{[A-Za-z_0-9]*\}")


def raw_placeholders(fmu: FmuReport) -> list[str]:
    """Every finding message, every string in a finding's evidence (at any depth) and every
    reason of a rule not run that still shows a template field, as ``CODE: text`` (an empty
    list when the report reads well)."""
    texts = [(f.code, f.message) for f in fmu.findings]
    texts += [(f.code, text) for f in fmu.findings for text in _strings(f.evidence)]
    texts += list(fmu.rules_skipped) + list(fmu.rules_not_run)
    return [f"{code}: {text}" for code, text in texts if PLACEHOLDER.search(text)]


def _strings(value: object) -> list[str]:
    """The strings in an evidence value: tuples of pairs, lists and plain values."""
    if isinstance(value, str):
        return [value]
    if isinstance(value, (tuple, list)):
        return [s for item in value for s in _strings(item)]
    return []


def errors_and_warnings(fmu: FmuReport) -> dict[str, list]:
    """The findings of an error or warning, by rule code (what a verdict counts)."""
    out: dict[str, list] = {}
    for f in fmu.findings:
        if f.severity >= Severity.WARNING:
            out.setdefault(f.code, []).append(f)
    return out
