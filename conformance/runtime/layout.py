"""The model's layout: which value references are states, algebraic variables, residuals, inputs
and outputs in each mode, with their nominal values, bounds and start values; read once from the
model and the manifest, used by every instance of the FMU.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from ..model.attributes import start_flagged, usable_bounds, usable_nominal, usable_start
from ..model.manifest import Manifest
from ..model.description import FLOAT_TYPES, ModelDescription, Variable


def _scalar_float64(var: Variable | None) -> bool:
    return var is not None and var.type == "Float64" and not var.dimensions


@dataclass(frozen=True)
class Layout:
    """Which value references play which role, per mode; read once from model and manifest.

    Only scalar Float64 variables take part (``ignored`` lists the others by name). The DAE-mode
    lists come from the manifest ModelStructure, falling back to modelDescription's for a kind
    the manifest does not list (open question Q-02 of the digest).
    """

    states: tuple[int, ...]              # DAE mode, in ContinuousStateDerivative order
    derivatives: tuple[int, ...]
    ode_states: tuple[int, ...]
    ode_derivatives: tuple[int, ...]
    algebraic: tuple[int, ...]
    residuals: tuple[int, ...]
    inputs: tuple[int, ...]
    outputs: tuple[int, ...]
    ode_outputs: tuple[int, ...]
    enable: int | None                   # value reference of the usable Boolean switch
    # "ok", "absent" (a DAE-only FMU), "unusable", or "no-layer": no manifest, an ordinary
    # Model Exchange FMU, which has only ODE mode
    enable_status: str
    enable_tunable: bool
    token: str
    model_identifier: str
    start_time: float = 0.0
    names: Mapping[int, str] = field(default_factory=dict)
    nominal: Mapping[int, float] = field(default_factory=dict)
    bounds: Mapping[int, tuple[float, float]] = field(default_factory=dict)
    start: Mapping[int, float] = field(default_factory=dict)
    flagged_start: frozenset[int] = frozenset()   # start values the static stage flags
    ignored: tuple[str, ...] = ()
    provides_directional: bool = False
    provides_adjoint: bool = False
    # <EventIndicator> value references in document order (the fmi3GetEventIndicators vector):
    # DAE mode from the manifest, falling back to modelDescription's like the outputs
    event_indicators: tuple[int, ...] = ()
    ode_event_indicators: tuple[int, ...] = ()

    @property
    def modes(self) -> tuple[str, ...]:
        """The modes an instance can be started in: ODE mode only without the layer, DAE mode
        only for a DAE-only FMU, else both (an unusable switch leaves neither)."""
        return {"ok": ("dae", "ode"), "absent": ("dae",), "no-layer": ("ode",)}.get(
            self.enable_status, ())

    def states_for(self, mode: str) -> tuple[int, ...]:
        return self.states if mode == "dae" else self.ode_states

    def derivatives_for(self, mode: str) -> tuple[int, ...]:
        return self.derivatives if mode == "dae" else self.ode_derivatives

    def outputs_for(self, mode: str) -> tuple[int, ...]:
        return self.outputs if mode == "dae" else self.ode_outputs

    def event_indicators_for(self, mode: str) -> tuple[int, ...]:
        return self.event_indicators if mode == "dae" else self.ode_event_indicators

    def name(self, vr: int) -> str:
        return self.names.get(vr, f"vr {vr}")

    def scale(self, vr: int) -> float:
        return self.nominal.get(vr, 1.0)

    @classmethod
    def build(cls, model: ModelDescription, manifest: Manifest | None) -> Layout:
        by_vr = model.by_vr
        ignored: list[str] = []

        def usable(vrs: Sequence[int | None]) -> tuple[int, ...]:
            out: dict[int, None] = {}   # insertion-ordered: O(1) membership, first order kept
            for vr in vrs:
                var = by_vr.get(vr) if vr is not None else None
                if _scalar_float64(var) and vr not in out:
                    out[vr] = None  # type: ignore[index]
                elif var is not None and var.type in FLOAT_TYPES:
                    ignored.append(var.name)
            return tuple(out)

        def derivative_pairs(unknowns: Sequence[Any]) -> tuple[tuple[int, ...], tuple[int, ...]]:
            ders, states = [], []
            for u in unknowns:
                der = by_vr.get(u.vr) if u.vr is not None else None
                state = by_vr.get(der.derivative) if der and der.derivative is not None else None
                if _scalar_float64(der) and _scalar_float64(state):
                    ders.append(u.vr)
                    states.append(der.derivative)  # type: ignore[union-attr]
            return tuple(states), tuple(ders)

        md_csd = list(model.unknowns("ContinuousStateDerivative"))
        ode_states, ode_ders = derivative_pairs(md_csd)
        ms_csd = list(manifest.unknowns("ContinuousStateDerivative")) if manifest else []
        states, ders = derivative_pairs(ms_csd) if ms_csd else (ode_states, ode_ders)
        md_outputs = [u.vr for u in model.unknowns("Output")]
        ms_outputs = [u.vr for u in manifest.unknowns("Output")] if manifest else []
        md_indicators = [u.vr for u in model.unknowns("EventIndicator")]
        ms_indicators = [u.vr for u in manifest.unknowns("EventIndicator")] if manifest else []
        enable, status, tunable = _enable(model, manifest)
        me = model.model_exchange
        names, nominal, bounds, start = {}, {}, {}, {}
        flagged: set[int] = set()
        for var in model.variables:
            if var.vr is None:
                continue
            names.setdefault(var.vr, var.name)
            if var.type in FLOAT_TYPES:
                # what the static stage flags (conformance.model.attributes) is never sampled from
                nominal[var.vr] = usable_nominal(var.nominal)
                bounds[var.vr] = usable_bounds(var.minimum, var.maximum)
                if var.start is not None:
                    start[var.vr] = usable_start(var.start, 0.0)
                    if start_flagged(var.start):
                        flagged.add(var.vr)
        inputs = [v.vr for v in model.variables
                  if v.causality == "input" and v.variability == "continuous"]
        return cls(
            states=states, derivatives=ders, ode_states=ode_states, ode_derivatives=ode_ders,
            algebraic=usable([a.vr for a in manifest.algebraic] if manifest else []),
            residuals=usable([r.vr for r in manifest.residuals] if manifest else []),
            inputs=usable(inputs), outputs=usable(ms_outputs or md_outputs),
            ode_outputs=usable(md_outputs), enable=enable, enable_status=status,
            enable_tunable=tunable, token=model.instantiation_token or "",
            start_time=_start_time(model),
            model_identifier=(me.model_identifier if me else None) or "",
            names=names, nominal=nominal, bounds=bounds, start=start,
            flagged_start=frozenset(flagged),
            ignored=tuple(dict.fromkeys(ignored)),
            provides_directional=bool(me and me.flag("providesDirectionalDerivatives")),
            provides_adjoint=bool(me and me.flag("providesAdjointDerivatives")),
            event_indicators=usable(ms_indicators or md_indicators),
            ode_event_indicators=usable(md_indicators),
        )


def _start_time(model: ModelDescription) -> float:
    """The DefaultExperiment's startTime when it is a finite number, else 0."""
    experiment = model.default_experiment
    start = experiment.start_time if experiment is not None else None
    return float(start) if start is not None and math.isfinite(start) else 0.0


def _enable(model: ModelDescription, manifest: Manifest | None) -> tuple[int | None, str, bool]:
    """(value reference, status, tunable) of the enable parameter, if it can be used: a scalar
    Boolean structural parameter, fixed or tunable. Any other switch cannot be set at all: FMI
    3.0.2 §2.3.6 allows fmi3Set in Configuration Mode only on such a variable (and §2.3.2
    fmi3EnterConfigurationMode only on an FMU that has one); the static rules report why
    (enable-parameter-not-boolean, -not-structural, -variability, -not-scalar)."""
    if manifest is None:
        return None, "no-layer", False
    if not manifest.enables:
        return None, "absent", False
    ref = manifest.enables[0]
    var = model.by_vr.get(ref.vr) if ref.vr is not None else None
    if var is None and ref.name:
        var = next((v for v in model.variables if v.name == ref.name), None)
    if (var is None or var.vr is None or var.type != "Boolean" or var.dimensions
            or var.causality != "structuralParameter"
            or var.variability not in ("fixed", "tunable")):
        return None, "unusable", False
    return var.vr, "ok", var.variability == "tunable"
