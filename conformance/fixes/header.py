"""The three fmi-ls: header fields of the manifest root, as edits of its start tag."""
from __future__ import annotations

from ..model.drafts.detect import ALPHA1_DESCRIPTION, ALPHA1_NAME, ALPHA1_VERSION, LS_NAMESPACE
from .change import NoFix
from .edits import Edit
from .xmltext import StartTag, escape

ALPHA1_ROOT = "fmiDAEManifest"
HEADER = {"fmi-ls-name": ALPHA1_NAME, "fmi-ls-version": ALPHA1_VERSION,
          "fmi-ls-description": ALPHA1_DESCRIPTION}


def header_edits(file: str, tag: StartTag, attributes: list[str], *,
                 only_if_wrong: bool = False) -> list[Edit]:
    """Set each named header attribute to its fixed value: the value of a qualified attribute is
    replaced, an unqualified one is qualified, a missing one is added before the tag's end, and
    the fmi-ls prefix is declared when no prefix is bound to the namespace."""
    prefixes = tag.prefixes_for(LS_NAMESPACE)
    prefix = prefixes[0] if prefixes else "fmi-ls"
    edits: list[Edit] = []
    insert = b""
    for attribute in attributes:
        wanted = HEADER[attribute]
        qualified = next((tag.attribute(f"{p}:{attribute}") for p in prefixes
                          if tag.attribute(f"{p}:{attribute}") is not None), None)
        bare = tag.attribute(attribute)
        if qualified is not None:
            if not (only_if_wrong and qualified.value == wanted):
                edits.append(Edit(file, qualified.value_start, qualified.value_end,
                                  escape(wanted, qualified.quote)))
        elif bare is not None:
            end = bare.name_start + len(attribute)
            edits.append(Edit(file, bare.name_start, end, f"{prefix}:{attribute}".encode()))
            if bare.value != wanted:
                edits.append(Edit(file, bare.value_start, bare.value_end,
                                  escape(wanted, bare.quote)))
        else:
            insert += f' {prefix}:{attribute}="'.encode() + escape(wanted) + b'"'
    if not prefixes and (insert or edits):
        if tag.attribute("xmlns:fmi-ls") is not None:
            raise NoFix("the prefix fmi-ls is bound to another namespace")
        insert = f' xmlns:fmi-ls="{LS_NAMESPACE}"'.encode() + insert
    if insert:
        edits.append(Edit(file, tag.close, tag.close, insert))
    return edits
