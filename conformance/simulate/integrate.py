"""Integrate one FMU instance: the public function of the simulation, for the probes and benchmarks.

:func:`simulate_instance` takes an instance already in Continuous-Time Mode in DAE mode (IDA on
the residuals, with the FMU's coloured Jacobian) or ODE mode (CVODE on the derivatives), through
the FMU's events (state events on its event indicators, the time events its event updates
schedule, from the one that ended initialisation on: ``inst.discrete``), and returns the
:class:`~conformance.numerics.settings.Trajectory`. The instance is the caller's to
free. Whether a run makes sense (a square DAE, states to integrate) is the caller's to decide.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.dae import integrate_dae
from ..numerics.ode import integrate_ode
from ..numerics.settings import Settings, Trajectory
from ..runtime.errors import FmiError
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
        system = choose_jacobian(FmuDae(inst, layout, manifest,
                                        dense_up_to=settings.dense_up_to), start, derivatives)
        y0 = inst.get_float64([*system.states, *system.algebraic])
        traj = integrate_dae(system, settings, t0=start, y0=y0, stop=stop,
                             start_update=inst.discrete)
        # after events the discrete state no longer fits early times; after an fmi3Error the
        # instance is in Terminated, where nothing may be set (FMI 3.0.2 §2.3.8)
        if not traj.has_events and inst.failure is None:
            traj.residual_along = residual_along(inst, layout, traj)
        return traj
    ode = choose_jacobian(FmuOde(inst, layout, model, dense_up_to=settings.dense_up_to), start,
                          derivatives)
    nominal = np.array([layout.scale(vr) for vr in ode.algebraic])
    return integrate_ode(ode, settings, t0=start, x0=inst.get_float64(ode.states), stop=stop,
                         algebraic_nominal=nominal, start_update=inst.discrete)


def residual_along(inst: Instance, layout: Layout, traj: Trajectory) -> dict[str, Any]:
    """The largest |residual| at the output times of a DAE-mode run: how well the run kept
    0 = g(x, w) (``{}`` when there are no residuals, or the FMU cannot be evaluated again).
    Evaluated after the run, so the run's own counts stay as they were."""
    residuals = list(layout.residuals)
    index = {name: k for k, name in enumerate(traj.names)}
    states = [index.get(layout.name(vr)) for vr in layout.states]
    algebraic = [index.get(layout.name(vr)) for vr in layout.algebraic]
    if not residuals or None in states or None in algebraic or not traj.times:
        return {}
    worst: dict[str, Any] = {}
    try:
        for row, t in enumerate(traj.times):
            values = traj.values[row]
            if not np.all(np.isfinite(values)):
                continue
            inst.set_time(t)
            if states:
                inst.set_states([values[k] for k in states])
            inst.set_float64(list(layout.algebraic), [values[k] for k in algebraic])
            g = np.abs(inst.get_float64(residuals))
            k = int(np.argmax(g))
            if not worst or g[k] > worst["max_abs"]:
                worst = {"max_abs": float(g[k]), "residual": layout.name(residuals[k]),
                         "t": float(t)}
    except FmiError:
        return worst
    return worst
