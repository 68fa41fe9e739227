"""Integrate one FMU instance: the public function of the simulation, for the probes and benchmarks.

:func:`simulate_instance` takes an instance already in Continuous-Time Mode in DAE mode (IDA on
the residuals, with the FMU's coloured Jacobian) or ODE mode (CVODE on the derivatives) and
returns the :class:`~conformance.numerics.settings.Trajectory`. The instance is the caller's to
free. Whether a run makes sense (a square DAE, states to integrate) is the caller's to decide.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.dae import integrate_dae
from ..numerics.ode import integrate_ode
from ..numerics.settings import Settings, Trajectory
from ..runtime.instance import Instance
from ..runtime.layout import Layout
from .jacobian_check import DerivativeCheck, choose_jacobian
from .system import FmuDae, FmuOde


def simulate_instance(inst: Instance, layout: Layout, settings: Settings, *, start: float,
                      stop: float, model: Any, manifest: Any,
                      derivatives: DerivativeCheck | None = None) -> Trajectory:
    """Integrate ``inst`` in its mode (``inst.mode``) from ``start`` to ``stop``, starting from
    the values it holds; the model and manifest give the declared sparsity of its Jacobian,
    ``derivatives`` whether the FMU's directional derivatives may be used (jacobian_check)."""
    if inst.mode == "dae":
        system = choose_jacobian(FmuDae(inst, layout, manifest), start, derivatives)
        y0 = inst.get_float64([*system.states, *system.algebraic])
        return integrate_dae(system, settings, t0=start, y0=y0, stop=stop)
    ode = choose_jacobian(FmuOde(inst, layout, model), start, derivatives)
    nominal = np.array([layout.scale(vr) for vr in ode.algebraic])
    return integrate_ode(ode, settings, t0=start, x0=inst.get_float64(ode.states), stop=stop,
                         algebraic_nominal=nominal)
