"""Simulate one FMU from the parent process: the simulation probes through the engine.

:func:`simulate_fmu` runs the simulation probes (``conformance/probes/simulation/verdicts.py``,
which call :func:`conformance.simulate.integrate.simulate_instance` in the worker) through the
engine, on a copy of the catalogue whose ``simulation-failed`` options are the given settings and
whose time limits fit the budget, then reads the trajectories back from the report's
``info["simulation"]``. A crash or hang of the FMU is a ``binary-*`` finding, never a traceback.
Also what the command reads from modelDescription.xml before it starts: the DefaultExperiment
and the start values it is given. Used by ``lsdae simulate`` (:mod:`conformance.commands.simulate`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..report.catalogue import Catalogue, default_catalogue
from .engine import EngineOptions, check_fmu
from ..report.findings import thaw
from ..intake.fmu import MODEL_DESCRIPTION, ArchiveReadError, open_fmu
from ..model.description import ModelDescription, read_model_description
from ..intake.xmlsafe import parse_xml


RULES_BY_MODE = {"dae": ("DAE801", "DAE802", "DAE803", "DAE804"),
                 "ode": ("DAE801", "DAE803", "DAE804"),
                 "both": ("DAE801", "DAE802", "DAE803", "DAE804", "DAE805")}
# Archive, XML and engine pseudo-rules, and the runner's binary-* rules: a broken FMU says why.
ALWAYS = ("DAE0", "DAE70")
RUNNER_MARGIN_S = 30.0


@dataclass
class Simulation:
    """What one FMU's simulation gave: the report (findings, skipped rules), the runs (DAE mode
    first), the comparison of the two modes, and the catalogue used (for reporters)."""

    report: Any
    catalogue: Any
    trajectories: list[Any] = field(default_factory=list)  # Trajectory
    comparison: dict[str, Any] | None = None

    def skipped(self) -> list[str]:
        """Why rules of this simulation did not run (distinct reasons, in code order)."""
        codes = set(RULES_BY_MODE["both"])
        return list(dict.fromkeys(r for c, r in sorted(self.report.rules_skipped)
                                  if c in codes))


def read_model(path: Path | str) -> ModelDescription | None:
    """The FMU's modelDescription.xml, read safely once; None when it cannot be read."""
    source, _ = open_fmu(Path(path))
    if source is None:
        return None
    with source:
        try:
            data = source.read(MODEL_DESCRIPTION)
        except (KeyError, ArchiveReadError, OSError):
            return None
    tree, _ = parse_xml(data, file=MODEL_DESCRIPTION)
    return read_model_description(tree) if tree is not None else None


def default_experiment(model: ModelDescription | None) -> dict[str, float]:
    """The DefaultExperiment's startTime, stopTime and tolerance that are finite numbers."""
    experiment = model.default_experiment if model is not None else None
    if experiment is None:
        return {}
    values = {"startTime": experiment.start_time, "stopTime": experiment.stop_time,
              "tolerance": experiment.tolerance}
    return {k: float(v) for k, v in values.items() if v is not None and math.isfinite(v)}


SETTABLE_START = ("input", "parameter")


def start_values(model: ModelDescription | None, items: list[str]
                 ) -> tuple[tuple[str, float], ...]:
    """``NAME=VALUE`` items as (name, value), checked against the model: the name is a scalar
    Float64 input or parameter (as fmpy's start_values); ValueError says what is wrong."""
    if not items:
        return ()
    variables = {v.name: v for v in model.variables} if model is not None else {}
    out = []
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep:
            raise ValueError(f"--start-value takes NAME=VALUE, not {item!r}")
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"--start-value {name}: not a number: {text!r}") from None
        var = variables.get(name)
        if var is None:
            raise ValueError(f"--start-value: the FMU has no variable {name!r}")
        if var.causality not in SETTABLE_START or var.type != "Float64" or var.dimensions:
            raise ValueError(f"--start-value {name}: only scalar Float64 inputs and parameters "
                             f"can be given (it is a {var.type} {var.causality})")
        out.append((name, value))
    return tuple(out)


def simulation_catalogue(settings: Any, *, time_limit: float | None = None) -> Catalogue:
    """The default catalogue with ``settings`` as the options of simulation-failed, and the
    runner's time limits raised above the wall-clock budget (``time_limit``, per run)."""
    limit = settings.wall_seconds if time_limit is None else time_limit
    runs = 2 if settings.mode == "both" else 1
    rules = []
    for rule in default_catalogue():
        if rule.name == "simulation-failed":
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, **settings.as_options(),
                 "published_series": 0,   # every trajectory: the command writes them out
                 "output_times": tuple(settings.output_times),
                 "start_values": tuple(tuple(p) for p in settings.start_values)}.items())))
        elif rule.name == "binary-timed-out":
            # the confirmation runs of ode-dae-trajectory-mismatch take up to one budget more
            rule = dataclasses.replace(rule, options=tuple(sorted({
                **rule.option_values, "probe_seconds": 2 * limit + RUNNER_MARGIN_S,
                "fmu_seconds": (runs + 1) * limit + 2 * RUNNER_MARGIN_S}.items())))
        rules.append(rule)
    return Catalogue(rules)


def simulate_fmu(path: Path | str, settings: Any) -> Simulation:
    """Simulate the FMU at ``path`` (file or folder) as ``settings`` say; never raises for a
    bad FMU (its faults are findings of the report)."""
    catalogue = simulation_catalogue(settings)
    options = EngineOptions(select=(*ALWAYS, *RULES_BY_MODE[settings.mode]), probes_only=True)
    report = check_fmu(Path(path), options=options, catalogue=catalogue, display_path=str(path))
    info = thaw(report.info)
    simulation = info.get("simulation") if isinstance(info, dict) else None
    result = Simulation(report, catalogue)
    if isinstance(simulation, dict) and simulation.get("times") is not None:
        from ..numerics.settings import Trajectory  # numpy: only once a run is read back

        result.trajectories.append(Trajectory.from_info(simulation))
        if isinstance(simulation.get("ode"), dict):
            result.trajectories.append(Trajectory.from_info(simulation["ode"]))
        if isinstance(simulation.get("comparison"), dict):
            result.comparison = simulation["comparison"]
    return result
