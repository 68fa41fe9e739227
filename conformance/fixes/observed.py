"""Unsafe fixes: what the probes observed the binary do, written into the dependencies.

Sampling can show that a dependency exists, never that one does not, so these only ever widen a
claim: a partial derivative seen clearly non-zero that ``dependencies`` leaves out is added (kind
``dependent``), and an entry declared ``constant`` (or ``fixed``, ``tunable``, ``discrete``)
whose partial was seen to change becomes ``dependent``. Nothing is removed, nothing is made
``constant``. Applied only with ``lsdae fix --unsafe-fixes``, each re-checked with the probes.
"""
from __future__ import annotations

import bisect
from collections.abc import Sequence

from ..report.findings import Finding
from .archive import Package
from .change import Change
from .edits import Edit
from .xmltext import Element, element_tree, escape

_STEP_SUFFIX = "]"


def find_path(root: Element, path: str) -> Element | None:
    """The element at an XPath-like location path such as ``/a/B/C[2]`` (1-based indices)."""
    steps = [s for s in (path or "").split("/") if s]
    if not steps or steps[0] != root.name:
        return None
    element = root
    for step in steps[1:]:
        name, _, index = step.partition("[")
        position = int(index[:-1]) if index.endswith(_STEP_SUFFIX) and index[:-1].isdigit() \
            else 1
        matches = element.named(name)
        if not 1 <= position <= len(matches):
            return None
        element = matches[position - 1]
    return element


def _targets(package: Package, findings: Sequence[Finding]
             ) -> dict[tuple[str, str], tuple[Element, bytes, list[tuple[int, Finding]]]]:
    out: dict[tuple[str, str], tuple[Element, bytes, list[tuple[int, Finding]]]] = {}
    trees: dict[str, tuple[Element | None, bytes]] = {}
    for finding in findings:
        vr = finding.evidence_dict().get("known_value_reference")
        file, path = finding.location.file, finding.location.path
        if not isinstance(vr, int) or not file or not path:
            continue
        if file not in trees:
            data = package.read(file) or b""
            trees[file] = (element_tree(data), data)
        root, data = trees[file]
        element = find_path(root, path) if root is not None else None
        if element is None:
            continue
        out.setdefault((file, path), (element, data, []))[2].append((vr, finding))
    return out


def _tokens(element: Element, name: str) -> list[str] | None:
    attribute = element.tag.attribute(name)
    return None if attribute is None else attribute.value.split()


def _set(file: str, element: Element, name: str, tokens: list[str]) -> Edit:
    attribute = element.tag.attribute(name)
    assert attribute is not None
    return Edit(file, attribute.value_start, attribute.value_end,
                escape(" ".join(tokens), attribute.quote))


def add_observed_dependencies(package: Package, findings: Sequence[Finding]) -> Change | None:
    """dependency-undeclared, initial-dependency-undeclared: add the observed known."""
    edits: list[Edit] = []
    fixed: list[Finding] = []
    for (file, _), (element, _, items) in _targets(package, findings).items():
        deps = _tokens(element, "dependencies")
        kinds = _tokens(element, "dependenciesKind")
        if deps is None or not all(d.isdigit() for d in deps):
            continue   # no dependencies attribute: it already depends on everything
        if kinds is not None and len(kinds) != len(deps):
            continue
        numbers = [int(d) for d in deps]
        ordered = numbers == sorted(numbers)
        for vr, finding in sorted(items, key=lambda item: item[0]):
            if vr in numbers:
                continue
            at = bisect.bisect(numbers, vr) if ordered else len(numbers)
            numbers.insert(at, vr)
            if kinds is not None:
                kinds.insert(at, "dependent")
            fixed.append(finding)
        edits.append(_set(file, element, "dependencies", [str(n) for n in numbers]))
        if kinds is not None:
            edits.append(_set(file, element, "dependenciesKind", kinds))
    return Change("add-observed-dependencies", tuple(fixed), tuple(edits)) if fixed else None


def observed_kinds(package: Package, findings: Sequence[Finding]) -> Change | None:
    """dependencies-kind-violated, initial-dependencies-kind-violated: make it ``dependent``."""
    edits: list[Edit] = []
    fixed: list[Finding] = []
    for (file, _), (element, _, items) in _targets(package, findings).items():
        deps = _tokens(element, "dependencies")
        kinds = _tokens(element, "dependenciesKind")
        if deps is None or kinds is None or len(deps) != len(kinds):
            continue
        for vr, finding in items:
            if str(vr) in deps:
                kinds[deps.index(str(vr))] = "dependent"
                fixed.append(finding)
        edits.append(_set(file, element, "dependenciesKind", kinds))
    return Change("observed-kinds", tuple(fixed), tuple(edits)) if fixed else None
