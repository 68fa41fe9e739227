"""conformance/model/unknowns.py: dependency tokens that are not value references, as a finding
shows them (clipped to 40 characters)."""
from __future__ import annotations

from lxml import etree

from conformance.model.unknowns import parse_unknown, read_structure


def test_bad_dependency_tokens_are_kept_and_clipped_at_40_characters():
    forty, forty_one = "x" * 40, "y" * 41
    ms = etree.fromstring(f'<ModelStructure><Output valueReference="1" '
                          f'dependencies="2 {forty} 4294967296 {forty_one} 3"/></ModelStructure>')
    (u,) = read_structure(ms, "f.xml", "/m/ModelStructure/{}[{}]")
    assert u.dependencies == (2, 3)
    assert u.bad_tokens == (forty, "4294967296", "y" * 37 + "...")
    assert parse_unknown(ms[0], "Output", "f.xml", "/p").bad_tokens == u.bad_tokens
