"""The safe fixers: each turns the findings of its rules into a change derived from the files.

A fixer takes the package being fixed and the findings of its rules and returns a
:class:`Change` (byte edits, dropped zip entries, and the findings it claims to fix), or None
when nothing can be derived exactly. Fixers never parse and re-serialise XML.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

from ..report.findings import Finding
from .archive import Package
from .change import Change
from .edits import Edit
from .header import ALPHA1_ROOT, HEADER, header_edits
from .initial_unknowns import add_initial_unknowns
from .migrate import migrate_manifest
from .observed import add_observed_dependencies, observed_kinds
from .xmltext import root_start_tag


def declare_prefix(package: Package, findings: Sequence[Finding]) -> Change | None:
    """xml-not-well-formed whose only cause is a known prefix used undeclared: declare it on the
    root start tag, exactly as ``check`` read the file (evidence ``read_as_importers_do``)."""
    edits, fixed = [], []
    for finding in findings:
        declarations = finding.evidence_dict().get("read_as_importers_do")
        file = finding.location.file
        if not declarations or not file:
            continue
        data = package.read(file)
        tag = root_start_tag(data) if data is not None else None
        if tag is None:
            continue
        text = "".join(f" {d}" for d in declarations).encode("utf-8")
        edits.append(Edit(file, tag.name_end, tag.name_end, text))
        fixed.append(finding)
    return Change("declare-prefix", tuple(fixed), tuple(edits)) if edits else None


def header_fields(package: Package, findings: Sequence[Finding]) -> Change | None:
    """ls-name, ls-version, ls-description of a manifest with the alpha.1 root: set the fixed
    values, qualify an unqualified attribute, add a missing one (and the prefix's declaration)."""
    by_file: dict[str, list[Finding]] = {}
    for finding in findings:
        if finding.subject in HEADER and finding.location.file:
            by_file.setdefault(finding.location.file, []).append(finding)
    edits: list[Edit] = []
    fixed: list[Finding] = []
    for file, found in by_file.items():
        data = package.read(file)
        tag = root_start_tag(data) if data is not None else None
        if tag is None or tag.name != ALPHA1_ROOT:
            continue  # a legacy shape: the migration sets the header with everything else
        edits += header_edits(file, tag, [f.subject or "" for f in found])
        fixed += found
    return Change("header-fields", tuple(fixed), tuple(edits)) if fixed else None


def identical_duplicates(package: Package, findings: Sequence[Finding]) -> Change | None:
    """archive-duplicate-entry for a name stored twice with the same bytes: keep the first."""
    entries = package.entries()
    groups: dict[str, list[int]] = {}
    for index, info in enumerate(entries):
        groups.setdefault(info.filename, []).append(index)
    drop: set[int] = set()
    names: set[str] = set()
    for name, indices in groups.items():
        if len(indices) < 2 or any(i in package.dropped for i in indices):
            continue
        first = package.entry_bytes(indices[0])
        if all(package.entry_bytes(i) == first for i in indices[1:]):
            drop.update(indices[1:])
            names.add(name)
    fixed = tuple(f for f in findings if f.subject in names)
    return Change("identical-duplicates", fixed, drop=frozenset(drop)) if fixed else None


Fixer = Callable[[Package, Sequence[Finding]], "Change | None"]

#: fixer name -> (rule codes it fixes, function), in the order they run.
FIXERS: dict[str, tuple[tuple[str, ...], Fixer]] = {
    "identical-duplicates": (("DAE003",), identical_duplicates),
    "declare-prefix": (("DAE010",), declare_prefix),
    "header-fields": (("DAE102", "DAE103", "DAE104"), header_fields),
    "migrate-manifest": (("DAE021",), migrate_manifest),
    "add-initial-unknowns": (("DAE513",), add_initial_unknowns),
}

#: The unsafe fixers (``--unsafe-fixes``): from the probes' observations, re-checked with them.
UNSAFE_FIXERS: dict[str, tuple[tuple[str, ...], Fixer]] = {
    "add-observed-dependencies": (("DAE742", "DAE750"), add_observed_dependencies),
    "observed-kinds": (("DAE744", "DAE751"), observed_kinds),
}
