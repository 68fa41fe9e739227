"""The fmi-ls-dae manifest as a frozen dataclass, read from any draft shape.

Every shape in the wild (see conformance/model/drafts/) is normalised into one :class:`Manifest`:
element names are compared by local name, so namespaced legacy manifests read the same as
alpha.1 ones; a legacy ``<Residual><Formulation .../></Residual>`` becomes a Residual
:class:`~conformance.model.unknowns.Unknown` whose ``formulations`` counts the Formulation children.
The shape itself is reported by the draft rules; the semantic rules then run on this model.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

from lxml import etree

from .drafts.detect import LS_NAMESPACE
from .unknowns import Unknown, parse_unknown, parse_vr, path_template, read_structure

MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
LS_ATTRIBUTES = ("fmi-ls-name", "fmi-ls-version", "fmi-ls-description")
ENABLE_ELEMENTS = ("EnableDAEParameter", "EnableDAE")


class VrRef(NamedTuple):
    """A manifest element that points at a variable: enable parameter or algebraic variable.

    ``path`` is built on demand from ``where`` and ``ordinal``, as for
    :class:`~conformance.model.unknowns.Unknown` (a manifest may list 125k algebraic variables).
    """

    vr: int | None
    line: int | None
    where: str                       # the path, or a template filled with element and ordinal
    element: str                     # EnableDAEParameter, EnableDAE, @enableDAEModeVariable, ...
    raw: str | None = None           # the valueReference text when it is not an integer
    name: str | None = None          # when the variable is given by name (an old draft)
    extra: tuple[tuple[str, str], ...] = ()   # attributes beyond valueReference
    ordinal: int = 0                 # > 0: 1-based position in its list (``where`` a template)

    @property
    def path(self) -> str:
        return self.where.format(self.element, self.ordinal) if self.ordinal else self.where


@dataclass(frozen=True)
class Manifest:
    file: str
    root_name: str
    root_namespace: str | None
    root_line: int | None
    ls_name: str | None
    ls_version: str | None
    ls_description: str | None
    unqualified_ls_attributes: tuple[str, ...]
    enables: tuple[VrRef, ...]
    algebraic: tuple[VrRef, ...]
    algebraic_line: int | None
    structure: tuple[Unknown, ...]
    has_model_structure: bool
    is_dae_fmu: str | None
    draft: str

    @property
    def enable(self) -> VrRef | None:
        return self.enables[0] if self.enables else None

    @cached_property
    def _by_kind(self) -> dict[str, tuple[Unknown, ...]]:
        kinds: dict[str, list[Unknown]] = {}
        for u in self.structure:
            kinds.setdefault(u.kind, []).append(u)
        return {k: tuple(v) for k, v in kinds.items()}

    @property
    def residuals(self) -> tuple[Unknown, ...]:
        return self._by_kind.get("Residual", ())

    def unknowns(self, kind: str) -> tuple[Unknown, ...]:
        return self._by_kind.get(kind, ())


def _local(el: etree._Element) -> str:
    tag = el.tag
    if not isinstance(tag, str):
        return ""
    return tag if tag[0] != "{" else etree.QName(el).localname


def _elements(el: etree._Element | None) -> list[etree._Element]:
    return [] if el is None else [c for c in el if isinstance(c.tag, str)]


def _ref(el: etree._Element, where: str, ordinal: int = 0,
         names: dict[str, str] | None = None) -> VrRef:
    """``where`` and ``ordinal`` as in :class:`VrRef`; ``names`` shares the element names
    (one dict per list)."""
    raw = el.get("valueReference")
    vr = parse_vr(raw)
    attrib = el.attrib
    extra: tuple[tuple[str, str], ...] = ()
    if len(attrib) > (raw is not None):  # attributes beyond valueReference: rare
        extra = tuple(sorted((etree.QName(k).localname, v) for k, v in attrib.items()
                             if k != "valueReference"))
    element = _local(el)
    if names is not None:
        element = names.setdefault(element, element)
    # tuple.__new__ skips the NamedTuple's Python-level __new__ (125k of these at 500k variables)
    return tuple.__new__(VrRef, (vr, el.sourceline, where, element,
                                 raw if vr is None else None, None, extra, ordinal))


def _refs(container: etree._Element, where: str) -> list[VrRef]:
    """The elements of a list (``<AlgebraicVariables>``) as :func:`_ref` reads each, ``where``
    a template, in one loop: a manifest may list 125k of them (reports/bench/static.md)."""
    out: list[VrRef] = []
    append = out.append
    new = tuple.__new__   # skips the NamedTuple's Python-level __new__
    names: dict[str, str] = {}
    last_tag = element = None
    ordinal = 0
    for el in container:
        tag = el.tag
        if tag != last_tag:   # one kind of element, as a rule: look its name up once a run
            if not isinstance(tag, str):
                continue
            element = _local(el)
            element = names.setdefault(element, element)
            last_tag = tag
        ordinal += 1
        items = el.items()
        if len(items) == 1 and items[0][0] == "valueReference":   # the common case, fast
            raw = items[0][1]
            if len(raw) < 10 and raw.isdigit() and raw.isascii():
                append(new(VrRef, (int(raw), el.sourceline, where, element, None, None, (),
                                   ordinal)))
                continue
        append(_ref(el, where, ordinal, names))
    return out


def read_manifest(tree: etree._ElementTree, *, draft: str, file: str = MANIFEST) -> Manifest:
    """Normalise a manifest tree of any known shape; never raises on odd content."""
    root = tree.getroot()
    rname = _local(root)
    qualified = {a: root.get(f"{{{LS_NAMESPACE}}}{a}") for a in LS_ATTRIBUTES}
    unqualified = tuple(a for a in LS_ATTRIBUTES if root.get(a) is not None)

    enables: list[VrRef] = []
    algebraic: list[VrRef] = []
    algebraic_line = None
    structure: list[Unknown] = []
    has_ms = False
    for child in _elements(root):
        tag = _local(child)
        if tag in ENABLE_ELEMENTS:
            enables.append(_ref(child, f"/{rname}/{tag}"))
        elif tag == "AlgebraicVariables":
            algebraic_line = child.sourceline
            where = path_template(f"/{rname}/AlgebraicVariables")
            algebraic.extend(_refs(child, where))
        elif tag == "ModelStructure":
            has_ms = True
            structure.extend(_structure(child, rname, file))
    by_name = root.get("enableDAEModeVariable")
    if by_name is not None:
        enables.append(VrRef(vr=parse_vr(by_name), line=root.sourceline,
                             where=f"/{rname}/@enableDAEModeVariable",
                             element="@enableDAEModeVariable",
                             name=None if by_name.strip().isdigit() else by_name))
    ns = etree.QName(root).namespace if isinstance(root.tag, str) else None
    return Manifest(
        file=file, root_name=rname, root_namespace=ns, root_line=root.sourceline,
        ls_name=qualified["fmi-ls-name"], ls_version=qualified["fmi-ls-version"],
        ls_description=qualified["fmi-ls-description"], unqualified_ls_attributes=unqualified,
        enables=tuple(enables), algebraic=tuple(algebraic), algebraic_line=algebraic_line,
        structure=tuple(structure), has_model_structure=has_ms,
        is_dae_fmu=root.get("isDaeFmu"), draft=draft,
    )


def _structure(ms: etree._Element, rname: str, file: str) -> list[Unknown]:
    where = path_template(f"/{rname}/ModelStructure")

    def legacy(el: etree._Element, kind: str, ordinal: int, shared: dict) -> Unknown | None:
        """A legacy <Residual> with <Formulation> children: read its first Formulation."""
        if kind != "Residual":
            return None
        formulations = [f for f in _elements(el) if _local(f) == "Formulation"]
        if not formulations:
            return None
        unknown = parse_unknown(formulations[0], kind, file, where + "/Formulation[1]",
                                ordinal, shared=shared)
        return unknown._replace(formulations=len(formulations))

    return read_structure(ms, file, where, legacy)
