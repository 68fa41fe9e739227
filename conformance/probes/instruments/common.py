"""Helpers shared by the basic probes (evaluation/basic.py) and the handshake probes
(evaluation/handshake.py).

The :class:`~conformance.runtime.layout.Layout` and the loaded
:class:`~conformance.runtime.library.Library` come from ``ctx.facts`` (``"layout"``,
``"library"``); locations point at the manifest element (or the variable) a finding is about.
"""
from __future__ import annotations

import contextlib
from typing import Any, Iterator, Sequence

import numpy as np

from ...report.findings import Location
from ...model.description import MODEL_DESCRIPTION
from .api import FmiError, ProbeContext, ProbeSkipped
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from ...runtime.library import Library


def layout_of(ctx: ProbeContext) -> Layout:
    return ctx.facts["layout"]  # type: ignore[return-value]


def dae_of(ctx: ProbeContext) -> Instance:
    """The DAE-mode evaluator, or ProbeSkipped saying why there is none."""
    if ctx.dae is None:
        error = ctx.facts.get("dae_error")
        raise ProbeSkipped(f"DAE mode could not be started: {error}" if error else
                           "DAE mode could not be started")
    return ctx.dae  # type: ignore[return-value]


def var_location(ctx: ProbeContext, vr: int) -> Location:
    var = ctx.model.by_vr.get(vr)
    if var is None:
        return Location(file=MODEL_DESCRIPTION)
    return Location(file=ctx.model.file, line=var.line, path=var.path)


def manifest_location(ctx: ProbeContext, vr: int | None, kinds: Sequence[str]) -> Location:
    """The manifest element of kind ``kinds`` (AlgebraicVariable, Residual, ...) for ``vr``."""
    m = ctx.manifest
    if m is None:
        return Location()
    if "AlgebraicVariable" in kinds:
        for ref in m.algebraic:
            if ref.vr == vr:
                return Location(file=m.file, line=ref.line, path=ref.path)
    if "Enable" in kinds and m.enables:
        ref = m.enables[0]
        return Location(file=m.file, line=ref.line, path=ref.path)
    for u in m.structure:
        if u.kind in kinds and u.vr == vr:
            return Location(file=m.file, line=u.line, path=u.path)
    return var_location(ctx, vr) if vr is not None else Location(file=m.file, line=m.root_line)


def root_location(ctx: ProbeContext) -> Location:
    m = ctx.manifest
    return Location(file=m.file, line=m.root_line) if m else Location(file=MODEL_DESCRIPTION)


def unknown_location(ctx: ProbeContext, vr: int) -> Location:
    loc = manifest_location(ctx, vr, ("Residual", "ContinuousStateDerivative", "Output"))
    return loc if loc.line is not None else var_location(ctx, vr)


def unknowns_of(layout: Layout, mode: str = "dae") -> list[int]:
    """Residuals (DAE mode), derivatives and outputs, each once."""
    vrs = [*(layout.residuals if mode == "dae" else ()), *layout.derivatives_for(mode),
           *layout.outputs_for(mode)]
    return list(dict.fromkeys(vrs))


def error_evidence(exc: FmiError) -> dict[str, Any]:
    return {"call": exc.call, "status": exc.status, "log": list(exc.log[:10])}


def close(a: float, b: float, *, rtol: float, atol: float, scale: float) -> bool:
    return abs(a - b) <= atol + rtol * max(scale, abs(a), abs(b))


def finite(values: Any) -> bool:
    return bool(np.all(np.isfinite(values)))


def new_instance(library: Library, label: str) -> Instance:
    return Instance(library, name=library.next_name(label))


def renew(ctx: ProbeContext, mode: str) -> Any:
    """A fresh instance in Continuous-Time Mode in ``mode`` in place of ``ctx.dae`` or
    ``ctx.ode`` (the old one freed), or None, with the reason in ``ctx.facts``, when it cannot
    be started. For an instance with a failed call: fmi3Error put it in Terminated (SM-04), so
    whatever fails on it later is a consequence, not something to report."""
    old = getattr(ctx, mode)
    if old is not None:
        old.free()
    try:
        new = ctx.new_instance(mode)
    except (FmiError, ProbeSkipped) as exc:
        new = None
        ctx.facts[f"{mode}_error"] = exc
    setattr(ctx, mode, new)
    return new


def renew_failed(ctx: ProbeContext) -> None:
    """Renew ``ctx.dae`` and ``ctx.ode`` where an earlier call returned fmi3Error (see
    :func:`renew`): the probe stage does it before each probe."""
    for mode in ("dae", "ode"):
        if getattr(getattr(ctx, mode), "failure", None) is not None:
            renew(ctx, mode)


@contextlib.contextmanager
def fresh_instance(ctx: ProbeContext, mode: str) -> Iterator[Instance]:
    """A new instance in Continuous-Time Mode in ``mode``, freed afterwards."""
    inst = ctx.new_instance(mode)
    try:
        yield inst  # type: ignore[misc]
    finally:
        inst.free()  # type: ignore[attr-defined]

