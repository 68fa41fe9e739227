"""Independent evidence for a survivor's verdict: which promises the FMU breaks, measured with
fmpy alone (no lsdae code).

A survivor is a *consistent model change* when the mutant keeps every promise the original
keeps, a *missed defect* when it breaks one that lsdae did not report. The promises measured,
with the digest ids (``/work/shared/spec/fmi-ls-dae-digest.md``):

- Every instance is initialised as simulators do it: ODE mode with a tolerance and a stop
  time defined, DAE mode without (a failure there is the broken promise "runs through").
- MV-23: after instantiation (both modes) every variable with a ``start`` reads it back;
  after ``fmi3Reset`` every variable reads what a fresh instance reads, and the switch is off
  (DAE-11).
- MS-03, MS-06, SM-03, DAE-15: ``fmi3GetContinuousStates``, ``...StateDerivatives`` and
  ``fmi3GetEventIndicators`` equal ``fmi3GetFloat64`` of the variables they stand for, and the
  counts equal the XML's.
- FMI 3.0.2 §3.2.1: ``fmi3GetNominalsOfContinuousStates`` gives finite values > 0 whatever the
  caller's buffer held; derived: they equal the XML's ``nominal`` (1 when absent).
- DAE-12, DAE-40, DAE-41: the switch reads back true; in DAE mode a w set in Continuous-Time
  Mode reads back; DAE-42: at ODE mode's solved w, DAE mode's residuals vanish and its
  derivatives and outputs equal ODE mode's; DAE-14/DAE721: residuals vanish after
  initialisation in DAE mode.
- PD-06, MS-20, MS-31 (``promise_jacobian``): derivatives against finite differences,
  structural zeros, kinds.
- FMI 3.0.2 2.2.6: every Float64 variable reads back with ``fmi3GetFloat64`` (Instantiated,
  Continuous-Time Mode); 2.3.5: in event iterations, ``valuesOfContinuousStatesChanged`` is
  true only when a state changed, an announced ``nextEventTime`` is not in the past, the values
  read after an event iteration are up to date, every output argument is written (two instances whose outputs hold true / false before the call
  agree); the nominals do not depend on what the caller's buffer held.
- FMI 3.0.2 3.2.1: each variable read on its own, first after the point is set (coming from
  another point), reads what it reads with all the others: no read returns a value computed
  for an earlier point.
- Illegal calls are refused (an unknown value reference, setting a derivative, an output, or w
  in ODE mode, an event indicator or output as a known, a short seed, the switch's setter on
  another variable): SG-MATRIX, DAE-43, PD-01, PD-04, PD-05.
- Repeatability and independence: a point evaluated again after another gives the same
  values; a second instance alive beside the first, and a third after it, give the first's
  values at the same point.

``python -m bench.mutation.promises FMU --out FILE`` writes ``{key: detail}`` of the broken
promises; :func:`check` runs it in a subprocess with a timeout (a crash or hang is reported as
the promise "no crash").
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Any, Callable

from .fmu_view import Failure, SceneLayout, Session, fixed_points, illegal_calls, read_layout
from .promise_calls import (CONSISTENT_REL, compare, events, noise_of, read_alone,
                            running)
from .promise_jacobian import Violation, derivative_violations, kind_violations

REPO_ROOT = Path(__file__).resolve().parents[2]
def _start_and_reset(unzipped: Path, lay: SceneLayout, mode: str) -> list[Violation]:
    vrs = lay.all_vrs()
    names = [lay.variables[vr].name for vr in vrs]
    fresh = Session(unzipped, lay, "fresh")
    if mode == "dae":
        fresh.configure_dae()
    first = fresh.read(vrs)
    fresh.free()
    out = _refused(first, names, f"Instantiated, {mode}")
    with_start = [(n, g, lay.variables[vr].start) for n, g, vr in zip(names, first, vrs)
                  if lay.variables[vr].start is not None]
    out += compare(f"MV-23 start value in Instantiated ({mode})", [n for n, _, _ in with_start],
                   [g for _, g, _ in with_start], [w for _, _, w in with_start])
    s = running(unzipped, lay, mode, "reset")
    p = fixed_points(lay)[0]
    s.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
    s.read(vrs)
    s.call("fmi3Reset", s.model.reset)
    if mode == "ode":
        reference = first
    else:
        fresh = Session(unzipped, lay, "fresh-ode")
        reference = fresh.read(vrs)
        fresh.free()
    out += compare(f"MV-23 value after fmi3Reset ({mode})", names, s.read(vrs), reference)
    if s.enable() is not False:
        out.append((f"DAE-11 switch off after fmi3Reset ({mode})", f"reads {s.enable()}"))
    s.free()
    return out


def _refused(values: list[Any], names: list[str], where: str) -> list[Violation]:
    return [(f"FMI 3.0.2 2.2.6 fmi3GetFloat64 reads every variable ({where}) {n}", str(v)[:120])
            for n, v in zip(names, values) if isinstance(v, str)]


def _getters(s: Session, lay: SceneLayout, where: str) -> list[Violation]:
    out: list[Violation] = []
    n = len(lay.states)
    for vector, vrs, key in (("states", lay.states, "MS-03 fmi3GetContinuousStates"),
                             ("derivatives", lay.derivatives,
                              "MS-03 fmi3GetContinuousStateDerivatives"),
                             ("indicators", lay.indicators, "MS-06 fmi3GetEventIndicators")):
        if vrs:
            got = s.vector(vector, len(vrs))
            names = [lay.variables[vr].name for vr in vrs]
            want = s.read(vrs)
            out += compare(f"{key} = fmi3GetFloat64 ({where})", names,
                           got if isinstance(got, list) else [got] * len(vrs), want)
    nominals = s.vector("nominals", n)
    if nominals != s.vector("nominals", n, fill=1e300):
        out.append((f"FMI 3.0.2 3.2.1 nominals whatever the buffer held ({where})",
                    f"{nominals} / {s.vector('nominals', n, fill=1e300)}"))
    if n and isinstance(nominals, list):
        bad = [v for v in nominals if not (isinstance(v, float) and math.isfinite(v) and v > 0)]
        if bad:
            out.append((f"FMI 3.0.2 3.2.1 nominals finite and > 0 ({where})", f"{nominals}"))
        xml = [lay.variables[vr].nominal or 1.0 for vr in lay.states]
        out += compare(f"derived: nominals = XML nominal ({where})",
                       [lay.variables[vr].name for vr in lay.states], nominals, xml)
    counts = {"states": s.call("count", s.model.getNumberOfContinuousStates),
              "indicators": s.call("count", s.model.getNumberOfEventIndicators)}
    for what, want in (("states", n), ("indicators", len(lay.indicators))):
        if counts[what] != want:
            out.append((f"SM-03 number of {what} = XML ({where})",
                        f"{counts[what]} instead of {want}"))
    return out


def _mode(unzipped: Path, lay: SceneLayout, mode: str) -> list[Violation]:
    out: list[Violation] = []
    s = running(unzipped, lay, mode, f"promises-{mode}")
    vrs = lay.all_vrs()
    names = [lay.variables[vr].name for vr in vrs]
    if mode == "dae":
        if s.enable() is not True:
            out.append(("DAE-12 switch reads back true", f"reads {s.enable()}"))
        res = s.read(lay.residuals)
        if any(not isinstance(r, float) or not abs(r) <= 1e-6 for r in res):
            out.append(("DAE-14/DAE721 residuals vanish after initialisation (dae)", f"{res}"))
    jacobians = []
    values = {}
    for k, p in enumerate(fixed_points(lay), start=1):
        s.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
        values[k] = s.read(vrs)
        out += _refused(values[k], names, f"Continuous-Time Mode, {mode}")
        out += _getters(s, lay, f"{mode} p{k}")
        if mode == "dae" and lay.algebraic:
            out += compare("DAE-40 w set in Continuous-Time Mode reads back (dae)",
                           [lay.variables[vr].name for vr in lay.algebraic],
                           s.read(lay.algebraic), p["w"])
        found, jac = derivative_violations(s, lay, mode, f"p{k}")
        out += found
        jacobians.append(jac)
    out += kind_violations(lay, mode, jacobians)
    p = fixed_points(lay)[0]
    out += read_alone(s, lay, p, mode, values[1])
    s.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
    noise = noise_of(lay, mode)
    out += compare(f"repeatable: p1 again after p2 ({mode})", names, s.read(vrs), values[1],
                   noise=noise)
    other = running(unzipped, lay, mode, "second")
    other.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
    out += compare(f"independent: a second instance at p1 ({mode})", names,
                   other.read(vrs), values[1], noise=noise)
    other.free()
    out += compare(f"independent: the first instance after the second ({mode})", names,
                   s.read(vrs), values[1], noise=noise)
    s.free()
    third = running(unzipped, lay, mode, "third")
    third.set_point(p["t"], p["x"], p["u"], p["w"] if mode == "dae" else None)
    out += compare(f"independent: a later instance at p1 ({mode})", names, third.read(vrs),
                   values[1], noise=noise)
    third.free()
    return out


def _ode_dae(unzipped: Path, lay: SceneLayout) -> list[Violation]:
    """DAE-42 at each fixed point: DAE mode at ODE mode's solved w."""
    out: list[Violation] = []
    ode, dae = running(unzipped, lay, "ode", "ode"), running(unzipped, lay, "dae", "dae")
    unknowns = [*lay.derivatives, *lay.outputs]
    names = [lay.variables[vr].name for vr in unknowns]
    for k, p in enumerate(fixed_points(lay), start=1):
        ode.set_point(p["t"], p["x"], p["u"], None)
        w = [float(v) for v in ode.read(lay.algebraic)]
        dae.set_point(p["t"], p["x"], p["u"], w)
        res = dae.read(lay.residuals)
        if any(not isinstance(r, float) or not abs(r) <= 1e-8 for r in res):
            out.append((f"DAE-42 residuals vanish at ODE mode's w (p{k})", f"{res}"))
        out += compare(f"DAE-42 DAE mode = ODE mode (p{k})", names, dae.read(unknowns),
                       ode.read(unknowns), CONSISTENT_REL)
    ode.free()
    dae.free()
    return out


def _illegal(unzipped: Path, lay: SceneLayout, mode: str) -> list[Violation]:
    """Calls FMI 3.0 does not allow are refused with fmi3Error (SG-MATRIX, DAE-43, PD-01,
    PD-04, PD-05 of the digest; the switch's setter checks its value reference)."""
    outcome = illegal_calls(lambda: running(unzipped, lay, mode, "illegal"), mode)
    if mode == "dae":
        s = Session(unzipped, lay, "switch")
        s.call("fmi3EnterConfigurationMode", s.model.enterConfigurationMode)
        outcome["fmi3SetBoolean of a Float64 variable"] = s.status(
            "fmi3SetBoolean", s.model.setBoolean, [min(lay.variables)], [True])
        s.free()
    return [(f"an illegal call is refused ({mode}): {what}", "accepted with fmi3OK")
            for what, result in outcome.items() if result == "ok"]


def broken_unzipped(unzipped: Path) -> dict[str, str]:
    """The broken promises of an unpacked FMU: key -> detail."""
    lay = read_layout(unzipped)
    found: dict[str, str] = {}
    steps: list[tuple[str, Callable[[], list[Violation]]]] = [
        *((f"start and reset ({m})", lambda m=m: _start_and_reset(unzipped, lay, m))
          for m in ("ode", "dae")),
        *((f"mode {m}", lambda m=m: _mode(unzipped, lay, m)) for m in ("ode", "dae")),
        *((f"events {m}", lambda m=m: events(unzipped, lay, m)) for m in ("ode", "dae")),
        *((f"illegal calls {m}", lambda m=m: _illegal(unzipped, lay, m)) for m in ("ode", "dae")),
        ("ODE/DAE", lambda: _ode_dae(unzipped, lay))]
    for label, step in steps:
        try:
            for key, detail in step():
                found.setdefault(key, detail)
        except (Failure, ValueError, TypeError) as exc:
            found[f"runs through: {label}"] = str(exc)[:200]
    return found


def check(fmu: Path, *, timeout: float = 120.0) -> dict[str, str]:
    """:func:`broken_unzipped` in a subprocess; a crash or a hang is a broken promise too."""
    with tempfile.TemporaryDirectory(prefix="lsdae-promises-") as tmp:
        out = Path(tmp) / "promises.json"
        cmd = [sys.executable, "-m", "bench.mutation.promises", str(fmu), "--out", str(out)]
        try:
            proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            return {"no hang": f"no answer within {timeout:g} s"}
        if proc.returncode != 0 or not out.is_file():
            return {"no crash": f"exit {proc.returncode}: {proc.stderr.strip()[-200:]}"}
        return json.loads(out.read_text())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="The promises a scene FMU breaks (JSON).")
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="lsdae-promises-fmu-") as tmp:
        with zipfile.ZipFile(args.fmu) as zf:
            zf.extractall(tmp)
        found = broken_unzipped(Path(tmp))
    args.out.write_text(json.dumps(found, indent=1, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
