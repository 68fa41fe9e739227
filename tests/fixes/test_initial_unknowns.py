"""Where added InitialUnknowns go: value-reference order, the neighbour's indentation."""
from __future__ import annotations

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
