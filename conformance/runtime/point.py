"""A point of the model's knowns, and the Evaluator protocol that evaluates the FMU there."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Protocol, Sequence

import numpy as np


@dataclass(frozen=True)
class Point:
    """A sampling point: time and the values of states, algebraic variables and inputs by vr."""

    t: float
    values: Mapping[int, float]
    label: str = ""          # e.g. "start", "near-3"


class Evaluator(Protocol):
    """An instance in Continuous-Time Mode, in one mode (DAE or ODE), driven by value reference.

    All arrays are float64, ordered as the sequences of value references passed in.
    """

    mode: str                                  # "dae" or "ode"
    calls: int                                 # FMI calls made so far (for the benchmarks)

    def evaluate(self, point: Point, unknowns: Sequence[int]) -> np.ndarray:
        """Set t and the point's knowns (states via fmi3SetContinuousStates or SetFloat64,
        algebraic variables (DAE mode), inputs), then read ``unknowns`` with fmi3GetFloat64."""
        ...

    def directional(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                    seed: np.ndarray) -> np.ndarray:
        """fmi3GetDirectionalDerivative at the point: J[unknowns, knowns] @ seed."""
        ...

    def adjoint(self, point: Point, unknowns: Sequence[int], knowns: Sequence[int],
                seed: np.ndarray) -> np.ndarray:
        """fmi3GetAdjointDerivative at the point: seed @ J[unknowns, knowns]."""
        ...
