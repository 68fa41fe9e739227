"""What a check sees: the parsed model, the manifest, the draft and the archive's file names."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, TypeVar

from ..report.findings import Violation
from ..model.layer import layer_declaration
from ..model.manifest import Manifest
from ..model.description import ModelDescription


T = TypeVar("T")


@dataclass(frozen=True)
class CheckContext:
    """Everything a static check may read. Checks never see the engine or the catalogue."""

    model: ModelDescription | None
    manifest: Manifest | None
    draft: str | None
    names: tuple[str, ...] = ()     # member names of the FMU (forward slashes)
    _memo: dict[str, Any] = field(default_factory=dict, repr=False, compare=False, hash=False)

    @property
    def dae_layer(self) -> bool:
        """Whether the FMU declares the fmi-ls-dae layer (:mod:`conformance.model.layer`)."""
        return self.manifest is not None or self.memo(
            "layer-declaration", lambda: layer_declaration(self.model, self.names)) is not None

    def memo(self, key: str, compute: Callable[[], T]) -> T:
        """Compute a derived fact once per FMU and share it between checks (e.g. the set of
        continuous states, or a classification several rules partition)."""
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]


# A check takes the context and its rule options (keyword-only) and yields violations.
Check = Callable[..., Iterable[Violation]]
