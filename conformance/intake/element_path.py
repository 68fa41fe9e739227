"""The readable XPath-like path of an element (:func:`element_path`), for locations."""
from __future__ import annotations

import logging

from lxml import etree

log = logging.getLogger(__name__)


def element_path(el: etree._Element) -> str:
    """A readable XPath-like path, e.g. ``/fmiModelDescription/ModelVariables/Float64[@name='x']``.

    An element with a ``name`` attribute is identified by it; otherwise by its position among
    siblings with the same tag, and only when it has such siblings. Cheap: no whole-tree scan.
    """
    try:
        steps = []
        node: etree._Element | None = el
        while node is not None:
            steps.append(_step(node))
            node = node.getparent()
        return "/" + "/".join(reversed(steps))
    except Exception:  # a path is a convenience; never let it break a check
        log.debug("element_path failed", exc_info=True)
        return ""


def _step(node: etree._Element) -> str:
    tag = node.tag
    if not isinstance(tag, str):
        if isinstance(node, etree._Comment):
            label = "comment()"
        elif isinstance(node, etree._ProcessingInstruction):
            label = "processing-instruction()"
        else:
            label = "node()"
        return f"{label}[{_position(node, None)}]"
    qname = etree.QName(tag).localname
    if node.prefix:
        qname = f"{node.prefix}:{qname}"
    name = node.get("name")
    if name is not None:
        quote = "'" if "'" not in name else '"'
        return f"{qname}[@name={quote}{name}{quote}]"
    if node.getparent() is None:
        return qname
    same = any(True for _ in node.itersiblings(tag)) or any(
        True for _ in node.itersiblings(tag, preceding=True))
    return f"{qname}[{_position(node, tag)}]" if same else qname


def _position(node: etree._Element, tag: str | None) -> int:
    if tag is None:
        return 1 + sum(1 for s in node.itersiblings(preceding=True) if type(s) is type(node))
    return 1 + sum(1 for _ in node.itersiblings(tag, preceding=True))

