"""What every report must satisfy, whatever the input: text a reader can take as it is."""
from __future__ import annotations

import re

from conformance.report.findings import FmuReport

#: A template field left in text: ``{subject}``, ``{name}``, ``{0}``.
PLACEHOLDER = re.compile(r"\{[A-Za-z_0-9]*\}")


def raw_placeholders(fmu: FmuReport) -> list[str]:
    """Every finding message and every reason of a rule not run that still shows a template
    field, as ``CODE: text`` (an empty list when the report reads well)."""
    texts = [(f.code, f.message) for f in fmu.findings]
    texts += list(fmu.rules_skipped) + list(fmu.rules_not_run)
    return [f"{code}: {text}" for code, text in texts if PLACEHOLDER.search(text)]
