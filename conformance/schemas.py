"""XML Schema validation of modelDescription.xml and of the fmi-ls-dae manifest.

Both use lxml (libxml2): it validates an 18 MB modelDescription in a fraction of a second,
and its error log gives a line and an XPath for every error, which is all a finding needs.

Where the schemas come from:

- ``modelDescription.xml``: ``fmi3ModelDescription.xsd`` of the FMI 3.0 core, read at run time
  from the installed fmpy package (``fmpy/schema/fmi3``); never copied, never fetched.
- the manifest: ``schemas/fmi-ls-dae-<draft>.xsd`` (ours, one per draft). They reference the core
  schemas through the virtual location ``fmi-core/<file>.xsd``, which the resolver below maps to
  the same fmpy folder.

Loading never touches the network: every schema document is parsed with ``no_network=True`` and a
resolver that raises :class:`SchemaLoadError` for any http(s)/ftp location instead of fetching it.

Legacy manifests may put their elements in the layered-standard namespace (as default namespace or
with the ``fmi-ls:`` prefix) or leave them unqualified. Their schemas describe unqualified elements
only; :func:`validate_manifest` validates a copy in which elements of that namespace are moved to
no namespace (attributes untouched), so one schema covers every namespace variant of a draft.
The 1.0.0-alpha.1 manifest is validated as it is: its elements must be in no namespace.

Messages are libxml2's, tidied by :mod:`conformance.schema_messages`. A follow-up error on an
attribute that already has an error (libxml2 reports a bad list value twice, once for the item
and once for the list) is dropped.
"""
from __future__ import annotations

import copy
import functools
import importlib.util
import logging
import re
import threading
from pathlib import Path
from typing import Iterator, Union

from lxml import etree

from .drafts.detect import (
    ALPHA1,
    ATTRIBUTES_ONLY,
    DRAFT_LABELS,
    FLAT_INDEX,
    FORMULATION,
    LEGACY_DRAFTS,
    LS_DAE_ROOT,
    LS_NAMESPACE,
)
from .drafts.elements import all_elements, written_name
from .findings import Location, Violation, evidence
from .paths import schemas_dir
from .schema_messages import attribute_of, clean_message

log = logging.getLogger(__name__)

RULE = "schema-violation"
MODEL_DESCRIPTION_FILE = "modelDescription.xml"
MODEL_DESCRIPTION_XSD = "fmi3ModelDescription.xsd"

#: Our schema file for each draft id (in the ``schemas/`` folder).
SCHEMA_FILES: dict[str, str] = {
    ALPHA1: "fmi-ls-dae-alpha1.xsd",
    FORMULATION: "fmi-ls-dae-formulation.xsd",
    LS_DAE_ROOT: "fmi-ls-dae-ls-dae-root.xsd",
    FLAT_INDEX: "fmi-ls-dae-flat-index.xsd",
    ATTRIBUTES_ONLY: "fmi-ls-dae-attributes-only.xsd",
}

#: The local name of the root each draft's schema accepts (legacy roots may also be in the ls namespace).
EXPECTED_ROOTS: dict[str, str] = {
    ALPHA1: "fmiDAEManifest",
    FORMULATION: "fmiLayeredStandardManifest",
    LS_DAE_ROOT: "fmi-ls-dae",
    FLAT_INDEX: "fmiLayeredStandardManifest",
    ATTRIBUTES_ONLY: "fmi-dae",
}

_CORE_PREFIX = "fmi-core/"
_REMOTE = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*://")

XmlInput = Union["etree._ElementTree", "etree._Element"]


class SchemaLoadError(RuntimeError):
    """A schema could not be loaded: a file is missing, fmpy is absent, or a remote URL was asked for."""


# --------------------------------------------------------------------------------------------
# Locating and loading schemas


def schema_dir() -> Path:
    """The folder holding our per-draft XSDs (``schemas/``, or ``conformance/_schemas`` in a wheel)."""
    folder = schemas_dir()
    if not (folder / SCHEMA_FILES[ALPHA1]).is_file():
        raise SchemaLoadError(f"the lsdae schemas are missing from {folder}")
    return folder


def core_schema_dir() -> Path:
    """The FMI 3.0 core schemas installed with fmpy (``fmpy/schema/fmi3``), found without importing fmpy."""
    spec = importlib.util.find_spec("fmpy")
    if spec is None or not spec.submodule_search_locations:
        raise SchemaLoadError("fmpy is not installed; lsdae reads the FMI 3.0 core schemas from it")
    folder = Path(next(iter(spec.submodule_search_locations))) / "schema" / "fmi3"
    if not (folder / MODEL_DESCRIPTION_XSD).is_file():
        raise SchemaLoadError(f"the FMI 3.0 core schemas are missing from {folder}")
    return folder


class _OfflineResolver(etree.Resolver):
    """Maps ``.../fmi-core/<file>.xsd`` to fmpy's core schemas and refuses every remote URL."""

    def __init__(self, core: Path) -> None:
        super().__init__()
        self.core = core
        self.refused: list[str] = []

    def resolve(self, system_url: str | None, public_id: str | None, context: object) -> object:
        url = system_url or ""
        if _REMOTE.match(url) and not url.startswith("file://"):
            self.refused.append(url)
            raise SchemaLoadError(f"refused to fetch {url}: lsdae never uses the network")
        marker = url.replace("\\", "/").rfind("/" + _CORE_PREFIX)
        if marker >= 0 or url.startswith(_CORE_PREFIX):
            name = url[marker + 1 + len(_CORE_PREFIX):] if marker >= 0 else url[len(_CORE_PREFIX):]
            target = self.core / name
            if "/" in name or not target.is_file():
                raise SchemaLoadError(f"no FMI core schema {name!r} in {self.core}")
            return self.resolve_filename(str(target), context)
        return None  # a local file next to the including schema: let libxml2 read it


def _load_schema(path: Path) -> etree.XMLSchema:
    """Parse one XSD (and everything it includes or imports) offline."""
    resolver = _OfflineResolver(core_schema_dir())
    parser = etree.XMLParser(no_network=True, resolve_entities=False, load_dtd=False)
    parser.resolvers.add(resolver)
    try:
        document = etree.parse(str(path), parser)
        schema = etree.XMLSchema(document)
    except (etree.XMLSchemaParseError, etree.XMLSyntaxError, OSError) as exc:
        if resolver.refused:
            raise SchemaLoadError(
                f"{path.name}: refused to fetch {resolver.refused[0]}: lsdae never uses the network"
            ) from exc
        raise SchemaLoadError(f"{path.name}: {exc}") from exc
    if resolver.refused:  # libxml2 may carry on after a failed import; we do not
        raise SchemaLoadError(f"{path.name}: refused to fetch {resolver.refused[0]}")
    log.debug("loaded schema %s", path)
    return schema


@functools.lru_cache(maxsize=None)
def model_description_schema() -> etree.XMLSchema:
    """``fmi3ModelDescription.xsd`` from fmpy, loaded once per process."""
    return _load_schema(core_schema_dir() / MODEL_DESCRIPTION_XSD)


@functools.lru_cache(maxsize=None)
def manifest_schema(draft: str) -> etree.XMLSchema:
    """Our XSD for a draft id of :mod:`conformance.drafts.detect`, loaded once per process."""
    try:
        name = SCHEMA_FILES[draft]
    except KeyError:
        raise ValueError(f"no schema for draft {draft!r}") from None
    return _load_schema(schema_dir() / name)


def clear_schema_cache() -> None:
    """Forget every loaded schema (tests use this to prove that loading stays offline)."""
    model_description_schema.cache_clear()
    manifest_schema.cache_clear()


# --------------------------------------------------------------------------------------------
# Validation

# lxml's XMLSchema keeps the last run's error log on the object; one lock keeps runs apart.
_VALIDATE_LOCK = threading.Lock()


def validate_model_description(tree: XmlInput, *, file: str = MODEL_DESCRIPTION_FILE) -> Iterator[Violation]:
    """Validate a parsed ``modelDescription.xml`` against the FMI 3.0 core schema.

    Yields one ``schema-violation`` per XSD error, with the line and XPath of the offending element.
    """
    root = _root_of(tree)
    if etree.QName(root).text != "fmiModelDescription":
        yield Violation(
            message=f"the root element is <{written_name(root)}>; an FMI 3.0 modelDescription.xml "
            "has the root <fmiModelDescription> in no namespace",
            location=Location(file=file, line=root.sourceline, path="/" + written_name(root)),
            evidence=evidence(schema=MODEL_DESCRIPTION_XSD),
            subject="/" + written_name(root),
            rule=RULE,
        )
        return
    yield from _run(model_description_schema(), tree, file=file, schema_name=MODEL_DESCRIPTION_XSD)


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
        yield _wrong_root(root, draft, expected, file=file, schema_name=schema_name)
        return
    target: XmlInput = tree
    originals: list[etree._Element] | None = None
    if legacy and _has_ls_elements(root):
        target, originals = _unqualified_copy(root)
    yield from _run(manifest_schema(draft), target, file=file, schema_name=schema_name, originals=originals)


def _run(
    schema: etree.XMLSchema,
    target: XmlInput,
    *,
    file: str,
    schema_name: str,
    originals: list[etree._Element] | None = None,
) -> Iterator[Violation]:
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
        yield Violation(
            message=clean_message(entry.message),
            location=Location(file=file, line=line, column=entry.column or None, path=path),
            evidence=evidence(schema=schema_name, xsd_error=entry.type_name),
            subject=path,
            rule=RULE,
        )


def _wrong_root(root: etree._Element, draft: str, expected: str, *, file: str, schema_name: str) -> Violation:
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
    )


# --------------------------------------------------------------------------------------------
# Helpers


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
