"""Static checks: what a manifest takes from drafts newer than 1.0.0-alpha.1 (drafts in motion).

lsdae checks the normative draft, 1.0.0-alpha.1; the working group goes on. A manifest that
declares a later version, or uses the ``<Invariant>`` element that only the working group's
"ODE with invariants" text defines, is checked as alpha.1 all the same, but the importers that
read alpha.1 strictly reject it: fmi-rs and fmusim (through fmi-rs) accept exactly
``fmi-ls-version="1.0.0-alpha.1"`` and validate the manifest against the alpha.1 XSD they vendor
(modelica/Modelica-FMI, ``fmi-rs/src/schema/dae/``), which has no ``<Invariant>``. Each is one
warning saying what the FMU declares, what lsdae checked it against, and who rejects it.
"""
from __future__ import annotations

from typing import Iterator

from .context import CheckContext
from ..model.drafts.detect import ALPHA1, ALPHA1_VERSION
from ..report.findings import Location, Violation, evidence
from .header import newer_than_alpha1

STRICT_IMPORTERS = ("fmi-rs", "fmusim")


def ls_version_unknown(ctx: CheckContext) -> Iterator[Violation]:
    """D-04, DAE-02: the alpha.1-shaped manifest declares a later version than lsdae knows."""
    m = ctx.manifest
    if m is None or m.ls_version is None or (m.draft != ALPHA1 and ctx.draft != ALPHA1):
        return
    version = m.ls_version.strip()
    if not newer_than_alpha1(version):  # older, or not a version: ls-version-invalid
        return
    yield Violation(
        f'the manifest declares fmi-ls-version "{version}", a version lsdae does not know: it '
        f'was checked against {ALPHA1_VERSION}, the normative draft, and is labelled so in this '
        f'report; {" and ".join(STRICT_IMPORTERS)} accept exactly "{ALPHA1_VERSION}" and reject '
        "the manifest", Location(file=m.file, line=m.root_line,
                                 path=f"/{m.root_name}/@fmi-ls:fmi-ls-version"),
        evidence(declared=version, checked_against=ALPHA1_VERSION,
                 rejected_by=list(STRICT_IMPORTERS)),
        subject=version)


def invariant_rejected_by_importers(ctx: CheckContext) -> Iterator[Violation]:
    """D-13, Q-07: ``<Invariant>`` is in our alpha.1 XSD but in no text of alpha.1, and the
    alpha.1 XSD the strict importers vendor rejects it."""
    m = ctx.manifest
    if m is None:
        return
    for u in m.unknowns("Invariant"):
        yield Violation(
            "the manifest's <ModelStructure> has an <Invariant>, which only the working "
            "group's \"ODE with invariants\" text defines, not 1.0.0-alpha.1: lsdae accepts it "
            f"(and probes it, invariant-drift), but {' and '.join(STRICT_IMPORTERS)} validate "
            "the manifest against the alpha.1 XSD they vendor, which has no <Invariant>, and "
            "reject the whole manifest", Location(file=u.file, line=u.line, path=u.path),
            evidence(value_reference=u.vr, rejected_by=list(STRICT_IMPORTERS),
                     schema="modelica/Modelica-FMI fmi-rs/src/schema/dae/ (alpha.1)"),
            subject=str(u.vr))


CHECKS = {
    "DAE105": ls_version_unknown,
    "DAE427": invariant_rejected_by_importers,
}
