"""Static checks: where the manifest lives and its three ``fmi-ls:`` header attributes.

Digest B1 (DAE-01 to DAE-04) and FMI §2.6 (LS-02, LS-03). The header is what lets an importer
recognise the layered standard at all, so these rules apply to every draft shape.
"""
from __future__ import annotations

import re
from typing import Iterator

from .context import CheckContext
from ..model.drafts.detect import ALPHA1, ALPHA1_DESCRIPTION, ALPHA1_NAME, ALPHA1_VERSION
from ..report.findings import Location, Violation, evidence
from ..model.drafts.migrate import LEGACY_SHAPE_CAUSE
from ..model.manifest import MANIFEST, Manifest

MANIFEST_FILE = "fmi-ls-manifest.xml"

# https://semver.org/#is-there-a-suggested-regular-expression-regex-to-check-a-semver-string
_PRE_ID = r"(?:0|[1-9]\d*|\d*[A-Za-z-][0-9A-Za-z-]*)"
_SEMVER = re.compile(
    r"^(0|[1-9]\d*)\.(0|[1-9]\d*)\.(0|[1-9]\d*)"
    rf"(?:-({_PRE_ID}(?:\.{_PRE_ID})*))?"
    r"(?:\+[0-9A-Za-z-]+(?:\.[0-9A-Za-z-]+)*)?$")
# What the pre-alpha drafts wrote (0.1, 0.0.1, 0.1.0): one to three numeric components.
_VERSION_LIKE = re.compile(r"^\d+(?:\.\d+){0,2}(?:-[0-9A-Za-z.-]+)?(?:\+[0-9A-Za-z.-]+)?$")


def _semver_key(text: str) -> tuple | None:
    """Precedence key of a strict semver string (semver §11), or None if it is not one."""
    m = _SEMVER.match(text)
    if m is None:
        return None
    pre = m.group(4)
    ids = () if pre is None else tuple(
        (0, _numeric(p), "") if p.isdigit() else (1, (0, ""), p) for p in pre.split("."))
    # a release ranks above every pre-release of the same version
    return (_numeric(m.group(1)), _numeric(m.group(2)), _numeric(m.group(3)), pre is None, ids)


def _numeric(digits: str) -> tuple[int, str]:
    """A numeric identifier's rank without int(): no leading zeros, so the longer is larger and
    equal lengths compare as text (a component of thousands of digits is not an exception)."""
    return (len(digits), digits)


_ALPHA1_KEY: tuple = _semver_key(ALPHA1_VERSION) or ()


def _is_older_than_alpha1(version: str) -> bool:
    """Whether a version (strict semver, or a short draft number like 0.1) precedes alpha.1."""
    key = _semver_key(version)
    if key is None and _VERSION_LIKE.match(version):
        core = re.split(r"[-+]", version, maxsplit=1)[0].split(".")
        key = _semver_key(".".join(c.lstrip("0") or "0" for c in (core + ["0", "0"])[:3]))
    return key is not None and key < _ALPHA1_KEY


def newer_than_alpha1(version: str) -> bool:
    """Whether ``version`` is a strict semantic version that comes after 1.0.0-alpha.1."""
    key = _semver_key(version)
    return key is not None and key > _ALPHA1_KEY


def _names_dae(folder: str) -> bool:
    """Whether a folder name has "dae" as a word: fmi-ls-dae, DAE, FmiLsDae; not daemon."""
    words = re.sub(r"([a-z0-9])([A-Z])", r"\1 \2", folder)
    return "dae" in re.split(r"[^a-z0-9]+", words.lower())


def _root(m: Manifest, attribute: str | None = None) -> Location:
    path = f"/{m.root_name}" + (f"/@fmi-ls:{attribute}" if attribute else "")
    return Location(file=m.file, line=m.root_line, path=path)


def _unqualified(m: Manifest, attribute: str) -> Violation | None:
    """The attribute was written without the fmi-ls namespace (DAE-04): it does not count."""
    if attribute not in m.unqualified_ls_attributes:
        return None
    return Violation(
        "the manifest root carries {subject} without the fmi-ls namespace, so it does not count; "
        'write it as fmi-ls:%s with xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"'
        % attribute,
        _root(m, attribute), evidence(attribute=attribute, qualified=False), subject=attribute,
        part="missing-or-unqualified")


def _missing(m: Manifest, attribute: str, expected: str) -> Violation:
    return Violation(
        'the manifest root has no {subject} attribute; add fmi-ls:%s="%s"' % (attribute, expected),
        _root(m, attribute), evidence(attribute=attribute, expected=expected), subject=attribute,
        part="missing-or-unqualified")


def _legacy_shape(ctx: CheckContext, m: Manifest) -> bool:
    """Whether the manifest has a pre-alpha.1 shape, which the alpha.1 XSD's fixed values do not
    bind."""
    return not (m.draft == ALPHA1 or ctx.draft == ALPHA1)


# ---------------------------------------------------------------------------------------------
def manifest_location(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-01/LS-01: a DAE manifest stored anywhere but the standard path is never read."""
    if MANIFEST in ctx.names:
        return
    for name in ctx.names:
        parts = name.strip("/").split("/")
        if parts[-1].lower() != MANIFEST_FILE:
            continue
        if len(parts) > 1 and not any(_names_dae(p) for p in parts[:-1]):
            continue  # another layered standard's manifest
        yield Violation(
            "an fmi-ls-dae manifest is stored as {subject}, where importers do not look for it, "
            "so the FMU is treated as a plain Model Exchange FMU; move it to " + MANIFEST,
            Location(file=name), evidence(found=name, expected=MANIFEST), subject=name)


def ls_name_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-02/D-03: fmi-ls-name must be the reverse-DNS name of the layered standard."""
    m = ctx.manifest
    if m is None:
        return
    attribute = "fmi-ls-name"
    if m.ls_name is None:
        yield _unqualified(m, attribute) or _missing(m, attribute, ALPHA1_NAME)
    elif m.ls_name != ALPHA1_NAME:
        legacy = _legacy_shape(ctx, m)
        yield Violation(
            'the manifest\'s {subject} is not "%s"; importers recognise the layered standard '
            "by this exact reverse-DNS name" % ALPHA1_NAME,
            _root(m, attribute), evidence(expected=ALPHA1_NAME, actual=m.ls_name),
            subject=attribute, part="legacy-shape-name" if legacy else None,
            cause=LEGACY_SHAPE_CAUSE if legacy else None)


def ls_version_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """LS-02/DAE-02/D-04: fmi-ls-version present, version-shaped, and consistent with the shape."""
    m = ctx.manifest
    if m is None:
        return
    attribute = "fmi-ls-version"
    version = m.ls_version
    if version is None:
        yield _unqualified(m, attribute) or _missing(m, attribute, ALPHA1_VERSION)
        return
    loc = _root(m, attribute)
    text = version.strip()
    if not text:
        yield Violation(
            'the manifest\'s {subject} is empty; set it to "%s"' % ALPHA1_VERSION,
            loc, evidence(actual=version, expected=ALPHA1_VERSION), subject=attribute)
        return
    if not _legacy_shape(ctx, m):
        key = _semver_key(version)
        older = _is_older_than_alpha1(version)
        if older:
            yield Violation(
                "the manifest's {subject} names a draft older than 1.0.0-alpha.1 although the "
                'manifest has the 1.0.0-alpha.1 shape; set it to "%s"' % ALPHA1_VERSION,
                loc, evidence(actual=version, expected=ALPHA1_VERSION, reason="older than shape"),
                subject=attribute)
        elif key is None:
            yield Violation(
                "the manifest's {subject} is not a semantic version (MAJOR.MINOR.PATCH); "
                'this manifest has the 1.0.0-alpha.1 shape, so set it to "%s"' % ALPHA1_VERSION,
                loc, evidence(actual=version, expected=ALPHA1_VERSION, reason="not semver"),
                subject=attribute)
    elif not _VERSION_LIKE.match(version):
        yield Violation(
            "the manifest's {subject} is not a version number (MAJOR.MINOR.PATCH); "
            'the current version is "%s"' % ALPHA1_VERSION,
            loc, evidence(actual=version, expected=ALPHA1_VERSION, reason="not a version"),
            subject=attribute, part="legacy-not-version-like", cause=LEGACY_SHAPE_CAUSE)


def _description_difference(actual: str) -> str:
    """Say in a few words how a description differs from the fixed text."""
    if actual + "." == ALPHA1_DESCRIPTION:
        return "the final period is missing"
    if actual.strip() == ALPHA1_DESCRIPTION:
        return "leading or trailing whitespace"
    if " ".join(actual.split()) == ALPHA1_DESCRIPTION:
        return "different whitespace"
    if actual.strip().rstrip(".").lower() == ALPHA1_DESCRIPTION.rstrip(".").lower():
        return "different letter case" + ("" if actual.strip().endswith(".") else
                                          " and no final period")
    if actual.strip().rstrip(".").endswith("in FMU"):
        return 'says "FMU" where the text says "FMI"'
    if not actual.strip():
        return "empty"
    return "different text"


def ls_description_mismatch(ctx: CheckContext) -> Iterator[Violation]:
    """DAE-02/D-04: the alpha.1 XSD fixes fmi-ls-description, final period included."""
    m = ctx.manifest
    if m is None:
        return
    attribute = "fmi-ls-description"
    if m.ls_description is None:
        yield _unqualified(m, attribute) or _missing(m, attribute, ALPHA1_DESCRIPTION)
    elif m.ls_description != ALPHA1_DESCRIPTION:
        legacy = _legacy_shape(ctx, m)
        yield Violation(
            'the manifest\'s {subject} differs from the fixed text "%s"' % ALPHA1_DESCRIPTION,
            _root(m, attribute),
            evidence(expected=ALPHA1_DESCRIPTION, actual=m.ls_description,
                     difference=_description_difference(m.ls_description)),
            subject=attribute, part="legacy-shape-text" if legacy else None,
            cause=LEGACY_SHAPE_CAUSE if legacy else None)


CHECKS = {
    "DAE101": manifest_location,
    "DAE102": ls_name_mismatch,
    "DAE103": ls_version_invalid,
    "DAE104": ls_description_mismatch,
}
