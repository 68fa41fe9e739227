"""What a simulation is asked to do (:class:`Settings`) and what it produced (:class:`Trajectory`).

Settings come from the options of the ``simulation-failed`` catalogue entry (``lsdae check``)
or from the command line (``lsdae simulate``). A trajectory is plain data: it travels from the
worker process to the runner as JSON (:meth:`Trajectory.to_info`), NaN written as null.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any, Mapping, Sequence

import numpy as np

MODES = ("dae", "ode", "both")

# Why a run ended; every status but "ok" and "time-budget" is reported by one rule. BUDGET is
# our budget of steps (a count: the same on every machine); TIME_BUDGET is the wall-clock
# safety net, whose end says nothing about the FMU: the simulation rules do not run then.
OK, SOLVER, SINGULAR, FMU_FAILED, BUDGET, INIT, TIME_BUDGET = (
    "ok", "solver-failure", "singular", "fmu-failure", "budget", "init-failure", "time-budget")


@dataclass(frozen=True)
class Settings:
    """How to simulate. Times in the model's time unit, budgets per run (one mode).

    The defaults are the options of the ``simulation-failed`` rule in the catalogue (the one
    place they are written): callers build Settings with :meth:`from_options` from them.
    """

    mode: str                           # dae | ode | both
    rtol: float
    atol_factor: float                  # atol_i = atol_factor * rtol * nominal_i
    stop_time: float                    # 0: DefaultExperiment stopTime, else start + horizon
    horizon: float
    output_points: int                  # an even grid from start to stop, both included
    max_steps: int                      # the budget that decides simulation-budget-exceeded
    wall_seconds: float                 # a safety net only: its end is "not run", no finding
    stall_steps: int                    # steps without progress in time before giving up
    max_condition: float                # stop when the scaled dg/dw condition exceeds this
    stalled_condition: float            # a run that stalls or fails with dg/dw this bad: singular
    record_wall_time: bool              # wall_s in the report (not reproducible: off in check)
    dense_up_to: int                    # unknowns up to which Jacobians are dense arrays
    published_series: int               # variables whose trajectory the report keeps (0: all)
    output_times: tuple[float, ...] = ()  # explicit output times (replace the grid)
    start_values: tuple[tuple[str, float], ...] = ()  # (variable name, value), set before init

    @classmethod
    def from_options(cls, options: Mapping[str, Any]) -> Settings:
        """Build from catalogue or command-line options, ignoring keys that are not settings."""
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in options.items() if k in known}
        if "output_times" in values:
            values["output_times"] = tuple(float(t) for t in values["output_times"])
        if "start_values" in values:
            values["start_values"] = tuple((str(n), float(v)) for n, v in values["start_values"])
        settings = cls(**values)
        settings.validate()
        return settings

    def validate(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, not {self.mode!r}")
        if not (0 < self.rtol < 1):
            raise ValueError(f"rtol must be between 0 and 1, not {self.rtol!r}")
        if self.output_points < 2 and not self.output_times:
            raise ValueError("at least two output points are needed")

    def as_options(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["output_times"] = list(self.output_times)
        out["start_values"] = [list(pair) for pair in self.start_values]
        return out

    def stop(self, start: float, default_stop: float | None) -> float:
        """The stop time: explicit, else the DefaultExperiment's, else start + horizon."""
        if self.stop_time and self.stop_time > start:
            return float(self.stop_time)
        if default_stop is not None and math.isfinite(default_stop) and default_stop > start:
            return float(default_stop)
        return start + float(self.horizon)

    def times(self, start: float, stop: float) -> np.ndarray:
        """Output times within [start, stop], start always first, sorted, without duplicates."""
        if self.output_times:
            chosen = [t for t in self.output_times if start < t <= stop]
            return np.array(sorted({start, *chosen}), dtype=float)
        return np.linspace(start, stop, max(2, int(self.output_points)))


@dataclass
class Trajectory:
    """The result of one run: values at the output times reached, and how the run went.

    ``values`` has shape (len(times), len(names)); states come first, then algebraic variables
    (``kinds``). NaN marks a value that could not be read (an algebraic variable in ODE mode).
    ``event`` describes why a run ended early: the time, the condition number, the FMI call...
    """

    mode: str
    names: list[str]
    kinds: list[str]
    times: list[float]
    values: np.ndarray
    status: str = OK
    message: str = ""
    t_start: float = 0.0
    t_end: float = 0.0
    stop_time: float = 0.0
    rtol: float = 0.0
    atol: list[float] = field(default_factory=list)
    steps: int = 0
    function_calls: int = 0             # residual (DAE) or right-hand side (ODE) evaluations
    jacobian_calls: int = 0
    fmi_calls: int = 0
    wall_s: float = 0.0
    jacobian: str = ""                  # "directional derivatives" or "finite differences"
    recovered: int = 0                  # failed evaluations the step reduction got past
    max_condition: float = 0.0          # largest scaled dg/dw condition seen (DAE mode)
    max_condition_t: float | None = None
    init: dict[str, Any] = field(default_factory=dict)
    event: dict[str, Any] = field(default_factory=dict)
    # DAE mode: the largest |residual| at the output times ({"max_abs", "residual", "t"})
    residual_along: dict[str, Any] = field(default_factory=dict)
    # events (numerics/events.py): indicators watched, events handled, their times (the first
    # 1000), fmi3UpdateDiscreteStates calls, where the FMU asked to end the run, and (DAE mode)
    # the largest residual after an event, before the algebraic variables were solved again
    indicators: int = 0
    state_events: int = 0
    time_events: int = 0
    event_times: list[float] = field(default_factory=list)
    event_updates: int = 0
    terminated_at: float | None = None
    residual_jump: float = 0.0
    # (t, nextEventTime) of events that announced a next time event not ahead (the first few)
    events_behind: list[tuple[float, float]] = field(default_factory=list)
    events_behind_count: int = 0

    @property
    def ok(self) -> bool:
        return self.status == OK

    def series(self, name: str) -> np.ndarray:
        return self.values[:, self.names.index(name)]

    def to_info(self, *, limit: int | None = None, timing: bool = True,
                series: int = 0) -> dict[str, Any]:
        """A JSON-ready summary (``limit``: keep at most that many output times, evenly;
        ``timing``: include ``wall_s``, which makes two reports of one FMU differ; ``series``:
        keep the trajectories of the first that many variables, states first, 0 for all,
        and say how many were left out)."""
        rows = np.arange(len(self.times))
        if limit is not None and len(rows) > limit > 1:
            rows = np.unique(np.linspace(0, len(rows) - 1, limit).round().astype(int))
        kept = len(self.names) if series <= 0 else min(series, len(self.names))
        names = self.names[:kept]
        block = self.values[rows][:, :kept]
        finite = np.isfinite(block).all(axis=0)
        info = {
            "mode": self.mode, "status": self.status, "message": self.message,
            "times": [float(self.times[i]) for i in rows],
            "series": {n: block[:, k].tolist() if finite[k] else
                       [_json_float(v) for v in block[:, k]] for k, n in enumerate(names)},
            "kinds": dict(zip(names, self.kinds)),
            "rtol": self.rtol, "atol": dict(zip(names, self.atol)),
            "t_start": self.t_start, "t_end": self.t_end, "stop_time": self.stop_time,
            "steps": self.steps, "function_calls": self.function_calls,
            "jacobian_calls": self.jacobian_calls, "fmi_calls": self.fmi_calls,
            "jacobian": self.jacobian,
            "recovered": self.recovered, "max_condition": _json_float(self.max_condition),
            "max_condition_t": self.max_condition_t, "init": self.init, "event": self.event,
        }
        if kept < len(self.names):  # only then: smaller reports stay as they were
            info["series_left_out"] = len(self.names) - kept
        if self.residual_along:
            info["residual_along"] = self.residual_along
        if self.has_events:  # only then: the reports of FMUs without events stay as they were
            info["events"] = {
                "indicators": self.indicators, "state": self.state_events,
                "time": self.time_events, "times": [float(t) for t in self.event_times],
                "updates": self.event_updates, "terminated_at": self.terminated_at,
                "residual_jump": self.residual_jump}
            if self.events_behind_count:  # only then: other reports stay as they were
                info["events"]["behind"] = [[float(t), float(n)] for t, n in self.events_behind]
                info["events"]["behind_count"] = self.events_behind_count
        if timing:
            info["wall_s"] = round(self.wall_s, 6)
        return info

    @property
    def has_events(self) -> bool:
        """Whether the run watched event indicators or handled an event."""
        return bool(self.indicators or self.state_events or self.time_events
                    or self.terminated_at is not None)

    @classmethod
    def from_info(cls, info: Mapping[str, Any]) -> Trajectory:
        """The inverse of :meth:`to_info` (for the command line, which reads the report)."""
        names = list(info.get("series", {}))
        columns = [[_float(v) for v in info["series"][n]] for n in names]
        times = [float(t) for t in info.get("times", [])]
        values = np.array(columns, dtype=float).T if names else np.zeros((len(times), 0))
        kinds = dict(info.get("kinds") or {})
        atol = dict(info.get("atol") or {})
        return cls(
            mode=str(info.get("mode", "")), names=names,
            kinds=[str(kinds.get(n, "")) for n in names], times=times,
            values=values.reshape(len(times), len(names)), status=str(info.get("status", OK)),
            message=str(info.get("message", "")), t_start=float(info.get("t_start", 0.0)),
            t_end=float(info.get("t_end", 0.0)), stop_time=float(info.get("stop_time", 0.0)),
            rtol=float(info.get("rtol", 0.0)), atol=[float(atol.get(n, 0.0)) for n in names],
            steps=int(info.get("steps", 0)), function_calls=int(info.get("function_calls", 0)),
            jacobian_calls=int(info.get("jacobian_calls", 0)),
            fmi_calls=int(info.get("fmi_calls", 0)), wall_s=float(info.get("wall_s", 0.0)),
            jacobian=str(info.get("jacobian", "")), recovered=int(info.get("recovered", 0)),
            max_condition=_float(info.get("max_condition")),
            max_condition_t=info.get("max_condition_t"), init=dict(info.get("init") or {}),
            event=dict(info.get("event") or {}),
            residual_along=dict(info.get("residual_along") or {}),
            **_events_from(info.get("events")))


def _events_from(events: Any) -> dict[str, Any]:
    if not isinstance(events, Mapping):
        return {}
    end = events.get("terminated_at")
    return {"indicators": int(events.get("indicators", 0)),
            "state_events": int(events.get("state", 0)), "time_events": int(events.get("time", 0)),
            "event_times": [float(t) for t in events.get("times") or ()],
            "event_updates": int(events.get("updates", 0)),
            "terminated_at": None if end is None else float(end),
            "residual_jump": float(events.get("residual_jump") or 0.0),
            "events_behind": [(float(t), float(n)) for t, n in events.get("behind") or ()],
            "events_behind_count": int(events.get("behind_count") or 0)}


def _json_float(value: Any) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def _float(value: Any) -> float:
    return math.nan if value is None else float(value)


def parse_times(text: str) -> tuple[float, ...]:
    """``"0.4,40,4e5"`` -> (0.4, 40.0, 400000.0); raises ValueError on anything else."""
    out: list[float] = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        value = float(part)
        if not math.isfinite(value):
            raise ValueError(f"not a finite time: {part!r}")
        out.append(value)
    if not out:
        raise ValueError("no output times given")
    return tuple(out)


def finite_rows(values: np.ndarray, columns: Sequence[int]) -> np.ndarray:
    """Rows where every one of ``columns`` is finite, as a boolean mask."""
    if not len(columns):
        return np.ones(values.shape[0], dtype=bool)
    return np.all(np.isfinite(values[:, list(columns)]), axis=1)
