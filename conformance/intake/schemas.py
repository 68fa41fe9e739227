"""XML Schema validation of modelDescription.xml and of the fmi-ls-dae manifest.

Both use lxml (libxml2): it validates an 18 MB modelDescription in a fraction of a second,
and its error log gives a line and an XPath for every error, which is all a finding needs. The
schemas are located and loaded, offline, by :mod:`conformance.intake.schema_loader`: the FMI 3.0
core schema from the installed fmpy, ours from ``schemas/`` (one per draft).

Legacy manifests may put their elements in the layered-standard namespace (as default namespace or
with the ``fmi-ls:`` prefix) or leave them unqualified. Their schemas describe unqualified elements
only; :func:`validate_manifest` validates a copy in which elements of that namespace are moved to
no namespace (attributes untouched), so one schema covers every namespace variant of a draft.
The 1.0.0-alpha.1 manifest is validated as it is: its elements must be in no namespace.

Messages are libxml2's, tidied by :mod:`conformance.intake.schema_messages`. A follow-up error on an
attribute that already has an error (libxml2 reports a bad list value twice, once for the item
and once for the list) is dropped.
"""
from __future__ import annotations

import copy
import threading
from dataclasses import replace
from typing import Iterator, Union

from lxml import etree

from ..model.drafts.detect import (
    ALPHA1,
    ATTRIBUTES_ONLY,
    DRAFT_LABELS,
    FLAT_INDEX,
    FORMULATION,
    LEGACY_DRAFTS,
    LS_DAE_ROOT,
    LS_NAMESPACE,
)
from ..model.drafts.elements import all_elements, written_name
from ..report.findings import Location, Violation, evidence
from .schema_loader import (
    BUILD_DESCRIPTION_XSD,
    MODEL_DESCRIPTION_XSD,
    SCHEMA_FILES,
    build_description_schema,
    manifest_schema,
    model_description_schema,
)
from .schema_messages import attribute_of, clean_message

RULE = "schema-violation"
MODEL_DESCRIPTION_FILE = "modelDescription.xml"
BUILD_DESCRIPTION_RULE = "build-description-invalid"
BUILD_DESCRIPTION_FILE = "sources/buildDescription.xml"

#: The local name of the root each draft's schema accepts (legacy roots may also be in the ls namespace).
EXPECTED_ROOTS: dict[str, str] = {
    ALPHA1: "fmiDAEManifest",
    FORMULATION: "fmiLayeredStandardManifest",
    LS_DAE_ROOT: "fmi-ls-dae",
    FLAT_INDEX: "fmiLayeredStandardManifest",
    ATTRIBUTES_ONLY: "fmi-dae",
}

XmlInput = Union["etree._ElementTree", "etree._Element"]


# lxml's XMLSchema keeps the last run's error log on the object; one lock keeps runs apart.
_VALIDATE_LOCK = threading.Lock()


def validate_model_description(tree: XmlInput, *, file: str = MODEL_DESCRIPTION_FILE) -> Iterator[Violation]:
    """Validate a parsed ``modelDescription.xml`` against the FMI 3.0 core schema.

    Yields one ``schema-violation`` per XSD error, with the line and XPath of the offending element.
    """
    root = _root_of(tree)
    if etree.QName(root).text != "fmiModelDescription":
        yield _wrong_core_root(root, "modelDescription.xml", "fmiModelDescription", file=file,
                               schema_name=MODEL_DESCRIPTION_XSD, rule=RULE)
        return
    yield from _run(model_description_schema(), tree, file=file, schema_name=MODEL_DESCRIPTION_XSD)


def validate_build_description(tree: XmlInput, *, file: str = BUILD_DESCRIPTION_FILE
                               ) -> Iterator[Violation]:
    """Validate a parsed ``sources/buildDescription.xml`` against ``fmi3BuildDescription.xsd``.

    Yields ``build-description-invalid`` violations (the file of a source FMU; fmpy validate
    rejects an FMU whose build description does not validate).
    """
    root = _root_of(tree)
    if etree.QName(root).text != "fmiBuildDescription":
        yield _wrong_core_root(root, "buildDescription.xml", "fmiBuildDescription", file=file,
                               schema_name=BUILD_DESCRIPTION_XSD, rule=BUILD_DESCRIPTION_RULE)
        return
    yield from _run(build_description_schema(), tree, file=file,
                    schema_name=BUILD_DESCRIPTION_XSD, rule=BUILD_DESCRIPTION_RULE)


def validate_manifest(tree: XmlInput, draft: str, *, file: str) -> Iterator[Violation]:
    """Validate a parsed fmi-ls-dae manifest against our schema for ``draft``.

    For ``unknown`` (or any id without a schema) nothing is yielded: the draft rule reports it.
    Legacy drafts are validated on a copy with layered-standard-namespace elements unqualified.
    """
    if draft not in SCHEMA_FILES:
        return
    root = _root_of(tree)
    schema_name = SCHEMA_FILES[draft]
    expected = EXPECTED_ROOTS[draft]
    qname = etree.QName(root)
    legacy = draft in LEGACY_DRAFTS
    accepted_ns = (None, LS_NAMESPACE) if legacy else (None,)
    if qname.localname != expected or qname.namespace not in accepted_ns:
        if legacy:
            yield _wrong_root(root, draft, expected, file=file, schema_name=schema_name,
                              part="legacy-draft-schema")
        else:
            yield _wrong_root(root, draft, expected, file=file, schema_name=schema_name,
                              part="alpha1-manifest")
        return
    target: XmlInput = tree
    originals: list[etree._Element] | None = None
    if legacy and _has_ls_elements(root):
        target, originals = _unqualified_copy(root)
    if legacy:
        yield from _run(manifest_schema(draft), target, file=file, schema_name=schema_name,
                        originals=originals, part="legacy-draft-schema")
    else:
        yield from _run(manifest_schema(draft), target, file=file, schema_name=schema_name,
                        part="alpha1-manifest", published=True)


def _run(
    schema: etree.XMLSchema,
    target: XmlInput,
    *,
    file: str,
    schema_name: str,
    originals: list[etree._Element] | None = None,
    rule: str = RULE,
    part: str | None = None,
    published: bool = False,
) -> Iterator[Violation]:
    """Validate ``target``; each error is a violation of ``rule`` and ``part``. With
    ``published`` (the alpha.1 manifest), an error the published alpha.1 XSD would not make is
    the part ``beyond-published-xsd`` (:func:`_beyond_published_xsd`)."""
    with _VALIDATE_LOCK:
        valid = schema.validate(target)
        entries = [] if valid else list(schema.error_log)
    seen: set[tuple[str, str]] = set()
    for entry in entries:
        path = entry.path or None
        attribute = attribute_of(entry.message)
        if attribute is not None:
            key = (path or "", attribute)
            if key in seen:
                continue  # a follow-up error on the same attribute (list/union after the item)
            seen.add(key)
        line = entry.line or None
        if originals is not None and path:
            line = _original_line(target, path, originals) or line
        violation = Violation(
            message=clean_message(entry.message),
            location=Location(file=file, line=line, column=entry.column or None, path=path),
            evidence=evidence(schema=schema_name, xsd_error=entry.type_name),
            subject=path,
            rule=rule,
            part=part,
        )
        if published and _beyond_published_xsd(entry, attribute, target):
            violation = replace(violation, part="beyond-published-xsd")
        yield violation


def _wrong_core_root(root: etree._Element, document: str, expected: str, *, file: str,
                     schema_name: str, rule: str) -> Violation:
    """An FMI 3.0 document (modelDescription.xml, buildDescription.xml) with another root."""
    written = written_name(root)
    return Violation(
        message=f"the root element is <{written}>; an FMI 3.0 {document} has the root "
                f"<{expected}> in no namespace",
        location=Location(file=file, line=root.sourceline, path="/" + written),
        evidence=evidence(schema=schema_name),
        subject="/" + written,
        rule=rule,
    )


def _wrong_root(root: etree._Element, draft: str, expected: str, *, file: str, schema_name: str,
                part: str | None = None) -> Violation:
    written = written_name(root)
    namespace = etree.QName(root).namespace
    if draft == ALPHA1 and etree.QName(root).localname == expected:
        message = (
            f"the root <{written}> is in the namespace {namespace}; the fmi-ls-dae 1.0.0-alpha.1 root "
            "<fmiDAEManifest> and its children are in no namespace (only the three fmi-ls: "
            "attributes are qualified): remove the default namespace declaration"
        )
    else:
        message = (
            f"the root element is <{written}>, but the {DRAFT_LABELS[draft]} "
            f"has the root <{expected}>"
        )
    return Violation(
        message=message,
        location=Location(file=file, line=root.sourceline, path="/" + written),
        evidence=evidence(schema=schema_name, root=written, namespace=namespace, expected_root=expected),
        subject="/" + written,
        rule=RULE,
        part=part,
    )


# --------------------------------------------------------------------------------------------
# Helpers

# lsdae's alpha.1 XSD types these elements lsdaeValueReferenceOnly (a valueReference, nothing
# else); the published alpha.1 XSD types them TVariableReference, a restriction of fmi3Unknown
# that still allows these attributes and an <Annotations> child.
_VALUE_REFERENCE_ONLY = ("EnableDAEParameter", "AlgebraicVariable")
_PUBLISHED_ATTRIBUTES = ("dependencies", "dependenciesKind")


def _beyond_published_xsd(entry: etree._LogEntry, attribute: str | None,
                          target: XmlInput) -> bool:
    """Whether an alpha.1 schema error is one only lsdae's stricter XSD makes: an
    EnableDAEParameter or AlgebraicVariable with dependencies, dependenciesKind, or a single
    <Annotations> child and no text."""
    path = entry.path or ""
    if path.rsplit("/", 1)[-1].split("[", 1)[0] not in _VALUE_REFERENCE_ONLY:
        return False
    if entry.type_name == "SCHEMAV_CVC_COMPLEX_TYPE_3_2_1":  # attribute not allowed
        return attribute in _PUBLISHED_ATTRIBUTES
    if entry.type_name != "SCHEMAV_CVC_COMPLEX_TYPE_2_1":    # content where the type is empty
        return False
    try:
        found = _root_of(target).getroottree().xpath(path)
    except etree.XPathError:
        return False
    if not found or not isinstance(found[0], etree._Element):
        return False
    element = found[0]
    children = [c for c in element if isinstance(c.tag, str)]
    texts = [element.text] + [c.tail for c in element]
    return (len(children) == 1 and children[0].tag == "Annotations"
            and not "".join(t or "" for t in texts).strip())


def _root_of(tree: XmlInput) -> etree._Element:
    getroot = getattr(tree, "getroot", None)
    return getroot() if getroot is not None else tree


def _has_ls_elements(root: etree._Element) -> bool:
    return any(etree.QName(e).namespace == LS_NAMESPACE for e in all_elements(root))


def _unqualified_copy(root: etree._Element) -> tuple[etree._Element, list[etree._Element]]:
    """A copy of ``root`` with layered-standard-namespace elements moved to no namespace.

    Returns the copy and the original elements in document order, so an error in the copy can
    be mapped back to its original line (a copy keeps line numbers only below 65536).
    """
    duplicate = copy.deepcopy(root)
    for element in all_elements(duplicate):
        qname = etree.QName(element)
        if qname.namespace == LS_NAMESPACE:
            element.tag = qname.localname
    etree.cleanup_namespaces(duplicate)
    return duplicate, list(root.iter())


def _original_line(copy_root: XmlInput, path: str, originals: list[etree._Element]) -> int | None:
    try:
        found = _root_of(copy_root).getroottree().xpath(path)
    except etree.XPathError:
        return None
    if not found or not isinstance(found[0], etree._Element):
        return None
    index = list(_root_of(copy_root).iter()).index(found[0])
    return originals[index].sourceline if index < len(originals) else None

