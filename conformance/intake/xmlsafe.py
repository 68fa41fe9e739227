"""Parse XML from an untrusted FMU safely, and say precisely why a document cannot be used.

:func:`parse_xml` never expands or fetches entities, never touches the network, keeps source
lines, and never raises: every problem becomes a :class:`~conformance.report.findings.Violation`
with one of these pseudo-rules

- ``xml-not-well-formed``: the first (namespace) well-formedness error, with line and column.
  An undeclared prefix is reported as such even where libxml2 would only warn and build a tree.
- ``xml-unsafe-construct``: a DOCTYPE that declares entities or other markup, or refers to an
  external DTD. Other importers would expand or fetch what lsdae ignores, so the content cannot be
  trusted and no tree is returned.
- ``xml-encoding``: the document is not UTF-8 (FMI requires UTF-8), or, on request, its XML
  declaration does not state the encoding (AR-04); :mod:`conformance.intake.xml_encoding` tells.
"""
from __future__ import annotations

import logging
import re

from dataclasses import replace

from lxml import etree

from conformance.model.drafts.detect import LS_NAMESPACE
from conformance.report.findings import Location, Violation, evidence
from conformance.intake.xml_encoding import ENCODING, encoding_violations

log = logging.getLogger(__name__)

NOT_WELL_FORMED = "xml-not-well-formed"
UNSAFE_CONSTRUCT = "xml-unsafe-construct"

# Namespaces we can suggest when a document uses the prefix without declaring it.
KNOWN_PREFIXES = {
    "fmi-ls": LS_NAMESPACE,
    "xsi": "http://www.w3.org/2001/XMLSchema-instance",
    "xs": "http://www.w3.org/2001/XMLSchema",
}

# The file name of every layered standard's manifest (FMI 3.0.2 §2.6: extra/<ls-name>/...).
_LS_MANIFEST = "fmi-ls-manifest.xml"
_UNDEFINED_PREFIX = re.compile(r"Namespace prefix (\S+?) (?:for (\S+) )?on (\S+) is not defined")
# The root element's name: the first "<" that opens an element (not <?, <!, a comment).
_ROOT_START = re.compile(rb"<(?![?!])[A-Za-z_][\w.:-]*")
# libxml2 error types that mean "entity handling stopped the parse", not a syntax slip.
_ENTITY_ERRORS = ("RESOURCE_LIMIT", "ENTITY", "AMPLIFICATION", "LOOP")
# Limits that hold without XML_PARSE_HUGE: 10 MB text nodes, depth 256, 50000-character names.
_LIMIT_ERRORS = ("ERR_RESOURCE_LIMIT", "ERR_NAME_TOO_LONG")


def make_parser() -> etree.XMLParser:
    """A fresh parser with every network and entity feature turned off."""
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=False,
        remove_comments=False,
        remove_pis=False,
    )


def parse_xml(
    data: bytes, *, file: str, require_declaration: bool = False, bind_prefixes: bool = False
) -> tuple[etree._ElementTree | None, list[Violation]]:
    """Parse ``data`` (the bytes of ``file`` inside the FMU) without ever trusting it.

    Returns the tree, or None when the document is not well-formed or not safe to use, and the
    violations found. With ``require_declaration`` a missing ``<?xml ... encoding="UTF-8"?>``
    declaration is reported (AR-04 asks it of modelDescription.xml). With ``bind_prefixes``, a
    document whose only fault is a known prefix used without its declaration (``fmi-ls:``, as
    one exporter writes the manifest) is still reported as not namespace-well-formed, and then
    read the way importers read it, the prefix bound to its namespace, so that the other rules
    run in the same pass. Never raises.
    """
    try:
        tree, violations = _parse(bytes(data), file=file, require_declaration=require_declaration,
                                  bind_prefixes=bind_prefixes)
    except Exception as exc:  # untrusted input: anything unexpected is a finding, not a crash
        log.debug("unexpected failure parsing %s", file, exc_info=True)
        message = f"cannot be parsed: {type(exc).__name__}: {exc}"
        tree, violations = None, [Violation(message, Location(file=file), rule=NOT_WELL_FORMED)]
    # The messages above are predicates ("is not well-formed ..."); name their subject.
    name = file.rsplit("/", 1)[-1]
    return tree, [replace(v, message=f"{name} {v.message}") for v in violations]


def _parse(
    data: bytes, *, file: str, require_declaration: bool, bind_prefixes: bool = False
) -> tuple[etree._ElementTree | None, list[Violation]]:
    where = Location(file=file)
    if not data.strip():
        msg = "is empty" if not data else "contains only white space"
        return None, [Violation(f"{msg}; a well-formed document has a root element", where,
                                rule=NOT_WELL_FORMED)]
    violations = encoding_violations(data, where, require_declaration=require_declaration)
    parser = make_parser()
    root = None
    failure = ""
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        failure = str(exc)
    # In log order: the first error-level entry, or an undeclared prefix, which some libxml2
    # versions report only as a warning while still building a tree.
    problems = [e for e in parser.error_log if e.level >= etree.ErrorLevels.ERROR
                or e.type_name == "NS_ERR_UNDEFINED_NAMESPACE"]
    if root is not None and not problems:
        tree = root.getroottree()
        unsafe = _doctype_violations(tree, data, where)
        if unsafe:
            return None, violations + unsafe
        return tree, violations
    if not problems:
        return None, violations + [Violation(
            f"is not well-formed XML: {failure or 'no root element'}", where, rule=NOT_WELL_FORMED)]
    found = _failure_violations(problems, data, file, violations)
    if bind_prefixes:
        bound = _read_with_prefixes_bound(data, problems, file)
        if bound is not None:
            tree, uris = bound
            note = evidence(read_as_importers_do=[f'xmlns:{p}="{u}"' for p, u in uris.items()])
            return tree, violations + [replace(v, evidence=v.evidence + note) for v in found]
    return None, violations + found


def _read_with_prefixes_bound(data: bytes, problems: list[etree._LogEntry], file: str
                              ) -> tuple[etree._ElementTree, dict[str, str]] | None:
    """The tree of ``data`` with its undeclared known prefixes declared on the root element, or
    None when anything else is wrong (then nothing is read). The declarations go into the root
    start tag, on its line, so every line number stays as it was."""
    uris: dict[str, str] = {}
    for problem in problems:
        match = _UNDEFINED_PREFIX.search(problem.message or "")
        if problem.type_name != "NS_ERR_UNDEFINED_NAMESPACE" or match is None:
            return None
        prefix = match.group(1)
        if prefix not in KNOWN_PREFIXES:
            return None
        uris[prefix] = KNOWN_PREFIXES[prefix]
    root = _ROOT_START.search(data)
    if root is None or not uris:
        return None
    declarations = "".join(f' xmlns:{p}="{u}"' for p, u in uris.items()).encode()
    fixed = data[:root.end()] + declarations + data[root.end():]
    tree, violations = _parse(fixed, file=file, require_declaration=False)
    if tree is None or any(v.rule == NOT_WELL_FORMED for v in violations):
        return None
    return tree, uris


def _failure_violations(problems: list[etree._LogEntry], data: bytes, file: str,
                        earlier: list[Violation]) -> list[Violation]:
    """Say why the parse failed: unsafe construct, parser limit, encoding, or a syntax error."""
    first = problems[0]
    kind = first.type_name
    detail = _clip(first.message)
    at = Location(file=file, line=first.line or None, column=first.column or None)
    ev = evidence(libxml2=kind)
    entities = _contains(data, "<!ENTITY")
    if entities and any(t in kind for t in _ENTITY_ERRORS):
        return [Violation("declares entities in a DOCTYPE, and the parser stopped at its safety "
                          f"limits where they are used ({_without_hint(detail)}); lsdae never "
                          "expands or fetches entities, and the document is not used",
                          at, ev, rule=UNSAFE_CONSTRUCT)]
    if kind.startswith("IO_") and _contains(data, "<!DOCTYPE"):
        return [Violation(f"refers to an external DTD or entity ({detail}); it is never fetched, "
                          "and the document is not used", at, ev, rule=UNSAFE_CONSTRUCT)]
    if kind in _LIMIT_ERRORS:
        return [Violation(f"exceeds a safety limit of the XML parser ({_without_hint(detail)}); "
                          "lsdae keeps these limits for every file, so the document is not used",
                          at, ev, rule=UNSAFE_CONSTRUCT)]
    out = []
    if kind == "ERR_UNSUPPORTED_ENCODING" and not any(v.rule == ENCODING for v in earlier):
        out.append(Violation(f"declares an encoding that cannot be decoded ({detail}); FMI "
                             "requires UTF-8", Location(file=file), rule=ENCODING))
    out.append(_syntax_violation(first, file, further=len(problems) - 1))
    if entities:
        out.append(Violation("declares entities in a DOCTYPE; entities are never expanded or "
                             "fetched", Location(file=file), rule=UNSAFE_CONSTRUCT))
    return out


_HUGE_HINT = re.compile(r"[,;:]?\s*(?:try\s+)?(?:use\s+)?(?:the\s+)?XML_PARSE_HUGE\s*(?:option)?",
                        re.IGNORECASE)


def _without_hint(detail: str) -> str:
    """libxml2's message without its advice to lift the limit (XML_PARSE_HUGE): lsdae never
    lifts it, so repeating the advice would only mislead."""
    return _HUGE_HINT.sub("", detail).strip().rstrip(",;:") or detail


def _syntax_violation(err: etree._LogEntry, file: str, *, further: int) -> Violation:
    where = Location(file=file, line=err.line or None, column=err.column or None)
    text = _clip(err.message)
    ev: dict[str, object] = {"libxml2": err.type_name}
    if further > 0:
        ev["further_errors"] = further
    match = _UNDEFINED_PREFIX.search(text)
    if err.type_name == "NS_ERR_UNDEFINED_NAMESPACE" and match:
        prefix, attribute, element = match.groups()
        uri = KNOWN_PREFIXES.get(prefix)
        fix = f'add xmlns:{prefix}="{uri}"' if uri else f'declare it with xmlns:{prefix}="..."'
        message = (f"is not namespace-well-formed: namespace prefix '{prefix}' is used but never "
                   f"declared ({fix} to the root element)")
        ev.update(prefix=prefix, element=element)
        if attribute:
            ev["attribute"] = f"{prefix}:{attribute}"
        if uri is not None and file.rsplit("/", 1)[-1] == _LS_MANIFEST:
            # a layered-standard manifest whose fmi-ls: (or xsi:, xs:) prefix is not declared
            return Violation(message, where, evidence(ev), rule=NOT_WELL_FORMED,
                             part="undeclared-fmi-ls-prefix")
        return Violation(message, where, evidence(ev), rule=NOT_WELL_FORMED)
    if err.type_name == "ERR_INVALID_ENCODING" or "Invalid bytes in character encoding" in text:
        message = ("contains bytes that are not valid in its encoding (FMI requires UTF-8; "
                   "a Latin-1 file without an encoding declaration looks like this)")
        return Violation(message, where, evidence(ev), rule=NOT_WELL_FORMED)
    return Violation(f"is not well-formed XML: {text}", where, evidence(ev), rule=NOT_WELL_FORMED)


def _clip(text: str | None, limit: int = 200) -> str:
    """Untrusted text made safe to print: no control characters, bounded length."""
    text = "".join(c if c.isprintable() else " " for c in (text or "").strip())
    return text if len(text) <= limit else text[:limit] + "..."


def _contains(data: bytes, needle: str) -> bool:
    return any(needle.encode(enc) in data for enc in ("ascii", "utf-16-le", "utf-16-be"))


def _doctype_violations(tree: etree._ElementTree, data: bytes, where: Location) -> list[Violation]:
    info = tree.docinfo
    dtd = info.internalDTD
    entities = list(dtd.iterentities()) if dtd is not None else []
    declarations = list(dtd.iterelements()) if dtd is not None else []
    external = info.system_url or info.public_id
    if not (entities or declarations or external):
        return []
    at = Location(file=where.file, line=_doctype_line(data))
    fetched = [e for e in entities if e.system_url]
    names = [e.name for e in entities]
    if fetched:
        first = fetched[0]
        message = (f"declares an external entity '{_clip(first.name)}' referring to "
                   f"'{_clip(first.system_url)}' (XXE); it is never fetched, and the document "
                   "is not used")
    elif entities:
        shown = ", ".join(_clip(n, 40) for n in names[:5]) + (", ..." if len(names) > 5 else "")
        message = (f"declares {len(entities)} entit{'y' if len(entities) == 1 else 'ies'} in a "
                   f"DOCTYPE ({shown}); entities are never expanded (a nested set is the "
                   "'billion laughs' attack), and the document is not used")
    elif external:
        message = (f"refers to an external DTD '{_clip(external)}'; it is never fetched, and other "
                   "importers could read different content, so the document is not used")
    else:
        message = ("declares markup in a DOCTYPE; other importers would apply it (default "
                   "attributes), so the document is not used")
    ev = evidence(entities=names[:20], external_dtd=external or None)
    return [Violation(message, at, ev, rule=UNSAFE_CONSTRUCT)]


def _doctype_line(data: bytes) -> int | None:
    """The line of ``<!DOCTYPE``: libxml2 keeps no line for it."""
    for enc in ("ascii", "utf-16-le", "utf-16-be"):
        index = data.find("<!DOCTYPE".encode(enc))
        if index >= 0:
            return data.count("\n".encode(enc), 0, index) + 1
    return None

