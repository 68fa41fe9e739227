"""The one-loop readers of large documents read what a plain reading of each element reads.

``unknowns.read_structure``, ``model._variables`` and ``manifest._refs`` are shaped for speed
(issue 11): one loop, a kind looked up once per run of siblings, a variable's attributes in two
calls through a getter per attribute list. Each is compared here with a plain reading, element by
element and attribute by attribute, on generated documents with comments, namespaced tags and
attributes, interleaved kinds, odd tokens and legacy children.
"""
from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st
from lxml import etree

from conformance.model.manifest import _ref, _refs
from conformance.model.description import _details, _effective, _variables
from conformance.model.parts import NO_DETAILS
from conformance.model.unknowns import parse_unknown, parse_vr, read_structure

NS = "urn:x"
KINDS = ["Output", "ContinuousStateDerivative", "InitialUnknown", "Residual", f"{{{NS}}}Output"]
TOKENS = st.sampled_from(["0", "1", "17", "4294967295", "4294967296", "0000000001", "-1", "+2",
                          "1_0", "x", "²", "123456789", "1234567890", ""])
WORDS = st.sampled_from(["constant", "fixed", "tunable", "discrete", "dependent", "bogus"])
NUMBERISH = st.sampled_from(["1", "42", "007", " 3", "-1", "x", "99999999999", "4294967295"])


def _attr(name: str, value: str | None) -> str:
    return "" if value is None else f' {name}="{value}"'


@st.composite
def structure_xml(draw) -> str:
    parts = []
    for _ in range(draw(st.integers(0, 12))):
        if draw(st.booleans()) and draw(st.booleans()):
            parts.append("<!-- a comment -->")
        tag = draw(st.sampled_from(KINDS))
        deps = draw(st.none() | st.lists(TOKENS, max_size=4).map(" ".join))
        kinds = draw(st.none() | st.lists(WORDS, max_size=4).map(" ".join))
        attrs = (_attr("valueReference", draw(st.none() | NUMBERISH)) + _attr("dependencies", deps)
                 + _attr("dependenciesKind", kinds)
                 + _attr("index", draw(st.none() | st.just("2"))))
        children = "<Formulation dependencies='1 2'/>" if draw(st.booleans()) else ""
        name = tag.replace(f"{{{NS}}}", "x:")
        parts.append(f"<{name}{attrs}>{children}</{name}>")
    return f'<ModelStructure xmlns:x="{NS}">{"".join(parts)}</ModelStructure>'


def _plain_structure(ms: etree._Element, where: str) -> list:
    counts: dict[str, int] = {}
    shared: dict = {}
    out = []
    for el in ms:
        if not isinstance(el.tag, str):
            continue
        kind = etree.QName(el).localname
        counts[kind] = counts.get(kind, 0) + 1
        out.append(parse_unknown(el, kind, "f.xml", where, counts[kind], shared=shared))
    return out


@settings(max_examples=300, deadline=None)
@given(structure_xml())
def test_read_structure_reads_each_element_as_parse_unknown_does(xml):
    ms = etree.fromstring(xml)
    where = "/m/ModelStructure/{}[{}]"
    got = read_structure(ms, "f.xml", where)
    assert got == _plain_structure(ms, where)
    assert [u.path for u in got] == [u.path for u in _plain_structure(ms, where)]


VARIABLE_TAGS = ["Float64", "Int32", "Boolean", "String", "Float32", "Clock", f"{{{NS}}}Float64",
                 "NotAType"]
OPTIONAL = {
    "causality": st.sampled_from(["local", "output", "input", "parameter", "independent", "x"]),
    "variability": st.sampled_from(["continuous", "discrete", "fixed", "tunable", "constant"]),
    "initial": st.sampled_from(["exact", "approx", "calculated"]),
    "valueReference": NUMBERISH,
    "start": st.sampled_from(["0", "1", "0.5", "false"]),
    "derivative": NUMBERISH,
    "description": st.just("d"),
    "unit": st.just("m"),
    "nominal": st.just("2"),
    "x:extra": st.just("e"),
}


@st.composite
def variables_xml(draw) -> str:
    parts = []
    for i in range(draw(st.integers(0, 10))):
        if draw(st.booleans()) and draw(st.booleans()):
            parts.append("<!-- c -->")
        tag = draw(st.sampled_from(VARIABLE_TAGS)).replace(f"{{{NS}}}", "x:")
        names = draw(st.permutations(list(OPTIONAL)))
        chosen = [n for n in names if draw(st.booleans())]
        attrs = _attr("name", draw(st.none() | st.just(f"v{i}")))
        attrs += "".join(_attr(n, draw(OPTIONAL[n])) for n in chosen)
        children = "<Dimension start='2'/>" if draw(st.booleans()) and draw(st.booleans()) else ""
        parts.append(f"<{tag}{attrs}>{children}</{tag}>")
    return f'<ModelVariables xmlns:x="{NS}">{"".join(parts)}</ModelVariables>'


def _plain_variables(container: etree._Element) -> list:
    """Each variable read attribute by attribute, as the reader did before its one loop."""
    from conformance.model.parts import VARIABLE_TYPES, Variable

    out, kinds, shared = [], {}, {}
    for el in container:
        if not isinstance(el.tag, str) or etree.QName(el).localname not in VARIABLE_TYPES:
            continue
        get = el.get
        key = (etree.QName(el).localname, get("causality"), get("variability"), get("initial"))
        type_, causality, declared_var, declared_init, variability, initial = _effective(
            kinds, key)
        raw_vr = get("valueReference")
        vr = parse_vr(raw_vr)
        raw_vr = raw_vr if vr is None else None
        start, details = get("start"), NO_DETAILS
        read = ("name", "valueReference", "start", "derivative", "description", "causality",
                "variability", "initial")
        if len(el) or raw_vr is not None or any(k not in read for k in el.keys()):
            start, details = _details(el, start, raw_vr, shared)
        derivative = get("derivative")
        out.append(Variable(get("name") or "", vr, type_, causality, variability, initial,
                            declared_var, declared_init, start,
                            parse_vr(derivative) if derivative is not None else None,
                            el.sourceline, get("description"), details))
    return out


@settings(max_examples=300, deadline=None)
@given(variables_xml())
def test_variables_read_in_one_loop_as_attribute_by_attribute(xml):
    container = etree.fromstring(xml)
    assert _variables(container) == _plain_variables(container)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["AlgebraicVariable", "x:AlgebraicVariable"]),
                          st.none() | NUMBERISH, st.booleans(), st.booleans()), max_size=8))
def test_algebraic_list_read_in_one_loop_as_element_by_element(entries):
    xml = "".join(
        ("<!-- c -->" if comment else "")
        + f"<{tag}{_attr('valueReference', vr)}{_attr('name', 'w' if named else None)}/>"
        for tag, vr, named, comment in entries)
    container = etree.fromstring(f'<AlgebraicVariables xmlns:x="{NS}">{xml}</AlgebraicVariables>')
    where = "/r/AlgebraicVariables/{}[{}]"
    names: dict[str, str] = {}
    plain = [_ref(el, where, i, names)
             for i, el in enumerate((c for c in container if isinstance(c.tag, str)), 1)]
    assert _refs(container, where) == plain
