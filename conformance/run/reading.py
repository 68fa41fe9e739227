"""Reading an FMU's XML files for the checks, and the state of one check.

Each file is read once, parsed safely (:mod:`conformance.intake.xmlsafe`), its bytes kept for source
lines (:mod:`conformance.run.source_texts`), and validated against its XSD in a
:class:`~conformance.run.background.Background` thread while the same tree is read into the model
or the manifest. What could not be read is remembered in :class:`RunState`, so that the rules
that need it are listed as not run, with the reason.
"""
from __future__ import annotations

from typing import Sequence

from .background import Background
from .collector import Collector
from ..model.drafts.detect import UNKNOWN, detect_draft, unrecognised_violations
from ..model.drafts.migrate import legacy_violations
from .options import EngineOptions
from ..report.findings import Location, Violation, evidence
from ..intake.fmu import ArchiveReadError
from ..model.layer import layer_declaration, manifest_missing
from ..model.manifest import MANIFEST, Manifest, read_manifest
from ..model.description import MODEL_DESCRIPTION, ModelDescription, read_model_description
from ..intake.schemas import validate_manifest, validate_model_description
from .source_texts import SourceTexts
from ..intake.xmlsafe import parse_xml


class RunState:
    """What one check of one FMU has found out so far, besides its findings: the draft, the
    rules run and skipped (and why), the info for the report, which files were not read."""

    def __init__(self) -> None:
        self.draft: str | None = None
        self.run: set[str] = set()
        self.skipped: set[tuple[str, str]] = set()
        self.not_run: set[tuple[str, str]] = set()   # skipped although they should have run
        self.info: dict[str, object] = {}
        self.unread: dict[str, str] = {}  # need -> why the file it stands for was not read
        self.has_manifest = False
        self.not_checked: str | None = None   # why nothing past the archive was checked

    def skip_for(self, code: str, needs, have, reason: str) -> str:
        """Skip a rule whose ``needs`` are not all there, and return the reason: the layer's
        ``reason`` -- or, when the file a need stands for is there but was not read, that (a
        failure, listed as not run)."""
        missing = [n for n in needs if not have.get(n, False) and n in self.unread]
        if missing:
            reason = self.unread[missing[0]]
            self.not_run.add((code, reason))
        self.skipped.add((code, reason))
        return reason


def _read(source, name: str, collector: Collector) -> bytes | None:
    try:
        return source.read(name)
    except ArchiveReadError as exc:  # limits, corrupt data: the archive layer names the rule
        collector.add_stage([exc.violation])
    except Exception as exc:  # a last resort
        collector.emit("archive-unreadable", Violation(
            f"cannot read {name}: {exc}", Location(file=name)))
    return None


def read_xml(source, name: str, collector: Collector, texts: SourceTexts):
    """Read and safely parse one XML member; keep its bytes for source excerpts. The manifest
    is read as importers read it when its only fault is an undeclared fmi-ls prefix."""
    data = _read(source, name, collector)
    if data is None:
        return None
    texts.keep(name, data)
    tree, violations = parse_xml(data, file=name, bind_prefixes=name == MANIFEST)
    collector.add_stage(violations)
    return tree


def _not_read(source, name: str, need: str, info_key: str, state: RunState) -> bool:
    """Whether ``name`` is in the FMU but was left out by an archive finding (too large, unsafe):
    then it is "not read because of" that finding, not missing."""
    rule = source.excluded().get(name)
    if rule is None:
        return False
    state.unread[need] = f"{name} not read because of {rule}"
    state.info[info_key] = f"not read because of {rule}"
    return True


def read_model(source, names: Sequence[str], options: EngineOptions, collector: Collector,
                texts: SourceTexts, state: RunState) -> ModelDescription | None:
    if MODEL_DESCRIPTION not in names:
        if not _not_read(source, MODEL_DESCRIPTION, "model-description", "modelDescription",
                         state):
            collector.emit("model-description-missing", Violation(
                "the FMU has no modelDescription.xml at its root",
                Location(file=MODEL_DESCRIPTION)))
        return None
    tree = read_xml(source, MODEL_DESCRIPTION, collector, texts)
    if tree is None:
        state.unread["model-description"] = f"{MODEL_DESCRIPTION} cannot be read or parsed"
        return None
    version = (tree.getroot().get("fmiVersion") or "").strip()
    if version[:2] in ("1.", "2."):  # out of scope: said once, nothing else is checked
        # an FMI 1.0/2.0 FMU that carries files of the fmi-ls-dae folder claims the layer
        layer = layer_declaration(None, names) is not None
        collector.emit("fmi-version-unsupported", Violation(
            f"an FMI {version} FMU: fmi-ls-dae is a layered standard of FMI 3.0, so this FMU "
            "is not checked", Location(file=MODEL_DESCRIPTION, line=tree.getroot().sourceline,
                                       path="/fmiModelDescription"),
            evidence(fmi_version=version), part="fmi2-with-dae-layer" if layer else None))
        state.not_checked = f"FMI {version} FMU: fmi-ls-dae needs FMI 3.0"
        return None
    if options.probes_only:
        return read_model_description(tree, file=MODEL_DESCRIPTION)
    # the XSD validation (libxml2, without the GIL) runs beside the reading of the same tree
    validation = Background(lambda: list(validate_model_description(tree)))
    try:
        return read_model_description(tree, file=MODEL_DESCRIPTION)
    finally:
        collector.add_stage(validation.result())


def read_manifest_file(source, names: Sequence[str], options: EngineOptions, collector: Collector,
                   texts: SourceTexts, state: RunState,
                   model: ModelDescription | None) -> Manifest | None:
    if MANIFEST not in names:
        if _not_read(source, MANIFEST, "manifest", "manifest", state):
            return None
        collector.emit("manifest-missing", manifest_missing(model, names))
        return None
    tree = read_xml(source, MANIFEST, collector, texts)
    if tree is None:
        state.info["manifest"] = "unreadable: nothing to check or probe"
        state.unread["manifest"] = "the manifest cannot be read or parsed"
        return None
    draft = detect_draft(tree.getroot()) if options.draft == "auto" else options.draft
    state.draft = draft
    if draft == UNKNOWN:
        collector.add_stage(unrecognised_violations(tree.getroot(), file=MANIFEST))
        return None
    if options.probes_only:
        return read_manifest(tree, draft=draft, file=MANIFEST)
    validation = Background(lambda: list(validate_manifest(tree, draft, file=MANIFEST)))
    try:
        return read_manifest(tree, draft=draft, file=MANIFEST)
    finally:
        collector.add_stage(validation.result())
        collector.add_stage(legacy_violations(tree.getroot(), draft, file=MANIFEST))
