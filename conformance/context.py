"""What a check sees: the parsed model, the manifest, the draft and the archive's file names."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

from .findings import Violation
from .manifest import Manifest
from .model import ModelDescription


@dataclass(frozen=True)
class CheckContext:
    """Everything a static check may read. Checks never see the engine or the catalogue."""

    model: ModelDescription | None
    manifest: Manifest | None
    draft: str | None
    names: tuple[str, ...] = ()     # member names of the FMU (forward slashes)


# A check takes the context and its rule options (keyword-only) and yields violations.
Check = Callable[..., Iterable[Violation]]
