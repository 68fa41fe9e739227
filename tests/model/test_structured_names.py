"""The structured-name grammar (conformance/model/structured_names.py, FMI 3.0.2 §2.4.7.5.1)."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conformance.model.structured_names import all_structured, is_structured_name, name_problem

# The examples the standard gives, plus one of each construct.
LEGAL = [
    "vehicle.engine.speed", "resistor12.u", "v_min", "robot.axis.'motor #234'",
    "der(pipe[3,4].T[14],2)", "der(x)", "der(a.b[1])", "x", "_", "_0", "a[1]", "a[01,2].b[3]",
    "'a'", "'\\''", "'\\\"\\?\\\\\\a\\b\\f\\n\\r\\t\\v'", "'x y'", "'2nd'.stage",
    "'[]{}().,;:'", "der", "der.x", "derx",
]

# (name, index where it leaves the grammar)
ILLEGAL = [
    ("", 0), ("2g", 0), ("a.", 2), (".a", 0), ("a..b", 2), ("a b", 1), ("a[]", 2), ("a[1,]", 4),
    ("a[1", 3), ("a[x]", 2), ("der(x", 5), ("der()", 4), ("der(x,)", 6), ("der(x,2", 7),
    ("der(x).y", 6), ("''", 1), ("'abc", 4), ("'a\\q'", 2), ("'a\\", 2), ("a'b'", 1),
    ("é", 0), ("'é'", 1), ("a`", 1), ("'a\"b'", 2), ("'a'b'", 3), ("a\tb", 1), ("x(1)", 1),
    ("der(x)(", 6), ("a[1]]", 4), ("a-b", 1),
]


@pytest.mark.parametrize("name", LEGAL)
def test_legal_names(name):
    assert is_structured_name(name)
    assert name_problem(name) is None


@pytest.mark.parametrize("name,index", ILLEGAL)
def test_illegal_names_say_where(name, index):
    assert not is_structured_name(name)
    problem = name_problem(name)
    assert problem is not None and problem.index == index


@pytest.mark.parametrize("name, expected", [
    ("a b", "'.', '[' or the end of the name"),
    ("'a\\q'", "an escape sequence: \\' \\\" \\? \\\\ \\a \\b \\f \\n \\r \\t \\v"),
    ("2g", "a letter or '_' starting a name part, or a quoted name '...'"),
    ("der(x", "'.', '[', ',' and an order, or ')' closing der("),
    ("''", "at least one character between the quotes"),
])
def test_illegal_names_say_what_was_expected(name, expected):
    # the expectation is the text the structured-name finding shows
    assert name_problem(name).expected == expected


# Text built mostly from the characters the grammar cares about, so that random strings land
# near the boundary between legal and illegal.
_ALPHABET = st.sampled_from(list("ab_Z09.[],()'\\ \"?ntder#`é\t") + ["der(", "'a'", "[1]"])
_TEXT = st.lists(_ALPHABET, max_size=14).map("".join)


@settings(max_examples=1500, derandomize=True, deadline=None)
@given(_TEXT)
def test_regular_expression_and_walker_agree(name):
    assert is_structured_name(name) == (name_problem(name) is None)


_PLAIN = st.from_regex(r"[_a-zA-Z][_a-zA-Z0-9]{0,5}", fullmatch=True)
_QUOTED = st.lists(st.one_of(st.sampled_from(list("aZ09!#$%&()*+,-./:;<>=?@[]^{}|~ ")),
                             st.sampled_from(["\\'", '\\"', "\\?", "\\\\", "\\a", "\\n", "\\v"])),
                   min_size=1, max_size=5).map(lambda cs: "'" + "".join(cs) + "'")
_INDICES = st.lists(st.integers(0, 999), min_size=1, max_size=3).map(
    lambda ns: "[" + ",".join(map(str, ns)) + "]")
_PART = st.tuples(st.one_of(_PLAIN, _QUOTED), st.one_of(st.just(""), _INDICES)).map("".join)
_IDENTIFIER = st.lists(_PART, min_size=1, max_size=4).map(".".join)
_NAME = st.one_of(_IDENTIFIER, _IDENTIFIER.map(lambda i: f"der({i})"),
                  st.tuples(_IDENTIFIER, st.integers(1, 9)).map(lambda t: f"der({t[0]},{t[1]})"))


@settings(max_examples=500, derandomize=True, deadline=None)
@given(_NAME)
def test_names_built_from_the_grammar_are_legal(name):
    assert is_structured_name(name), name
    assert name_problem(name) is None


@pytest.mark.parametrize("name", [
    "a" * 20_000 + "!", "a." * 10_000 + "!", "'" + "a" * 20_000, "a[" + "1," * 10_000 + "x]",
    "der(" + "a." * 10_000 + "a,", "'" + "\\'" * 10_000,
])
def test_long_illegal_names_are_decided(name):
    # A regular expression that backtracked exponentially would hang here.
    assert not is_structured_name(name)
    assert name_problem(name) is not None


@settings(max_examples=500, derandomize=True, deadline=None)
@given(st.lists(st.one_of(_TEXT, _NAME), max_size=6))
def test_all_structured_agrees_with_each_name(names):
    # all_structured matches each shape once (digits written as 0, names joined by NUL)
    assert all_structured(names) == all(map(is_structured_name, names))
    assert all_structured(iter(names)) == all(map(is_structured_name, names))


@pytest.mark.parametrize("names, legal", [
    ([], True), (["a1", "b22", "c[3,44]"], True), (["a1", "1a"], False),
    (["x[1]", "x[01]", "der(x[9],7)"], True), (["a", "b\x00c"], False), (["a\x00b"], False),
    (["'2nd'", "'9'"], True), (["a[1]", "a[1x]"], False), ([""], False),
])
def test_all_structured_examples(names, legal):
    assert all_structured(names) is legal
