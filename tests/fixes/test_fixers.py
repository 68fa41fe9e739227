"""The text fixers on their own: the exact bytes each writes, file by file.

A fixer's edit is what ``lsdae fix`` writes into the user's FMU, so each test here names the
bytes before and after, not only that the rule stops firing.
"""
from __future__ import annotations

import pytest

from conformance.fixes.change import NoFix
from conformance.fixes.edits import apply_edits, by_file
from conformance.fixes.fixers import declare_prefix, header_fields
from conformance.fixes.header import header_edits
from conformance.fixes.xmltext import root_start_tag
from conformance.model.drafts.names import LS_NAMESPACE
from conformance.report.findings import Finding, Location, Severity, evidence

NAME = 'fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"'
VERSION = 'fmi-ls:fmi-ls-version="1.0.0-alpha.1"'
DESCRIPTION = 'fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI."'
BIND = f'xmlns:fmi-ls="{LS_NAMESPACE}"'


class _Files:
    """The least of a Package the text fixers use: files by name."""

    def __init__(self, **files: bytes):
        self.files = files

    def read(self, name: str) -> bytes | None:
        return self.files.get(name)


def _finding(code: str, file: str, subject: str | None = None, **ev) -> Finding:
    return Finding(code, "x", Severity.ERROR, "m", Location(file=file, line=1), evidence(ev),
                   subject)


def _fixed(files: _Files, change) -> dict[str, bytes]:
    return {name: apply_edits(files.read(name), edits)
            for name, edits in by_file(change.edits).items()}


def test_declare_prefix_declares_every_prefix_in_order_on_the_root_tag():
    files = _Files(a=b'<?xml version="1.0"?>\n<root x="1">\n  <p:a q:b="2"/>\n</root>\n')
    found = _finding("DAE010", "a", read_as_importers_do=['xmlns:p="urn:p"', 'xmlns:q="urn:q"'])
    change = declare_prefix(files, [found])
    assert change.fixer == "declare-prefix" and change.fixes == (found,)
    assert _fixed(files, change) == {
        "a": b'<?xml version="1.0"?>\n<root xmlns:p="urn:p" xmlns:q="urn:q" x="1">\n'
             b'  <p:a q:b="2"/>\n</root>\n'}


def _manifest(attributes: str, root: str = "fmiDAEManifest") -> bytes:
    return f'<{root} {attributes}>\n  <AlgebraicVariables/>\n</{root}>\n'.encode()


def test_header_fields_are_fixed_in_every_alpha1_manifest_and_only_there():
    files = _Files(legacy=_manifest(f'{BIND} fmi-ls:fmi-ls-version="0.1"',
                                    "fmiLayeredStandardManifest"),
                   one=_manifest(f'{BIND} {NAME} fmi-ls:fmi-ls-version="0.1" {DESCRIPTION}'),
                   two=_manifest(f'{BIND} {NAME} {VERSION} fmi-ls:fmi-ls-description="x"'))
    findings = [_finding("DAE103", "legacy", "fmi-ls-version"),
                _finding("DAE103", "one", "fmi-ls-version"),
                _finding("DAE104", "two", "fmi-ls-description"),
                _finding("DAE104", "two", None)]   # no header subject: not this fixer's
    change = header_fields(files, findings)
    assert change.fixer == "header-fields"
    assert change.fixes == tuple(findings[1:3])
    assert _fixed(files, change) == {
        "one": _manifest(f"{BIND} {NAME} {VERSION} {DESCRIPTION}"),
        "two": _manifest(f"{BIND} {NAME} {VERSION} {DESCRIPTION}")}


def _edited(attributes: str, wanted: list[str], **kw) -> bytes:
    data = _manifest(attributes)
    edits = header_edits("m.xml", root_start_tag(data), wanted, **kw)
    assert {e.file for e in edits} == {"m.xml"}
    return apply_edits(data, edits)


def test_a_missing_header_attribute_is_added_before_the_tag_ends():
    assert _edited(f"{BIND} {NAME}", ["fmi-ls-version", "fmi-ls-description"]) == \
        _manifest(f"{BIND} {NAME} {VERSION} {DESCRIPTION}")


def test_without_the_prefix_bound_it_is_declared_with_the_attributes():
    assert _edited('x="1"', ["fmi-ls-name"]) == _manifest(f'x="1" {BIND} {NAME}')


def test_an_unqualified_attribute_is_qualified_and_its_value_set():
    assert _edited(f"{BIND} fmi-ls-version='0.1' {NAME}", ["fmi-ls-version"]) == \
        _manifest(f"{BIND} fmi-ls:fmi-ls-version='1.0.0-alpha.1' {NAME}")
    assert _edited(f'{BIND} fmi-ls-version="1.0.0-alpha.1"', ["fmi-ls-version"]) == \
        _manifest(f"{BIND} {VERSION}")


def test_a_right_value_is_left_alone_when_only_wrong_ones_are_fixed():
    attributes = f"{BIND} {NAME} {VERSION} {DESCRIPTION}"
    assert header_edits("m.xml", root_start_tag(_manifest(attributes)),
                        ["fmi-ls-name", "fmi-ls-version"], only_if_wrong=True) == []


def test_the_fmi_ls_prefix_bound_elsewhere_is_no_fix():
    with pytest.raises(NoFix, match="^the prefix fmi-ls is bound to another namespace$"):
        _edited('xmlns:fmi-ls="urn:other"', ["fmi-ls-name"])
