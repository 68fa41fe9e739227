"""Whether an XML document is UTF-8, as FMI requires: its byte-order mark, the NUL bytes of a
wide encoding without one, and the encoding its XML declaration states.

:func:`encoding_violations` reports the ``xml-encoding`` pseudo-rule for
:func:`conformance.intake.xmlsafe.parse_xml`; it reads only the first bytes of the document.
"""
from __future__ import annotations

import re

from conformance.report.findings import Location, Violation, evidence

ENCODING = "xml-encoding"

_DECLARATION = re.compile(rb"^<\?xml\s[^>]*?\?>")
_DECLARED_ENCODING = re.compile(rb"""\sencoding\s*=\s*["']([A-Za-z0-9._:-]*)["']""")
_UTF8_NAMES = {"utf-8", "utf8"}
_BOMS = (
    (b"\xef\xbb\xbf", "UTF-8"),
    (b"\xff\xfe\x00\x00", "UTF-32"),
    (b"\x00\x00\xfe\xff", "UTF-32"),
    (b"\xff\xfe", "UTF-16"),
    (b"\xfe\xff", "UTF-16"),
)


def encoding_violations(data: bytes, where: Location, *,
                        require_declaration: bool) -> list[Violation]:
    """Report a byte-order mark or declaration naming anything but UTF-8."""
    for bom, name in _BOMS:
        if data.startswith(bom):
            if name != "UTF-8":
                return [Violation(f"is encoded as {name} (byte-order mark); FMI requires UTF-8",
                                  where, evidence(encoding=name), rule=ENCODING)]
            data = data[len(bom):]
            break
    else:
        sniffed = _sniff_wide(data)
        if sniffed:
            return [Violation(f"is encoded as {sniffed}; FMI requires UTF-8", where,
                              evidence(encoding=sniffed), rule=ENCODING)]
    declaration = _DECLARATION.match(data[:1024])
    declared = _DECLARED_ENCODING.search(declaration.group(0)) if declaration else None
    if declared:
        name = declared.group(1).decode("ascii", "replace")
        if name.lower() not in _UTF8_NAMES:
            return [Violation(f'declares encoding="{name}"; FMI requires UTF-8', where,
                              evidence(encoding=name), rule=ENCODING)]
        return []
    if require_declaration:
        what = ("has an XML declaration without encoding" if declaration
                else "has no XML declaration")
        return [Violation(f'{what}; FMI asks for <?xml version="1.0" encoding="UTF-8"?> on the '
                          "first line", Location(file=where.file, line=1), rule=ENCODING,
                          part="declaration-missing")]
    return []


def _sniff_wide(data: bytes) -> str | None:
    """UTF-16/32 without a byte-order mark, recognised by the NUL bytes around '<'."""
    head = data[:4]
    if head in (b"<\x00\x00\x00", b"\x00\x00\x00<"):
        return "UTF-32"
    if head[:2] in (b"<\x00", b"\x00<"):
        return "UTF-16"
    return None
