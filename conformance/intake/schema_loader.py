"""Locate and load the XML schemas, offline, once per process.

Where the schemas come from:

- ``modelDescription.xml``: ``fmi3ModelDescription.xsd`` of the FMI 3.0 core, read at run time
  from the installed fmpy package (``fmpy/schema/fmi3``); never copied, never fetched.
- ``sources/buildDescription.xml`` (source FMUs): ``fmi3BuildDescription.xsd``, from fmpy too.
- the manifest: ``schemas/fmi-ls-dae-<draft>.xsd`` (ours, one per draft). They reference the core
  schemas through the virtual location ``fmi-core/<file>.xsd``, which the resolver below maps to
  the same fmpy folder.

Loading never touches the network: every schema document is parsed with ``no_network=True`` and a
resolver that raises :class:`SchemaLoadError` for any http(s)/ftp location instead of fetching it.
:mod:`conformance.intake.schemas` validates with what is loaded here.
"""
from __future__ import annotations

import functools
import importlib.util
import logging
import re
from pathlib import Path

from lxml import etree

from ..model.drafts.detect import ALPHA1, ATTRIBUTES_ONLY, FLAT_INDEX, FORMULATION, LS_DAE_ROOT
from ..report.paths import schemas_dir

log = logging.getLogger(__name__)

MODEL_DESCRIPTION_XSD = "fmi3ModelDescription.xsd"
BUILD_DESCRIPTION_XSD = "fmi3BuildDescription.xsd"

#: Our schema file for each draft id (in the ``schemas/`` folder).
SCHEMA_FILES: dict[str, str] = {
    ALPHA1: "fmi-ls-dae-alpha1.xsd",
    FORMULATION: "fmi-ls-dae-formulation.xsd",
    LS_DAE_ROOT: "fmi-ls-dae-ls-dae-root.xsd",
    FLAT_INDEX: "fmi-ls-dae-flat-index.xsd",
    ATTRIBUTES_ONLY: "fmi-ls-dae-attributes-only.xsd",
}

_CORE_PREFIX = "fmi-core/"
_REMOTE = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*://")


class SchemaLoadError(RuntimeError):
    """A schema could not be loaded: a file is missing, fmpy is absent, or a remote URL was asked for."""


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
def build_description_schema() -> etree.XMLSchema:
    """``fmi3BuildDescription.xsd`` from fmpy (for ``sources/buildDescription.xml``), loaded once."""
    return _load_schema(core_schema_dir() / BUILD_DESCRIPTION_XSD)


@functools.lru_cache(maxsize=None)
def manifest_schema(draft: str) -> etree.XMLSchema:
    """Our XSD for a draft id of :mod:`conformance.model.drafts.detect`, loaded once per process."""
    try:
        name = SCHEMA_FILES[draft]
    except KeyError:
        raise ValueError(f"no schema for draft {draft!r}") from None
    return _load_schema(schema_dir() / name)


def clear_schema_cache() -> None:
    """Forget every loaded schema (tests use this to prove that loading stays offline)."""
    model_description_schema.cache_clear()
    build_description_schema.cache_clear()
    manifest_schema.cache_clear()
