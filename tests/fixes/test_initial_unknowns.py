"""Where added InitialUnknowns go: value-reference order, the neighbour's indentation."""
from __future__ import annotations

import pytest

from conformance.fixes.change import NoFix
from conformance.fixes.edits import apply_edits
from conformance.fixes.initial_unknowns import _insertions
from conformance.fixes.xmltext import element_tree

MS = b"""<m>
  <ModelStructure>
    <Output valueReference="1"/>
    <InitialUnknown valueReference="3"/>
    <InitialUnknown valueReference="7"/>
    <EventIndicator valueReference="9"/>
  </ModelStructure>
</m>
"""


def _vrs_in_order(data: bytes) -> list[bytes]:
    return [line.strip() for line in data.splitlines() if b"InitialUnknown" in line]


def test_entries_go_in_value_reference_order_among_the_existing_ones():
    structure = element_tree(MS).named("ModelStructure")[0]
    out = apply_edits(MS, _insertions(MS, structure, [8, 2, 5], "md"))
    assert _vrs_in_order(out) == [f'<InitialUnknown valueReference="{v}"/>'.encode()
                                  for v in (2, 3, 5, 7, 8)]
    assert b'\n    <InitialUnknown valueReference="5"/>\n' in out
    assert element_tree(out) is not None


def test_without_initial_unknowns_they_follow_the_outputs():
    data = MS.replace(b'    <InitialUnknown valueReference="3"/>\n', b"").replace(
        b'    <InitialUnknown valueReference="7"/>\n', b"")
    structure = element_tree(data).named("ModelStructure")[0]
    out = apply_edits(data, _insertions(data, structure, [4, 2], "md"))
    lines = [line.strip() for line in out.splitlines()]
    assert lines[2:6] == [b'<Output valueReference="1"/>', b'<InitialUnknown valueReference="2"/>',
                          b'<InitialUnknown valueReference="4"/>',
                          b'<EventIndicator valueReference="9"/>']


def _added(data: bytes, vrs: list[int]) -> bytes:
    structure = element_tree(data).named("ModelStructure")[0]
    out = apply_edits(data, _insertions(data, structure, vrs, "md"))
    assert element_tree(out) is not None
    return out


def test_an_entry_takes_the_indentation_of_the_element_it_follows():
    data = (b'<m>\n  <ModelStructure>\n      <Output valueReference="1"/>\n'
            b"  </ModelStructure>\n</m>\n")
    assert _added(data, [2]) == data.replace(
        b'<Output valueReference="1"/>',
        b'<Output valueReference="1"/>\n      <InitialUnknown valueReference="2"/>')


def test_value_reference_zero_is_ordered_as_zero():
    data = MS.replace(b'<InitialUnknown valueReference="3"/>',
                      b'<InitialUnknown valueReference="0"/>')
    assert _vrs_in_order(_added(data, [1])) == [
        f'<InitialUnknown valueReference="{v}"/>'.encode() for v in (0, 1, 7)]


def test_without_outputs_the_entries_go_before_the_event_indicators():
    """ModelStructure's order is Output, ContinuousStateDerivative, ClockedState,
    InitialUnknown, EventIndicator: an entry after an EventIndicator breaks the schema."""
    data = (b'<m>\n  <ModelStructure>\n    <EventIndicator valueReference="9"/>\n'
            b"  </ModelStructure>\n</m>\n")
    out = _added(data, [4])
    assert out.index(b'<InitialUnknown valueReference="4"/>') < out.index(b"<EventIndicator")


def test_an_empty_element_model_structure_is_no_fix():
    data = b"<m>\n  <ModelStructure/>\n</m>\n"
    with pytest.raises(NoFix) as raised:
        _added(data, [1])
    assert str(raised.value) == ("<ModelStructure/> is empty-element tag; nothing to add the "
                                 "entries to")
