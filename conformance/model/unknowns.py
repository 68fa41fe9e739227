"""An element of a ModelStructure, in modelDescription.xml or in the manifest: :class:`Unknown`.

Both readers (:mod:`conformance.model.description`, :mod:`conformance.model.manifest`) read a ModelStructure with
:func:`read_structure` (one element: :func:`parse_unknown`), and unsigned-integer attributes
with :func:`parse_uint`. Parsing is
lenient: a value that does not parse becomes ``None`` or a ``bad_tokens`` entry, and the schema
stage and the rules report it.
"""
from __future__ import annotations

from typing import Callable, NamedTuple

from lxml import etree


class Unknown(NamedTuple):
    """An element of a ModelStructure (core or manifest): Output, Residual, ...

    ``path`` is built on demand: a manifest of 500k variables holds about a million of these, and
    a path string each would cost ~100 bytes apiece. The readers store one ``where`` template
    shared by all elements (``".../ModelStructure/{}[{}]"``, filled with ``kind`` and
    ``ordinal``); an Unknown built by hand may give the path itself as ``where`` (ordinal 0).
    """

    kind: str
    vr: int | None
    dependencies: tuple[int, ...] | None      # None: attribute absent ("depends on all")
    dependencies_kind: tuple[str, ...] | None
    line: int | None
    file: str
    where: str                                # the path, or a template (see ``ordinal``)
    bad_tokens: tuple[str, ...] = ()          # dependency tokens that are not integers
    index: str | None = None                  # legacy `index` attribute
    formulations: int = 0                     # legacy: number of <Formulation> children
    ordinal: int = 0                          # > 0: 1-based position among same-kind siblings

    @property
    def path(self) -> str:
        """The element's XPath, e.g. ``/fmiDAEManifest/ModelStructure/Residual[3]``."""
        return self.where.format(self.kind, self.ordinal) if self.ordinal else self.where


UINT32_MAX = 0xFFFF_FFFF               # fmi3ValueReference
UINT64_MAX = 0xFFFF_FFFF_FFFF_FFFF     # fmi3UInt64 (sizes, counts)
_DIGITS = len(str(UINT64_MAX))         # longer digit strings are never read as numbers


def parse_uint(text: str | None, *, limit: int = UINT64_MAX) -> int | None:
    """An unsigned integer attribute up to ``limit``, or None: not a number, or out of range
    (str.isdigit alone admits '²', which int refuses; a number of thousands of digits is out of
    range, never an exception)."""
    if text is None:
        return None
    text = text.strip()
    if not (text.isascii() and text.isdigit()) or len(text) > _DIGITS:
        return None
    value = int(text)
    return value if value <= limit else None


def parse_vr(text: str | None) -> int | None:
    """A valueReference: an unsigned integer that fits fmi3ValueReference (UInt32), or None."""
    return parse_uint(text, limit=UINT32_MAX)


def path_template(prefix: str) -> str:
    """The ``where`` template of the elements under the XPath ``prefix``:
    ``path_template(prefix).format(kind, ordinal) == f"{prefix}/{kind}[{ordinal}]"``."""
    return prefix.replace("{", "{{").replace("}", "}}") + "/{}[{}]"


_SHARED_KINDS_LIMIT = 1024   # distinct dependenciesKind texts shared per document


def parse_unknown(el: etree._Element, kind: str, file: str, where: str, ordinal: int = 0,
                  shared: dict[str, tuple[str, ...]] | None = None) -> Unknown:
    """Read valueReference / dependencies / dependenciesKind of one structure element, as
    :func:`read_structure` reads each element of a ModelStructure.

    ``where`` and ``ordinal`` as in :class:`Unknown`; ``shared`` as in :func:`_shared_kinds`.
    """
    get = el.get
    deps_text = get("dependencies")
    deps, bad = (None, ()) if deps_text is None else _slow_dependencies(deps_text.split())
    kinds_text = get("dependenciesKind")
    kinds = (None if kinds_text is None
             else _shared_kinds(kinds_text, {} if shared is None else shared))
    return Unknown(kind, parse_vr(get("valueReference")), deps, kinds, el.sourceline, file,
                   where, bad, get("index"), 0, ordinal)


def read_structure(ms: etree._Element, file: str, where: str,
                   legacy: Callable[[etree._Element, str, int, dict], Unknown | None] | None = None
                   ) -> list[Unknown]:
    """The elements of the ModelStructure ``ms``, in document order; ``where`` as in
    :class:`Unknown`. ``legacy(el, kind, ordinal, shared)``, when given, reads an element with
    children (a legacy ``<Residual><Formulation/></Residual>``), or returns None to read it as
    any other.

    The same as calling :func:`parse_unknown` on each element, in one loop: a manifest of 500k
    variables holds half a million of these (reports/bench/static.md), and a call per element
    and per attribute is most of their cost.
    """
    out: list[Unknown] = []
    append = out.append
    new = tuple.__new__   # skips the NamedTuple's Python-level __new__
    counts: dict[str, list] = {}   # kind -> [the kind's shared string, elements so far]
    shared: dict[str, tuple[str, ...]] = {}
    last_tag = counter = None
    for el in ms:
        tag = el.tag
        if tag != last_tag:   # siblings of one kind come in runs: look the kind up once a run
            if not isinstance(tag, str):
                continue
            kind = tag if tag[0] != "{" else etree.QName(el).localname
            counter = counts.get(kind)
            if counter is None:
                counter = counts[kind] = [kind, 0]
            last_tag = tag
        counter[1] += 1
        if legacy is not None and len(el):
            found = legacy(el, counter[0], counter[1], shared)
            if found is not None:
                append(found)
                continue
        get = el.get
        deps_text = get("dependencies")
        deps: tuple[int, ...] | None = None
        bad: tuple[str, ...] = ()
        if deps_text is not None:
            tokens = deps_text.split()
            joined = "".join(tokens)
            if not joined or (joined.isdigit() and joined.isascii()
                              and max(map(len, tokens)) <= 9):  # the common case, fast
                deps = tuple(map(int, tokens))
            else:
                deps, bad = _slow_dependencies(tokens)
        kinds_text = get("dependenciesKind")
        kinds: tuple[str, ...] | None = None
        if kinds_text is not None and (kinds := shared.get(kinds_text)) is None:
            kinds = _shared_kinds(kinds_text, shared)
        raw_vr = get("valueReference")
        vr = int(raw_vr) if (raw_vr is not None and len(raw_vr) < 10 and raw_vr.isdigit()
                             and raw_vr.isascii()) else parse_vr(raw_vr)
        append(new(Unknown, (counter[0], vr, deps, kinds, el.sourceline, file, where, bad,
                             get("index"), 0, counter[1])))
    return out


def _shared_kinds(text: str, shared: dict[str, tuple[str, ...]]) -> tuple[str, ...]:
    """The dependenciesKind list ``text`` as a tuple of shared strings, remembered in
    ``shared``, one dict per document: equal lists are one tuple (a chain's 500k elements hold
    a few distinct lists). A token t is also the text of the one-token list (t,): its entry
    shares t."""
    kinds = tuple([shared.setdefault(t, (t,))[0] for t in text.split()])
    if len(shared) < _SHARED_KINDS_LIMIT:
        shared[text] = kinds
    return kinds


def _slow_dependencies(tokens: list[str]) -> tuple[tuple[int, ...], tuple[str, ...]]:
    """The dependency values that parse, and the tokens that do not (clipped for display)."""
    values = []
    bad = []
    for token in tokens:
        value = parse_vr(token)
        if value is not None:
            values.append(value)
        else:
            bad.append(token if len(token) <= 40 else token[:37] + "...")
    return tuple(values), tuple(bad)
