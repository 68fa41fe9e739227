"""An element of a ModelStructure, in modelDescription.xml or in the manifest: :class:`Unknown`.

Both readers (:mod:`conformance.model`, :mod:`conformance.manifest`) read such elements with
:func:`parse_unknown`, and unsigned-integer attributes with :func:`parse_uint`. Parsing is
lenient: a value that does not parse becomes ``None`` or a ``bad_tokens`` entry, and the schema
stage and the rules report it.
"""
from __future__ import annotations

from typing import Mapping, NamedTuple

from lxml import etree


class Unknown(NamedTuple):
    """An element of a ModelStructure (core or manifest): Output, Residual, ..."""

    kind: str
    vr: int | None
    dependencies: tuple[int, ...] | None      # None: attribute absent ("depends on all")
    dependencies_kind: tuple[str, ...] | None
    line: int | None
    file: str
    path: str
    bad_tokens: tuple[str, ...] = ()          # dependency tokens that are not integers
    index: str | None = None                  # legacy `index` attribute
    formulations: int = 0                     # legacy: number of <Formulation> children


def parse_uint(text: str | None) -> int | None:
    """An unsigned integer attribute, or None (str.isdigit alone admits '²', which int refuses)."""
    if text is None:
        return None
    text = text.strip()
    return int(text) if text.isascii() and text.isdigit() else None


def parse_unknown(el: etree._Element, kind: str, file: str, path: str,
                  attrs: Mapping[str, str] | None = None) -> Unknown:
    """Read valueReference / dependencies / dependenciesKind of a structure element."""
    a = el.attrib if attrs is None else attrs
    deps_text = a.get("dependencies")
    deps: tuple[int, ...] | None = None
    bad: list[str] = []
    if deps_text is not None:
        tokens = deps_text.split()
        joined = "".join(tokens)
        if not joined or (joined.isascii() and joined.isdigit()):  # the common case, fast
            deps = tuple(map(int, tokens))
        else:
            values = []
            for token in tokens:
                if token.isascii() and token.isdigit():
                    values.append(int(token))
                else:
                    bad.append(token)
            deps = tuple(values)
    kinds_text = a.get("dependenciesKind")
    kinds = tuple(kinds_text.split()) if kinds_text is not None else None
    raw_vr = a.get("valueReference")
    vr = int(raw_vr) if raw_vr is not None and raw_vr.isascii() and raw_vr.isdigit() \
        else parse_uint(raw_vr)
    return Unknown(kind=kind, vr=vr, dependencies=deps,
                   dependencies_kind=kinds, line=el.sourceline, file=file, path=path,
                   bad_tokens=tuple(bad), index=a.get("index"))
