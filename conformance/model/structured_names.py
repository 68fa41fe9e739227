"""The FMI 3.0 grammar of variable names under ``variableNamingConvention="structured"``.

FMI 3.0.2 §2.4.7.5.1 (digest MD-06) defines, in EBNF::

    name            = identifier | "der(" identifier [ "," unsignedInteger ] ")"
    identifier      = B-name [ arrayIndices ] { "." B-name [ arrayIndices ] }
    B-name          = nondigit { digit | nondigit } | Q-name
    Q-name          = "'" ( Q-char | escape ) { Q-char | escape } "'"
    Q-char          = nondigit | digit | one of  ! # $ % & ( ) * + , - . / : ; < > = ? @ [ ] ^ { } | ~
                      and the space
    escape          = \\'  \\"  \\?  \\\\  \\a  \\b  \\f  \\n  \\r  \\t  \\v
    arrayIndices    = "[" unsignedInteger { "," unsignedInteger } "]"
    unsignedInteger = digit { digit }
    nondigit        = "_" | "a" ... "z" | "A" ... "Z"

The language is regular, so :func:`is_structured_name` is one compiled regular expression built
from these productions (a model has up to 100,000 names, most of them valid). For a name that does
not match, :func:`name_problem` walks the same productions by hand and says where the name leaves
the grammar and what the grammar expected there. The two are kept in agreement by a property test.
"""
from __future__ import annotations

import re
from collections.abc import Iterable
from typing import NamedTuple

_NONDIGIT = frozenset("_abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ")
_DIGIT = frozenset("0123456789")
_Q_CHAR = _NONDIGIT | _DIGIT | frozenset("!#$%&()*+,-./:;<>=?@[]^{}|~ ")
_ESCAPED = frozenset("'\"?\\abfnrtv")   # the character after the backslash of an escape


def _char_class(chars: frozenset[str]) -> str:
    return "[" + "".join(re.escape(c) for c in sorted(chars)) + "]"


# der( is tried first: most names do not start with it, and those that do then match at once.
# Plain quantifiers (Python 3.10 has no possessive ones); no repetition here can end in a
# character that what follows could start with, so a failing name backtracks little.
_UINT_RE = "[0-9]+"
_Q_NAME_RE = f"'(?:{_char_class(_Q_CHAR)}|\\\\{_char_class(_ESCAPED)})+'"
_B_NAME_RE = f"(?:[_a-zA-Z][_a-zA-Z0-9]*|{_Q_NAME_RE})"
_PART_RE = f"{_B_NAME_RE}(?:\\[{_UINT_RE}(?:,{_UINT_RE})*\\])?"
_IDENTIFIER_RE = f"{_PART_RE}(?:\\.{_PART_RE})*"
_NAME = re.compile(f"der\\({_IDENTIFIER_RE}(?:,{_UINT_RE})?\\)|{_IDENTIFIER_RE}")


def is_structured_name(name: str) -> bool:
    """Whether ``name`` is a legal name under the structured naming convention."""
    return _NAME.fullmatch(name) is not None


# Every character class of the grammar holds all ten digits or none, and no literal is a digit:
# writing each digit as 0 keeps a legal name legal and an illegal one illegal.
_DIGITS_AS_ZERO = str.maketrans("123456789", "000000000")


def all_structured(names: Iterable[str]) -> bool:
    """Whether every name is legal. The names of a model (x[1], x[2], ... x[100000]) have few
    shapes once their digits are written as 0, so each shape is matched once; the rewriting runs
    in C over the names joined by NUL, a character that XML, and so no name, can hold."""
    names = list(names)
    joined = "\x00".join(names)
    if joined.count("\x00") != max(len(names) - 1, 0):  # a name holds NUL: one match each
        return None not in map(_NAME.fullmatch, names)
    shapes = set(joined.translate(_DIGITS_AS_ZERO).split("\x00")) if names else set()
    return None not in map(_NAME.fullmatch, shapes)


class NameProblem(NamedTuple):
    """Where a name leaves the grammar: the 0-based index and what the grammar expected there."""

    index: int
    expected: str


class _Off(Exception):
    def __init__(self, index: int, expected: str) -> None:
        super().__init__(index, expected)
        self.problem = NameProblem(index, expected)


def name_problem(name: str) -> NameProblem | None:
    """The first place where ``name`` breaks the structured grammar, or None if it is legal."""
    try:
        if name.startswith("der("):
            i = _identifier(name, 4)
            if _at(name, i) == ",":
                i = _unsigned(name, i + 1)
                _expect(name, i, ")", "')' closing der(")
            else:
                _expect(name, i, ")", "'.', '[', ',' and an order, or ')' closing der(")
            i += 1
        else:
            i = _identifier(name, 0)
        if i != len(name):
            raise _Off(i, "'.', '[' or the end of the name")
    except _Off as off:
        return off.problem
    return None


def _at(s: str, i: int) -> str:
    return s[i] if i < len(s) else ""


def _expect(s: str, i: int, char: str, expected: str) -> None:
    if _at(s, i) != char:
        raise _Off(i, expected)


def _identifier(s: str, i: int) -> int:
    i = _part(s, i)
    while _at(s, i) == ".":
        i = _part(s, i + 1)
    return i


def _part(s: str, i: int) -> int:
    """B-name [ arrayIndices ]"""
    i = _q_name(s, i) if _at(s, i) == "'" else _b_name(s, i)
    if _at(s, i) == "[":
        i = _unsigned(s, i + 1)
        while _at(s, i) == ",":
            i = _unsigned(s, i + 1)
        _expect(s, i, "]", "',' and another index, or ']'")
        i += 1
    return i


def _b_name(s: str, i: int) -> int:
    if _at(s, i) not in _NONDIGIT:  # "" (the end) is in no character set
        raise _Off(i, "a letter or '_' starting a name part, or a quoted name '...'")
    i += 1
    while i < len(s) and (s[i] in _NONDIGIT or s[i] in _DIGIT):
        i += 1
    return i


def _q_name(s: str, i: int) -> int:
    j = i + 1
    while j < len(s) and s[j] != "'":
        if s[j] == "\\":
            if _at(s, j + 1) not in _ESCAPED:
                raise _Off(j, "an escape sequence: \\' \\\" \\? \\\\ \\a \\b \\f \\n \\r \\t \\v")
            j += 2
        elif s[j] in _Q_CHAR:
            j += 1
        else:
            raise _Off(j, "a letter, digit, space or one of !#$%&()*+,-./:;<>=?@[]^{}|~ "
                          "inside a quoted name (or an escape sequence)")
    if j >= len(s):
        raise _Off(j, "the closing ' of a quoted name")
    if j == i + 1:
        raise _Off(j, "at least one character between the quotes")
    return j + 1


def _unsigned(s: str, i: int) -> int:
    if _at(s, i) not in _DIGIT:
        raise _Off(i, "an unsigned integer")
    while i < len(s) and s[i] in _DIGIT:
        i += 1
    return i
