"""The FMI calls of one step of the endurance path run: every call an importer makes.

An importer that integrates the FMU in DAE mode, at every point its solver visits, sets time,
states, algebraic variables and inputs, and reads residuals, outputs, derivatives and event
indicators; it reads the state vector and its nominals after events, asks for directional (and
adjoint) derivatives to build its iteration matrix, and instantiates and frees instances between
runs. A defect that needs sustained use (a leak, a counter that overflows) can sit in any of
them, so the path run (:mod:`.run`) makes all of them: the base of each step (the
point set, fmi3GetFloat64, fmi3GetContinuousStateDerivatives) and the optional calls of
:class:`StepCalls`, which the FMU declares it supports:

* fmi3GetEventIndicators, when the FMU declares event indicators (the DAE-mode list of the XML,
  as an importer sizes its root function: fmi3GetNumberOfEventIndicators may not be asked in
  Continuous-Time Mode, FMI 3.0.2 §3.2.1; event-indicators-failed compares the two);
* fmi3GetContinuousStates and fmi3GetNominalsOfContinuousStates, when it has states;
* fmi3GetDirectionalDerivative and fmi3GetAdjointDerivative (every known seeded with 1, every
  unknown asked), when ``providesDirectionalDerivatives`` / ``providesAdjointDerivatives``;
* one instance instantiated, initialised and freed per lap of the path.

An optional call that fails at the start point on a fresh instance is left out of the walk with
the reason (``left_out``): the probes of that call report it; the walk is about what sustained
use does.
"""
from __future__ import annotations

import ctypes
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...runtime.arrays import double_array, vr_array
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from ..instruments.api import FmiError, Point, ProbeSkipped
from ..instruments.common import unknowns_of

INSTANCE_CYCLE = "fmi3InstantiateModelExchange/fmi3FreeInstance"


@dataclass
class StepCalls:
    """The optional calls of a step, their costs, and what was left out and why."""

    layout: Layout
    nz: int = 0
    calls: list[str] = field(default_factory=list)
    left_out: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        layout = self.layout
        self.nx = len(layout.states)
        self.unknowns = tuple(unknowns_of(layout))
        self.knowns = tuple(dict.fromkeys([*layout.states, *layout.algebraic, *layout.inputs]))
        self.seed = np.ones(len(self.knowns))
        self.adjoint_seed = np.ones(len(self.unknowns))
        self._args: dict[str, tuple[Any, ...]] = {}

    def candidates(self) -> list[str]:
        layout, out = self.layout, []
        if self.nz:
            out.append("fmi3GetEventIndicators")
        if self.nx:
            out += ["fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates"]
        if self.unknowns and self.knowns:
            if layout.provides_directional:
                out.append("fmi3GetDirectionalDerivative")
            if layout.provides_adjoint:
                out.append("fmi3GetAdjointDerivative")
        return out

    def prepare(self, new_instance: Callable[[], Instance], point: Point) -> None:
        """Keep each candidate that works at ``point`` on a fresh instance."""
        self.nz = len(self.layout.event_indicators)
        probe = new_instance()
        try:
            probe.set_point(point)
            for name in self.candidates():
                if probe.failure is not None:   # Terminated (SM-04): a fresh one for the rest
                    probe.free()
                    probe = new_instance()
                    probe.set_point(point)
                try:
                    self.call(probe, name)
                    self.calls.append(name)
                except FmiError as exc:
                    self.left_out[name] = f"{exc.call} returned {exc.status} at {point.label}"
                except ProbeSkipped as exc:   # not called again (it hung or was fatal before)
                    self.left_out[name] = str(exc)
        except (FmiError, ProbeSkipped) as exc:
            raise ProbeSkipped(f"the importer's calls could not be tried at {point.label} on "
                               f"a fresh instance: {exc}") from None
        finally:
            probe.free()

    def call(self, inst: Instance, name: str) -> None:
        """One optional call, with C arrays made once (a step costs the FMU's time, hardly
        lsdae's: the long level makes two million calls)."""
        args = self._args.get(name)
        if args is None:
            args = self._args[name] = self._make(name)
        inst.call(name, *args)

    def _make(self, name: str) -> tuple[Any, ...]:
        def doubles(n: int) -> Any:
            return (ctypes.c_double * n)()

        if name == "fmi3GetEventIndicators":
            return doubles(self.nz), self.nz
        if name in ("fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates"):
            return doubles(self.nx), self.nx
        unknowns, knowns = vr_array(self.unknowns), vr_array(self.knowns)
        nu, nk = len(self.unknowns), len(self.knowns)
        if name == "fmi3GetDirectionalDerivative":
            return (unknowns, nu, knowns, nk, double_array(self.seed), nk, doubles(nu), nu)
        return (unknowns, nu, knowns, nk, double_array(self.adjoint_seed), nu, doubles(nk), nk)

    def run(self, inst: Instance) -> None:
        for name in self.calls:
            self.call(inst, name)

    def values(self) -> int:
        """Values passed by the optional calls of one step (the budget counts them)."""
        sizes = {"fmi3GetEventIndicators": self.nz, "fmi3GetContinuousStates": self.nx,
                 "fmi3GetNominalsOfContinuousStates": self.nx,
                 "fmi3GetDirectionalDerivative": len(self.knowns) + len(self.unknowns),
                 "fmi3GetAdjointDerivative": len(self.knowns) + len(self.unknowns)}
        return sum(sizes[name] for name in self.calls)

    def info(self) -> dict[str, Any]:
        out: dict[str, Any] = {"calls": [*self.calls, INSTANCE_CYCLE]}
        if self.left_out:
            out["left_out"] = dict(self.left_out)
        return out
