"""libxml2 schema error messages, tidied for a finding.

Clark names ``{uri}local`` become ``fmi-ls:local``, enumeration sets are spelled out without
braces, and the ``Expected is ( .. )`` phrasing is made readable. :func:`attribute_of` names the
attribute a message is about, so that :mod:`conformance.intake.schemas` can drop a follow-up error on an
attribute that already has one.
"""
from __future__ import annotations

import re

from ..model.drafts.detect import LS_NAMESPACE

_XSI_NAMESPACE = "http://www.w3.org/2001/XMLSchema-instance"
_PREFIXES = {LS_NAMESPACE: "fmi-ls", _XSI_NAMESPACE: "xsi"}

_ATTRIBUTE_RE = re.compile(r"^Element '[^']*', attribute '([^']*)':")
_CLARK_RE = re.compile(r"\{([^{}'\s]+)\}([A-Za-z_][\w.-]*)")
_SET_RE = re.compile(r"The value ('[^']*') is not an element of the set \{(.*)\}\.?")
_FACET_RE = re.compile(r"\[facet '[^']*'\] ")
_EXPECTED_ONE_RE = re.compile(r"(?<=expected )is one of \( (.*?) \)\.?")
_EXPECTED_RE = re.compile(r"(?<=expected )is \( (.*?) \)\.?")
_REDUNDANT_ATTRIBUTE_RE = re.compile(r"Element ('[^']*'), attribute ('[^']*'): The attribute '[^']*' is not allowed\.?")
_MISSING_ATTRIBUTE_RE = re.compile(r"The attribute ('[^']*') is required but missing\.?")


def attribute_of(message: str) -> str | None:
    """The attribute a libxml2 schema message is about, or None."""
    match = _ATTRIBUTE_RE.match(message)
    return match.group(1) if match else None


def clean_message(message: str) -> str:
    """Tidy a libxml2 schema message: prefixes for namespaces, readable sets and expectations."""
    text = message.strip()
    text = _CLARK_RE.sub(_prefixed, text)
    text = _FACET_RE.sub("", text)
    text = _SET_RE.sub(lambda m: f"the value {m.group(1)} is not one of {m.group(2)}", text)
    text = _REDUNDANT_ATTRIBUTE_RE.sub(r"Element \1: attribute \2 is not allowed", text)
    text = _MISSING_ATTRIBUTE_RE.sub(r"the required attribute \1 is missing", text)
    text = text.replace("This element is not expected. Expected", "this element is not expected here; expected")
    text = text.replace("This element is not expected.", "this element is not expected here.")
    text = text.replace("Missing child element(s). Expected", "missing child element; expected")
    text = text.replace("Element content is not allowed, because the content type is empty",
                        "no child elements are allowed here")
    text = text.replace("No matching global declaration available for the validation root.",
                        "this root element is not declared by the schema.")
    text = _EXPECTED_ONE_RE.sub(lambda m: f"one of {m.group(1)}", text)
    text = _EXPECTED_RE.sub(lambda m: m.group(1), text)
    return text.rstrip(". ").rstrip()


def _prefixed(match: re.Match[str]) -> str:
    namespace, local = match.group(1), match.group(2)
    prefix = _PREFIXES.get(namespace)
    return f"{prefix}:{local}" if prefix else f"[{namespace}]{local}"
