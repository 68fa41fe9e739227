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


class Ordinals:
    """Each element kind of a ModelStructure: one shared string for its name, and how many
    elements of it came so far (the ordinal of ``Output[3]`` in a path)."""

    def __init__(self) -> None:
        self._counts: dict[str, list] = {}   # kind -> [the kind's shared string, elements so far]

    def next(self, kind: str) -> tuple[str, int]:
        counter = self._counts.get(kind)
        if counter is None:
            counter = self._counts[kind] = [kind, 0]
        counter[1] += 1
        return counter[0], counter[1]


def parse_unknown(el: etree._Element, kind: str, file: str, where: str, ordinal: int = 0,
                  attrs: Mapping[str, str] | None = None,
                  shared: dict[str, tuple[str, ...]] | None = None) -> Unknown:
    """Read valueReference / dependencies / dependenciesKind of a structure element.

    ``where`` and ``ordinal`` as in :class:`Unknown`. ``shared``, one dict per document, makes
    equal dependenciesKind lists one tuple of shared strings (a chain's 500k elements hold a few
    distinct lists)."""
    get = el.get if attrs is None else attrs.get
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
    if kinds_text is not None:
        if shared is None:
            kinds = tuple(kinds_text.split())
        elif (kinds := shared.get(kinds_text)) is None:
            # a token t is also the text of the one-token list (t,): its entry shares t
            kinds = tuple([shared.setdefault(t, (t,))[0] for t in kinds_text.split()])
            if len(shared) < _SHARED_KINDS_LIMIT:
                shared[kinds_text] = kinds
    raw_vr = get("valueReference")
    vr = int(raw_vr) if (raw_vr is not None and len(raw_vr) < 10 and raw_vr.isdigit()
                         and raw_vr.isascii()) else parse_vr(raw_vr)
    # tuple.__new__ skips the NamedTuple's Python-level __new__: a manifest of 500k variables
    # builds about a million of these (see reports/bench/static.md).
    return tuple.__new__(Unknown, (
        kind, vr, deps, kinds, el.sourceline, file, where, bad, get("index"), 0, ordinal))


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
