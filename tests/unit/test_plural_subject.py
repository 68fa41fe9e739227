"""Grouped findings read as English: the verb after a plural subject agrees with it."""
from __future__ import annotations

import pytest

from conformance.run.collector import plural_subject

GROUP = "4 items ('a', 'b', 'c', 'd')"


@pytest.mark.parametrize("template, expected", [
    ("{subject} is declared twice", f"{GROUP} are declared twice"),
    ("<Output> {subject} names no variable", f"<Output> {GROUP} name no variable"),
    ("{subject} has no start value", f"{GROUP} have no start value"),
    ("{subject} depends on 'u'", f"{GROUP} depend on 'u'"),
    ("reused by {subject}; give each its own", f"reused by {GROUP}; give each its own"),
    ("{subject} cannot be read", f"{GROUP} cannot be read"),
])
def test_verb_agrees_with_a_group(template, expected):
    assert plural_subject(template, GROUP) == expected
