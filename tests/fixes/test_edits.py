"""The edit engine and the start-tag reader: byte ranges on the original, overlaps refused."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from conformance.fixes.edits import Edit, EditConflict, apply_edits
from conformance.fixes.xmltext import ascii_compatible, element_tree, escape, root_start_tag


def test_edits_apply_in_offset_order_whatever_order_given():
    data = b"0123456789"
    edits = [Edit("f", 8, 9, b"X"), Edit("f", 0, 0, b"<"), Edit("f", 3, 5, b"")]
    assert apply_edits(data, edits) == b"<01256789".replace(b"8", b"X")


@pytest.mark.parametrize("a,b", [((2, 5), (4, 6)), ((3, 3), (3, 3)), ((3, 3), (3, 4)),
                                 ((0, 10), (4, 4))])
def test_overlapping_edits_are_refused(a, b):
    with pytest.raises(EditConflict):
        apply_edits(b"0123456789", [Edit("f", *a, b"x"), Edit("f", *b, b"y")])


def test_adjacent_edits_are_not_overlapping():
    assert apply_edits(b"abcd", [Edit("f", 0, 2, b"X"), Edit("f", 2, 4, b"Y")]) == b"XY"


def test_an_edit_beyond_the_end_is_refused():
    with pytest.raises(ValueError):
        apply_edits(b"abc", [Edit("f", 2, 9, b"")])


@given(st.binary(max_size=40), st.data())
def test_untouched_bytes_stay_where_they_were(data, draw):
    cut = draw.draw(st.integers(0, len(data)))
    end = draw.draw(st.integers(cut, len(data)))
    out = apply_edits(data, [Edit("f", cut, end, b"NEW")])
    assert out[:cut] == data[:cut] and out[cut + 3:] == data[end:]


def test_root_start_tag_skips_the_prolog_and_reads_attributes_in_place():
    data = (b'\xef\xbb\xbf<?xml version="1.0"?>\n<!-- a <comment> -->\n<!DOCTYPE x>\n'
            b"<root a='1'\n  b:c=\"two\" >\n<child/></root>")
    tag = root_start_tag(data)
    assert tag is not None and tag.name == "root"
    assert [a.name for a in tag.attributes] == ["a", "b:c"]
    b = tag.attribute("b:c")
    assert data[b.value_start:b.value_end] == b"two"
    assert data[tag.close:tag.close + 1] == b">"


def test_root_start_tag_gives_up_on_wide_encodings():
    assert root_start_tag('<root a="1"/>'.encode("utf-16")) is None


@pytest.mark.parametrize("data", [b"<a><b/>", b"<a><b></a>", b"<a/><b/>", b"text only"])
def test_element_tree_gives_up_on_what_it_cannot_read_exactly(data):
    assert element_tree(data) is None


def test_element_tree_spans():
    data = b'<?xml version="1.0"?>\n<a x="1">\n  <b/>\n  <!-- <c> -->\n  <d>t</d>\n</a>\n'
    root = element_tree(data)
    assert [c.name for c in root.children] == ["b", "d"]
    b, d = root.children
    assert data[b.tag.start:b.end] == b"<b/>" and b.end_tag_start is None
    assert data[d.tag.start:d.end] == b"<d>t</d>" and data[d.end_tag_start:d.end] == b"</d>"
    assert data[root.end_tag_start:root.end] == b"</a>"


def test_escape_for_the_quote_the_value_sits_in():
    assert escape("a&b<c\"d'e") == b"a&amp;b&lt;c&quot;d'e"
    assert escape("a&b<c\"d'e", b'"') == b"a&amp;b&lt;c&quot;d'e"
    assert escape("a&b<c\"d'e", b"'") == b"a&amp;b&lt;c\"d&apos;e"


def test_a_wide_encoding_is_recognised_by_a_nul_in_the_first_200_bytes():
    assert not ascii_compatible(b"<" + b" " * 198 + b"\x00")      # byte 199
    assert ascii_compatible(b"<" + b" " * 199 + b"\x00")          # byte 200: not looked at
    assert not ascii_compatible(b"\xff\xfe<\x00") and not ascii_compatible(b"\xfe\xff\x00<")
