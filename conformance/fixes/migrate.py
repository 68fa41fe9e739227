"""legacy-draft-shape: the migration to 1.0.0-alpha.1 as byte edits on the manifest as written.

The steps are the ones :mod:`conformance.model.drafts.migrate` prints as hints, done: rename the root to
``fmiDAEManifest`` and drop the default namespace (and an element prefix bound to the
layered-standard namespace), ``EnableDAE`` -> ``EnableDAEParameter``, a numeric
``enableDAEModeVariable`` (a value reference, or a variable name looked up in
modelDescription.xml) -> an ``<EnableDAEParameter>`` first child, ``nominal`` off
``AlgebraicVariable``, ``<Residual><Formulation …/></Residual>`` -> ``<Residual …/>`` without
``index``, the ModelStructure children in the alpha.1 order (each moved with the white space and
comments before it), and the three header fields. What cannot be derived from the files raises
:class:`NoFix` with the reason: a higher-index residual, an enable variable name modelDescription.xml does
not define once, an
``attributes-only`` manifest (it names no algebraic variables or residuals).
"""
from __future__ import annotations

from collections.abc import Sequence

from ..model.drafts.detect import ATTRIBUTES_ONLY, LEGACY_DRAFTS, LS_NAMESPACE
from ..model.drafts.migrate import MODEL_STRUCTURE_ORDER
from ..report.findings import Finding
from ..model.description import MODEL_DESCRIPTION
from ..intake.xmlsafe import parse_xml
from .archive import Package
from .change import Change, NoFix
from .edits import Edit, apply_edits
from .header import ALPHA1_ROOT, HEADER, header_edits
from .xmltext import Element, element_tree


def _walk(element: Element):
    yield element
    for child in element.children:
        yield from _walk(child)


def _drop_attribute(file: str, element: Element, name: str) -> list[Edit]:
    attribute = element.tag.attribute(name)
    return [] if attribute is None else [Edit(file, attribute.start, attribute.value_end + 1, b"")]


class _Migration:
    def __init__(self, file: str, data: bytes, draft: str, model: bytes | None = None):
        root = element_tree(data)
        if root is None:
            raise NoFix("the manifest could not be read exactly enough to edit it")
        self.file, self.data, self.root, self.draft = file, data, root, draft
        self.model = model
        self.edits: list[Edit] = []
        self.names: dict[int, str] = {}      # id(element) -> new name
        self.replaced: set[int] = set()      # elements whose whole text is replaced

    def run(self) -> list[Edit]:
        if self.draft == ATTRIBUTES_ONLY:
            raise NoFix("an attributes-only manifest names no algebraic variables, residuals or "
                        "enable parameter; they cannot be derived from the files")
        self._prefixes()
        self.names[id(self.root)] = ALPHA1_ROOT
        default = self.root.tag.attribute("xmlns")
        if default is not None:
            if default.value != LS_NAMESPACE:
                raise NoFix(f"the root's default namespace is {default.value}")
            self.edits += _drop_attribute(self.file, self.root, "xmlns")
        self._enable()
        for block in self._named(self.root, "AlgebraicVariables"):
            for variable in self._named(block, "AlgebraicVariable"):
                self.edits += _drop_attribute(self.file, variable, "nominal")
        for structure in self._named(self.root, "ModelStructure"):
            for residual in self._named(structure, "Residual"):
                self._residual(residual)
        self._names()
        self.edits += header_edits(self.file, self.root.tag, list(HEADER), only_if_wrong=True)
        for structure in self._named(self.root, "ModelStructure"):
            self._order(structure)
        return self.edits

    def _prefixes(self) -> None:
        bound = set(self.root.tag.prefixes_for(LS_NAMESPACE))
        for element in _walk(self.root):
            prefix, _, local = element.name.rpartition(":")
            if prefix and prefix not in bound:
                raise NoFix(f"the element <{element.name}> has a prefix not bound to "
                            f"{LS_NAMESPACE} on the root")
            if prefix:
                self.names[id(element)] = local

    def _local(self, element: Element) -> str:
        return element.name.rpartition(":")[2]

    def _named(self, parent: Element, local: str) -> list[Element]:
        return [c for c in parent.children if self._local(c) == local]

    def _enable(self) -> None:
        children = self.root.children
        legacy = [c for c in children if self._local(c) == "EnableDAE"]
        current = [c for c in children if self._local(c) == "EnableDAEParameter"]
        attribute = self.root.tag.attribute("enableDAEModeVariable")
        for element in legacy:
            if element is not children[0]:
                raise NoFix("<EnableDAE> is not the root's first child")
            self.names[id(element)] = "EnableDAEParameter"
        if attribute is None:
            return
        if not (legacy or current):
            vr = attribute.value.strip()
            if not vr.isdigit():
                vr = self._value_reference(vr)
            if not children:
                raise NoFix("the manifest root has no child to put the enable parameter before")
            first = children[0].tag.start
            line_start = self.data.rfind(b"\n", 0, first) + 1
            indent = self.data[line_start:first]
            indent = indent if not indent.strip() else b""
            self.edits.append(Edit(self.file, first, first,
                                   f'<EnableDAEParameter valueReference="{vr}"/>\n'.encode()
                                   + indent))
        self.edits += _drop_attribute(self.file, self.root, "enableDAEModeVariable")

    def _value_reference(self, name: str) -> str:
        """The value reference of the one variable called ``name`` in modelDescription.xml."""
        tree = parse_xml(self.model, file=MODEL_DESCRIPTION)[0] if self.model else None
        found = [] if tree is None else [
            v.get("valueReference", "") for block in tree.getroot().iterchildren("ModelVariables")
            for v in block.iterchildren() if v.get("name") == name]
        if len(found) != 1 or not found[0].strip().isdigit():
            raise NoFix(f"enableDAEModeVariable names the variable {name!r}, which "
                        "modelDescription.xml does not define exactly once with a value reference")
        return found[0].strip()

    def _residual(self, residual: Element) -> None:
        formulations = [c for c in residual.children if self._local(c) == "Formulation"]
        if len(formulations) > 1:
            raise NoFix(f"a <Residual> has {len(formulations)} Formulations: a higher-index "
                        "constraint has no alpha.1 form")
        if not formulations:
            self.edits += _drop_attribute(self.file, residual, "index")
            return
        formulation = formulations[0]
        inner = (self.data[residual.tag.close + 1:formulation.tag.start]
                 + self.data[formulation.end:residual.end_tag_start or residual.end])
        if residual.tag.attributes or len(residual.children) != 1 or inner.strip() \
                or formulation.children:
            raise NoFix("a <Residual> holds more than one <Formulation/> (attributes, comments "
                        "or other elements)")
        kept = b"".join(self.data[a.start:a.value_end + 1]
                        for a in formulation.tag.attributes if a.name != "index")
        self.edits.append(Edit(self.file, residual.tag.start, residual.end,
                               b"<Residual" + kept + b"/>"))
        self.replaced.add(id(residual))

    def _names(self) -> None:
        for element in _walk(self.root):
            new = self.names.get(id(element))
            if new is None or new == element.name or self._inside_replaced(element):
                continue
            start = element.tag.start + 1
            self.edits.append(Edit(self.file, start, start + len(element.name), new.encode()))
            if element.end_tag_start is not None:
                at = element.end_tag_start + 2
                self.edits.append(Edit(self.file, at, at + len(element.name), new.encode()))

    def _inside_replaced(self, element: Element) -> bool:
        return any(r.tag.start <= element.tag.start < r.end for r in self._replaced_elements())

    def _replaced_elements(self) -> list[Element]:
        return [e for e in _walk(self.root) if id(e) in self.replaced]

    def _order(self, structure: Element) -> None:
        rank = {k: i for i, k in enumerate(MODEL_STRUCTURE_ORDER)}
        kids = structure.children
        if any(self._local(k) not in rank for k in kids):
            raise NoFix("<ModelStructure> holds an element alpha.1 does not know")
        order = sorted(range(len(kids)), key=lambda i: rank[self._local(kids[i])])
        if order == list(range(len(kids))):
            return
        start = structure.tag.close + 1
        bounds = [start] + [k.end for k in kids]
        end = bounds[-1]
        inside = [e for e in self.edits if start <= e.start and e.end <= end]
        if any(e.start < start < e.end or e.start < end < e.end for e in self.edits):
            raise NoFix("the ModelStructure edits overlap")
        chunks = []
        for i in order:
            a, b = bounds[i], bounds[i + 1]
            local = [Edit(e.file, e.start - a, e.end - a, e.text) for e in inside
                     if a <= e.start and e.end <= b and not (e.start == e.end == b)]
            chunks.append(apply_edits(self.data[a:b], local))
        self.edits = [e for e in self.edits if e not in inside]
        self.edits.append(Edit(self.file, start, end, b"".join(chunks)))


def migrate_manifest(package: Package, findings: Sequence[Finding]) -> Change | None:
    """legacy-draft-shape: the whole migration as one change, or NoFix with the reason."""

    edits: list[Edit] = []
    for finding in findings:
        draft = finding.evidence_dict().get("draft") or finding.subject
        file = finding.location.file
        if draft not in LEGACY_DRAFTS or not file:
            continue
        data = package.read(file)
        if data is None:
            raise NoFix(f"{file} cannot be read")
        edits += _Migration(file, data, draft, package.read(MODEL_DESCRIPTION)).run()
    return Change("migrate-manifest", tuple(findings), tuple(edits)) if edits else None

