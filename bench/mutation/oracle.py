"""The equivalence oracle: what fmpy observes of a scene FMU at fixed points, in both modes.

It does not use lsdae. For each mode (ODE: the switch left false; DAE: the switch set true in
Configuration Mode, w set by the importer) one instance goes through the life cycle and every
observation is recorded: all Float64 variables after instantiation (the start values), in
Initialization Mode with the directional derivatives there, after initialisation with the
vector getters (states, derivatives, nominals, event indicators) and the counts; at each fixed
point of :func:`fmu_view.fixed_points` (time, states -- with fmi3SetContinuousStates at the
first, fmi3SetFloat64 at the second --, inputs, and w in DAE mode) every variable, the vectors
and the full directional and adjoint Jacobians of derivatives, outputs (and residuals) with
respect to states, inputs (and w), then each vector and each variable read first after the
point is set again, coming from another point (so that no value cached at the old point or by
another read stands in for it); one event
iteration at the last point and one at t = 0.9 (after the time event of EventDAE), their output
arguments preset to true (an FMU must write them all); the outcome of illegal calls, each on a
fresh instance (``fmu_view.illegal_calls``, and the switch's setter given the value reference
of time); a stop time and tolerance defined for ODE mode's initialisation; a switch to DAE
mode in Reconfiguration Mode when the switch is tunable; the values after ``fmi3Reset``, and
after a second initialisation of the reset instance.

Run as ``python -m bench.mutation.oracle FMU --out FILE`` it writes the observations as JSON;
:func:`observe` runs that in a subprocess with a timeout, so a crashing or hanging mutant is an
observation too ("crashed", "timeout") and never an equivalent. :func:`differences` compares
two observations: floats at 1e-12 relative (1e-14 absolute for values near zero), everything
else exactly.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Any, Callable

from .fmu_view import Failure, SceneLayout, Session, fixed_points, illegal_calls, read_layout

RTOL = 1e-12
ATOL = 1e-14
REPO_ROOT = Path(__file__).resolve().parents[2]


def _step(obs: dict[str, Any], label: str, fn: Callable[[], Any]) -> bool:
    """Record ``fn()`` under ``label``; a failure is recorded and stops the sequence."""
    try:
        obs[label] = fn()
        return True
    except Failure as exc:
        obs[label] = f"failed: {exc}"
        return False
    except Exception as exc:  # fmpy's FMICallException from a direct call of the model
        obs[label] = f"failed: {type(exc).__name__}: {exc}"
        return False


def _snapshot(s: Session, lay: SceneLayout, vectors: bool = True) -> dict[str, Any]:
    out: dict[str, Any] = {"values": s.read(lay.all_vrs()), "enable": s.enable()}
    if vectors:
        out["states"] = s.vector("states", len(lay.states))
        out["derivatives"] = s.vector("derivatives", len(lay.states))
        out["nominals"] = s.vector("nominals", len(lay.states))
        if lay.indicators:
            out["indicators"] = s.vector("indicators", len(lay.indicators))
    return out


def _jacobians(s: Session, lay: SceneLayout, mode: str) -> dict[str, Any]:
    unknowns = [*lay.derivatives, *lay.outputs, *(lay.residuals if mode == "dae" else ())]
    knowns = [*lay.states, *lay.inputs, *(lay.algebraic if mode == "dae" else ())]
    return {"directional": s.jacobian(unknowns, knowns),
            "adjoint": s.jacobian(unknowns, knowns, adjoint=True)}


def _decoy(p: dict[str, Any]) -> dict[str, Any]:
    """Another point at the same time (time may not go back): every value moved by 1 %."""
    return {"t": p["t"], **{k: [v * 1.01 + 1e-3 for v in p[k]] for k in ("x", "u", "w")}}


def _fresh(s: Session, lay: SceneLayout, p: dict[str, Any], mode: str,
           by_value: bool) -> dict[str, Any]:
    """Each vector and each variable read first after the point is set again, coming from
    another point where everything was evaluated (so a value cached at the old point, or by
    another read, cannot stand in for it)."""
    def again() -> None:
        for q in (_decoy(p), p):
            s.set_point(q["t"], q["x"], q["u"], q["w"] if mode == "dae" else None,
                        by_value=by_value)
            if q is not p:
                s.read(lay.all_vrs())

    out: dict[str, Any] = {}
    for name, n in (("derivatives", len(lay.states)), ("indicators", len(lay.indicators))):
        if n:
            again()
            out[name] = s.vector(name, n)
    values = []
    for vr in lay.all_vrs():
        again()
        values.append(s.read([vr])[0])
    out["values"] = values
    return out


def _running(unzipped: Path, lay: SceneLayout, mode: str) -> Session:
    s = Session(unzipped, lay, f"oracle-{mode}-illegal")
    if mode == "dae":
        s.configure_dae()
    s.call("init", s.model.enterInitializationMode, startTime=0.0)
    s.call("init", s.model.exitInitializationMode)
    s.call("CT", s.model.enterContinuousTimeMode)
    return s


def _wrong_switch(unzipped: Path, lay: SceneLayout) -> str:
    """The switch's setter given the value reference of time, in Configuration Mode."""
    s = Session(unzipped, lay, "oracle-switch")
    try:
        s.call("fmi3EnterConfigurationMode", s.model.enterConfigurationMode)
        return s.status("fmi3SetBoolean", s.model.setBoolean, [min(lay.variables)], [True])
    finally:
        s.free()


def _counts(s: Session) -> dict[str, Any]:
    return {"states": s.call("fmi3GetNumberOfContinuousStates",
                             s.model.getNumberOfContinuousStates),
            "indicators": s.call("fmi3GetNumberOfEventIndicators",
                                 s.model.getNumberOfEventIndicators)}


def _run_mode(unzipped: Path, lay: SceneLayout, mode: str) -> dict[str, Any]:
    obs: dict[str, Any] = {}
    try:
        s = Session(unzipped, lay, f"oracle-{mode}")
    except Failure as exc:
        return {"instantiate": f"failed: {exc}"}
    m = s.model
    try:
        if mode == "dae" and not _step(obs, "configure", lambda: s.configure_dae() or "ok"):
            return obs
        obs["instantiated"] = _snapshot(s, lay, vectors=False)
        # ODE mode with a stop time and tolerance defined, DAE mode without
        init = (lambda: m.enterInitializationMode(tolerance=1e-6, startTime=0.0, stopTime=1.0)) \
            if mode == "ode" else (lambda: m.enterInitializationMode(startTime=0.0))
        if not _step(obs, "enter-init", lambda: init() or "ok"):
            return obs
        init_unknowns = [*lay.derivatives, *lay.outputs,
                         *(lay.algebraic if mode == "dae" else ())]
        obs["init-mode"] = {"values": s.read(lay.all_vrs()),
                            "directional": s.jacobian(init_unknowns,
                                                      [*lay.states, *lay.inputs])}
        if not _step(obs, "exit-init", lambda: m.exitInitializationMode() or "ok"):
            return obs
        obs["initialized"] = _snapshot(s, lay)
        _step(obs, "counts", lambda: _counts(s))
        if not _step(obs, "enter-ct", lambda: m.enterContinuousTimeMode() or "ok"):
            return obs
        obs["start"] = {**_snapshot(s, lay), **_jacobians(s, lay, mode)}
        _step(obs, "illegal", lambda: illegal_calls(lambda: _running(unzipped, lay, mode), mode))
        if mode == "dae":
            _step(obs, "wrong-switch", lambda: _wrong_switch(unzipped, lay))
        for k, p in enumerate(fixed_points(lay), start=1):
            by_value = k == 2   # states set with fmi3SetFloat64 at p2
            if not _step(obs, f"set-p{k}", lambda: s.set_point(
                    p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None,
                    by_value=by_value) or "ok"):
                return obs
            obs[f"p{k}"] = {**_snapshot(s, lay), **_jacobians(s, lay, mode)}
            if not _step(obs, f"p{k}-fresh", lambda: _fresh(s, lay, p, mode, by_value)):
                return obs
        if not _step(obs, "event", lambda: [m.enterEventMode(),
                                            *s.update_discrete_states(preset=True)]):
            return obs
        obs["after-event"] = _snapshot(s, lay)
        if not _step(obs, "late-event", lambda: [   # after the scenes' time event at 0.75
                m.enterContinuousTimeMode(), m.setTime(0.9), m.enterEventMode(),
                *s.update_discrete_states(preset=True), *s.update_discrete_states(preset=True)]):
            return obs
        obs["after-late-event"] = _snapshot(s, lay)
        if mode == "ode" and lay.enable_tunable:
            if _step(obs, "reconfigure", lambda: s.configure_dae() or "ok"):
                obs["reconfigured"] = _snapshot(s, lay)
        if not _step(obs, "reset", lambda: m.reset() or "ok"):
            return obs
        obs["reset"] = _snapshot(s, lay, vectors=False)
        if _step(obs, "reinit", lambda: [m.enterInitializationMode(startTime=0.0),
                                         m.exitInitializationMode()] and "ok"):
            obs["reinitialized"] = _snapshot(s, lay)
        return obs
    finally:
        s.free()


def observe_unzipped(unzipped: Path) -> dict[str, Any]:
    lay = read_layout(unzipped)
    return {mode: _run_mode(unzipped, lay, mode) for mode in ("ode", "dae")}


def observe(fmu: Path, *, timeout: float = 60.0) -> dict[str, Any]:
    """The observations of ``fmu`` from a subprocess: ``{"status": "ok", "obs": ...}``, or
    ``{"status": "crashed" | "timeout", ...}``."""
    with tempfile.TemporaryDirectory(prefix="lsdae-oracle-") as tmp:
        out = Path(tmp) / "obs.json"
        cmd = [sys.executable, "-m", "bench.mutation.oracle", str(fmu), "--out", str(out)]
        try:
            proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            return {"status": "timeout", "seconds": timeout}
        if proc.returncode != 0 or not out.is_file():
            return {"status": "crashed", "returncode": proc.returncode,
                    "stderr": proc.stderr[-400:]}
        return {"status": "ok", "obs": json.loads(out.read_text())}


def _close(a: float, b: float) -> bool:
    return a == b or abs(a - b) <= RTOL * max(abs(a), abs(b)) + ATOL


def differences(a: Any, b: Any, where: str = "", limit: int = 8) -> list[str]:
    """Where ``b`` differs from ``a`` (paths of the observation tree), at most ``limit``."""
    out: list[str] = []

    def walk(x: Any, y: Any, path: str) -> None:
        if len(out) >= limit:
            return
        if isinstance(x, dict) and isinstance(y, dict):
            for key in sorted(set(x) | set(y)):
                walk(x.get(key, "<missing>"), y.get(key, "<missing>"), f"{path}/{key}")
        elif isinstance(x, list) and isinstance(y, list) and len(x) == len(y):
            for i, (xi, yi) in enumerate(zip(x, y)):
                walk(xi, yi, f"{path}[{i}]")
        elif isinstance(x, float) and isinstance(y, float) and not isinstance(x, bool):
            if not _close(x, y):
                out.append(f"{path}: {x!r} -> {y!r}")
        elif x != y or type(x) is not type(y):
            out.append(f"{path}: {str(x)[:60]} -> {str(y)[:60]}")

    walk(a, b, where)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Observe a scene FMU with fmpy (JSON).")
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="lsdae-oracle-fmu-") as tmp:
        with zipfile.ZipFile(args.fmu) as zf:
            zf.extractall(tmp)
        obs = observe_unzipped(Path(tmp))
    args.out.write_text(json.dumps(obs, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
