"""Small lxml helpers that draft detection, migration and schema validation share."""
from __future__ import annotations

from typing import Iterator

from lxml import etree


def element_children(element: etree._Element) -> list[etree._Element]:
    return [c for c in element if isinstance(c.tag, str)]


def children_named(element: etree._Element, local: str) -> list[etree._Element]:
    return [c for c in element_children(element) if etree.QName(c).localname == local]


def first_child(element: etree._Element) -> etree._Element | None:
    children = element_children(element)
    return children[0] if children else None


def all_elements(root: etree._Element) -> Iterator[etree._Element]:
    return (e for e in root.iter() if isinstance(e.tag, str))


def residual_elements(root: etree._Element) -> list[etree._Element]:
    return [r for s in children_named(root, "ModelStructure")
            for r in children_named(s, "Residual")]


def written_name(element: etree._Element) -> str:
    """The element name as the author wrote it (with its prefix, if any)."""
    local = etree.QName(element).localname
    return f"{element.prefix}:{local}" if element.prefix else local
