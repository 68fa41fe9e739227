"""Simulate one FMU from the parent process, the binary isolated in the probe worker.

:func:`simulate_fmu` runs the simulation probes through the engine (``check_fmu`` with only the
archive/XML pseudo-rules, the runner's ``binary-*`` rules and the simulation rules selected) on a
copy of the catalogue whose ``simulation-failed`` options are the given :class:`Settings` and
whose time limits fit the budget, then reads the trajectories back from the report's
``info["simulation"]``. A crash or hang of the FMU is a ``binary-*`` finding in the report.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .settings import Settings, Trajectory

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
    trajectories: list[Trajectory] = field(default_factory=list)
    comparison: dict[str, Any] | None = None

    def skipped(self) -> list[str]:
        """Why rules of this simulation did not run (distinct reasons, in code order)."""
        codes = set(RULES_BY_MODE["both"])
        return list(dict.fromkeys(r for c, r in sorted(self.report.rules_skipped)
                                  if c in codes))


def default_stop_time(path: Path | str) -> float | None:
    """The DefaultExperiment's stopTime, read safely; None when absent or unreadable."""
    from ..fmu import MODEL_DESCRIPTION, ArchiveReadError, open_fmu
    from ..xmlsafe import parse_xml

    source, _ = open_fmu(Path(path))
    if source is None:
        return None
    with source:
        try:
            data = source.read(MODEL_DESCRIPTION)
        except (KeyError, ArchiveReadError, OSError):
            return None
    tree, _ = parse_xml(data, file=MODEL_DESCRIPTION)
    element = tree.getroot().find("DefaultExperiment") if tree is not None else None
    try:
        return float(element.get("stopTime")) if element is not None else None
    except (TypeError, ValueError):
        return None


def simulation_catalogue(settings: Settings, *, time_limit: float | None = None) -> Any:
    """The default catalogue with ``settings`` as the options of simulation-failed, and the
    runner's time limits raised above the wall-clock budget (``time_limit``, per run)."""
    from ..catalogue import Catalogue, default_catalogue

    limit = settings.wall_seconds if time_limit is None else time_limit
    runs = 2 if settings.mode == "both" else 1
    rules = []
    for rule in default_catalogue():
        if rule.name == "simulation-failed":
            rule = dataclasses.replace(rule, options=tuple(sorted(
                {**rule.option_values, **settings.as_options(),
                 "output_times": tuple(settings.output_times)}.items())))
        elif rule.name == "binary-timed-out":
            # the confirmation runs of ode-dae-trajectory-mismatch take up to one budget more
            rule = dataclasses.replace(rule, options=tuple(sorted({
                **rule.option_values, "probe_seconds": 2 * limit + RUNNER_MARGIN_S,
                "fmu_seconds": (runs + 1) * limit + 2 * RUNNER_MARGIN_S}.items())))
        rules.append(rule)
    return Catalogue(rules)


def simulate_fmu(path: Path | str, settings: Settings) -> Simulation:
    """Simulate the FMU at ``path`` (file or folder) as ``settings`` say; never raises for a
    bad FMU (its faults are findings of the report)."""
    from ..engine import EngineOptions, check_fmu
    from ..findings import thaw

    catalogue = simulation_catalogue(settings)
    options = EngineOptions(select=(*ALWAYS, *RULES_BY_MODE[settings.mode]), probes_only=True)
    report = check_fmu(Path(path), options=options, catalogue=catalogue, display_path=str(path))
    info = thaw(report.info)
    simulation = info.get("simulation") if isinstance(info, dict) else None
    result = Simulation(report, catalogue)
    if isinstance(simulation, dict) and simulation.get("times") is not None:
        result.trajectories.append(Trajectory.from_info(simulation))
        if isinstance(simulation.get("ode"), dict):
            result.trajectories.append(Trajectory.from_info(simulation["ode"]))
        if isinstance(simulation.get("comparison"), dict):
            result.comparison = simulation["comparison"]
    return result
