"""The edit engine and the start-tag reader: byte ranges on the original, overlaps refused."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from conformance.fixes.edits import Edit, EditConflict, apply_edits
from conformance.fixes.xmltext import root_start_tag


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
