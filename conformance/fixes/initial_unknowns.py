"""model-structure-initial-unknown-mismatch: add the <InitialUnknown> entries FMI requires.

Only missing entries are added (an output, calculated parameter, state or derivative with
initial approx or calculated that the list leaves out), each as
``<InitialUnknown valueReference="N"/>``: without ``dependencies``, which FMI reads as "depends
on everything", the one claim that cannot be wrong. The entry goes in value-reference order among
the existing InitialUnknowns, else after Output/ContinuousStateDerivative/ClockedState, on a line
of its own with the indentation of its neighbour. Extra or duplicate entries are left.
"""
from __future__ import annotations

from collections.abc import Sequence

from ..report.findings import Finding
from .archive import Package
from .change import Change, NoFix
from .edits import Edit
from .xmltext import Element, element_tree

_BEFORE = ("Output", "ContinuousStateDerivative", "ClockedState")


def _indent(data: bytes, at: int) -> bytes:
    line = data.rfind(b"\n", 0, at) + 1
    text = data[line:at]
    return text if not text.strip() else b"  "


def _vr(element: Element) -> int | None:
    attribute = element.tag.attribute("valueReference")
    text = attribute.value.strip() if attribute else ""
    return int(text) if text.isdigit() else None


def _insertions(data: bytes, structure: Element, vrs: list[int], file: str) -> list[Edit]:
    kids = structure.children
    existing = [k for k in kids if k.name == "InitialUnknown"]
    if structure.end_tag_start is None:
        raise NoFix("<ModelStructure/> is empty-element tag; nothing to add the entries to")
    by_anchor: dict[int, list[bytes]] = {}
    for vr in sorted(vrs):
        after = [k for k in existing if (_vr(k) or 0) < vr]
        if after:
            anchor, model = after[-1].end, after[-1]
        elif existing:
            anchor, model = existing[0].tag.start, existing[0]
        else:
            before = [k for k in kids if k.name in _BEFORE]
            model = before[-1] if before else (kids[0] if kids else None)
            anchor = before[-1].end if before else (kids[0].tag.start if kids else
                                                     structure.end_tag_start)
        indent = _indent(data, model.tag.start) if model is not None else b"    "
        entry = f'<InitialUnknown valueReference="{vr}"/>'.encode()
        front = existing and anchor == existing[0].tag.start and not after
        by_anchor.setdefault(anchor, []).append(
            entry + b"\n" + indent if front else b"\n" + indent + entry)
    return [Edit(file, at, at, b"".join(parts)) for at, parts in by_anchor.items()]


def add_initial_unknowns(package: Package, findings: Sequence[Finding]) -> Change | None:
    missing: dict[str, list[tuple[int, Finding]]] = {}
    for finding in findings:
        ev = finding.evidence_dict()
        if finding.count != 1 or "reason" not in ev or ev.get("kind") != "InitialUnknown":
            continue   # an extra or duplicate entry, or a grouped finding: left as it is
        vr = ev.get("value_reference")
        if isinstance(vr, int) and finding.location.file:
            missing.setdefault(finding.location.file, []).append((vr, finding))
    edits: list[Edit] = []
    fixed: list[Finding] = []
    for file, items in missing.items():
        data = package.read(file)
        root = element_tree(data) if data is not None else None
        structures = root.named("ModelStructure") if root is not None else []
        if len(structures) != 1:
            raise NoFix(f"{file}: no single <ModelStructure> to add InitialUnknowns to")
        edits += _insertions(data, structures[0], [vr for vr, _ in items], file)
        fixed += [f for _, f in items]
    return Change("add-initial-unknowns", tuple(fixed), tuple(edits)) if fixed else None
