"""The root start tag of an XML document and its attributes, as byte offsets in the original.

Only ASCII-compatible encodings (UTF-8, Latin-1, ...) are handled; for anything else these
return None and no text fix is offered. Nothing here re-serialises: callers edit byte ranges.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

_PROLOG_ITEM = re.compile(rb"\s*(?:<\?.*?\?>|<!--.*?-->|<!DOCTYPE[^>\[]*(?:\[.*?\])?\s*>)", re.DOTALL)
_START = re.compile(rb"<([A-Za-z_][\w.:-]*)")
_ATTRIBUTE = re.compile(rb"(\s+)([A-Za-z_][\w.:-]*)(\s*=\s*)(\"[^\"<]*\"|'[^'<]*')")
_END = re.compile(rb"\s*(/?>)")


@dataclass(frozen=True, slots=True)
class Attribute:
    name: str
    value: str                 # as written, entities not expanded
    start: int                 # offset of the whitespace before the name
    name_start: int
    value_start: int           # offset of the first character inside the quotes
    value_end: int
    quote: bytes


@dataclass(frozen=True, slots=True)
class StartTag:
    name: str
    start: int                 # offset of '<'
    name_end: int
    attributes: tuple[Attribute, ...]
    close: int                 # offset of '>' or '/>' (after any trailing white space)

    def attribute(self, name: str) -> Attribute | None:
        return next((a for a in self.attributes if a.name == name), None)

    def prefixes_for(self, uri: str) -> list[str]:
        """Prefixes this tag binds to ``uri``."""
        return [a.name.split(":", 1)[1] for a in self.attributes
                if a.name.startswith("xmlns:") and a.value == uri]


def ascii_compatible(data: bytes) -> bool:
    return not (data.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in data[:200])


def root_start_tag(data: bytes) -> StartTag | None:
    """The root element's start tag, or None when it cannot be found exactly."""
    if not ascii_compatible(data):
        return None
    pos = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    while True:
        item = _PROLOG_ITEM.match(data, pos)
        if item is None:
            break
        pos = item.end()
    while pos < len(data) and data[pos:pos + 1].isspace():
        pos += 1
    return start_tag_at(data, pos)


def start_tag_at(data: bytes, pos: int) -> StartTag | None:
    """The start tag beginning at ``data[pos]`` ('<'), or None."""
    start = _START.match(data, pos)
    if start is None:
        return None
    attributes = []
    cursor = start.end()
    while (m := _ATTRIBUTE.match(data, cursor)) is not None:
        value = m.group(4)
        attributes.append(Attribute(
            name=m.group(2).decode("ascii", "replace"),
            value=value[1:-1].decode("utf-8", "replace"), start=m.start(),
            name_start=m.start(2), value_start=m.start(4) + 1, value_end=m.end(4) - 1,
            quote=value[:1]))
        cursor = m.end()
    end = _END.match(data, cursor)
    if end is None:
        return None
    return StartTag(start.group(1).decode("ascii", "replace"), start.start(), start.end(),
                    tuple(attributes), end.start(1))


@dataclass
class Element:
    """An element's byte spans: its start tag, and where it ends (after its end tag)."""

    tag: StartTag
    end: int = -1
    end_tag_start: int | None = None      # None for an empty-element tag <x/>
    children: list[Element] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.tag.name

    def named(self, name: str) -> list[Element]:
        return [c for c in self.children if c.name == name]


_MARKUP = re.compile(rb"<!--.*?-->|<\?.*?\?>|<!\[CDATA\[.*?\]\]>|<!DOCTYPE[^>\[]*(?:\[.*?\])?\s*>|"
                     rb"</([A-Za-z_][\w.:-]*)\s*>|<", re.DOTALL)


def element_tree(data: bytes) -> Element | None:
    """The document's elements with their byte spans, or None when it cannot be read exactly
    (a wide encoding, a tag it does not understand, mismatched end tags)."""
    if not ascii_compatible(data):
        return None
    stack: list[Element] = []
    root: Element | None = None
    pos = 0
    while (m := _MARKUP.search(data, pos)) is not None:
        if m.group(0) == b"<":
            tag = start_tag_at(data, m.start())
            if tag is None:
                return None
            element = Element(tag)
            if stack:
                stack[-1].children.append(element)
            elif root is None:
                root = element
            else:
                return None
            pos = tag.close + (2 if data[tag.close:tag.close + 2] == b"/>" else 1)
            if data[tag.close:tag.close + 2] == b"/>":
                element.end = pos
            else:
                stack.append(element)
        elif m.group(1) is not None:
            if not stack or stack[-1].name != m.group(1).decode("ascii", "replace"):
                return None
            element = stack.pop()
            element.end_tag_start, element.end = m.start(), m.end()
            pos = m.end()
        else:
            pos = m.end()
    return root if root is not None and not stack else None


def escape(value: str, quote: bytes = b'"') -> bytes:
    text = value.replace("&", "&amp;").replace("<", "&lt;")
    text = text.replace('"', "&quot;") if quote == b'"' else text.replace("'", "&apos;")
    return text.encode("utf-8")
