"""Simulation benchmark: work-precision of DAE mode (IDA) against ODE mode (CVODE).

For SimpleDAE, Robertson and Akzo, each FMU is integrated in DAE mode (SUNDIALS IDA with the
FMU's directional derivatives, conformance.numerics.dae) and in ODE mode (CVODE,
conformance.numerics.ode) for rtol = 1e-3 ... 1e-10 (atol_i = rtol * nominal_i), and the result
is compared with a reference at the output times:

* Robertson: the reference values of issue 5 (tight-tolerance solutions, consistent with the
  Hairer test set) at t = 0.4, 40, 4e5, 4e10;
* Akzo: the test set's reference solution at t = 180; at t = 1, 10, 50, 100 our own (the
  equations in numpy with y6 eliminated, scipy Radau, rtol 1e-13), which reproduces the t = 180
  values to a relative 1e-11 (checked on every run);
* SimpleDAE (inputs 0): our own, computed here: x1' = sin x1, x2' = sin(x1 x2), z1 = 0,
  z2 = asin(1/3)/x2 (the branch the FMU's Newton iteration takes from its start value), with
  scipy DOP853 at rtol 1e-13, at t = 0.25, 0.5, 0.75, 1.

The error of a run is measured per variable (states and algebraic variables) and output time
as |y - y_ref| / (|y_ref| + nominal), the norm the tolerances control (a run that meets its
tolerance everywhere has an error of about rtol); reported are the value at the final time and
the largest over all output times. Cost is the wall time of the integration (consistent
initialisation included; instantiation and the Jacobian's colouring left out; median of
``--runs`` runs after one warm-up run) and the number of FMI calls (the same in every run).
The sweep is not monotone in cost: every point is shown, failed runs are marked, and so are
runs that reached the stop time with an error above 1000 rtol.

Beside it, the cost and precision of the probes' derivative checks are taken from
``probes.json`` of ``bench.probe_bench`` (run it first; ``make bench`` does).

The FMUs are our own scenes, loaded in process. Writes ``simulation.md``, ``simulation.json``
and ``simulation.png`` into ``--out``.

    python -m bench.sim_bench [--out reports/bench] [--runs 5] [--quick]
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from bench.inprocess import LoadedFmu
from bench.static_bench import machine_info
from scenes.build import build_scene

SCENES = ("SimpleDAE", "Robertson", "Akzo")
RTOLS = tuple(10.0 ** -k for k in range(3, 11))
MODES = ("dae", "ode")
MAX_STEPS = 1_000_000
WALL_SECONDS = 120.0


# ------------------------------------------------------------------------------ references

@dataclass(frozen=True)
class Reference:
    """Values of every state and algebraic variable (by name) at the output times."""

    times: tuple[float, ...]
    values: dict[str, tuple[float, ...]]
    source: str


def robertson_reference() -> Reference:
    return Reference(
        times=(0.4, 40.0, 4e5, 4e10),
        values={"y1": (9.851721139e-1, 7.158270687e-1, 4.938274521e-3, 5.208345181e-8),
                "y2": (3.386395379e-5, 9.185534765e-6, 1.984994088e-8, 2.083338179e-13),
                "y3": (1.479402219e-2, 2.841637457e-1, 9.950617056e-1, 9.999999479e-1)},
        source="issue 5 (tight-tolerance solutions, consistent with the Hairer test set)")


AKZO_180 = (0.1150794920661702, 0.1203831471567715e-2, 0.1611562887407974,
            0.3656156421249283e-3, 0.1708010885264404e-1, 0.4873531310307455e-2)
AKZO_KS = 115.83


def _akzo_rhs(t: float, y: np.ndarray) -> list[float]:
    y1, y2, y3, y4, y5 = y
    y6 = AKZO_KS * y1 * y4
    s2 = math.sqrt(max(y2, 0.0))
    r1, r2, r3 = 18.7 * y1 ** 4 * s2, 0.58 * y3 * y4, 0.58 / 34.4 * y1 * y5
    r4, r5, fin = 0.09 * y1 * y4 ** 2, 0.42 * y6 ** 2 * s2, 3.3 * (0.9 / 737.0 - y2)
    return [-2 * r1 + r2 - r3 - r4, -0.5 * r1 - r4 - 0.5 * r5 + fin, r1 - r2 + r3,
            -r2 + r3 - 2 * r4, r2 - r3 + r5]


def akzo_reference() -> Reference:
    from scipy.integrate import solve_ivp

    times = (1.0, 10.0, 50.0, 100.0, 180.0)
    sol = solve_ivp(_akzo_rhs, (0.0, 180.0), [0.444, 0.00123, 0.0, 0.007, 0.0],
                    method="Radau", rtol=1e-13, atol=1e-16, t_eval=times)
    y = np.vstack([sol.y, AKZO_KS * sol.y[0] * sol.y[3]])
    deviation = np.max(np.abs(y[:, -1] - AKZO_180) / np.abs(AKZO_180))
    if not (sol.success and deviation < 1e-11):
        raise RuntimeError(f"the Akzo reference does not reproduce the test set ({deviation:g})")
    y[:, -1] = AKZO_180
    return Reference(times, {f"y{i + 1}": tuple(map(float, y[i])) for i in range(6)},
                     "t = 180: the test set (PSIDE, tolerance 1e-19); earlier times: ours "
                     f"(numpy, y6 eliminated, scipy Radau rtol 1e-13; {deviation:.1e} from the "
                     "test set at t = 180)")


def simple_dae_reference() -> Reference:
    from scipy.integrate import solve_ivp

    times = (0.25, 0.5, 0.75, 1.0)
    sol = solve_ivp(lambda t, x: [math.sin(x[0]), math.sin(x[0] * x[1])], (0.0, 1.0),
                    [0.5, 0.5], method="DOP853", rtol=1e-13, atol=1e-15, t_eval=times)
    x1, x2 = sol.y
    return Reference(times, {"x1": tuple(x1), "x2": tuple(x2), "z1": (0.0,) * len(times),
                             "z2": tuple(math.asin(1.0 / 3.0) / x2)},
                     "ours: x1' = sin x1, x2' = sin(x1 x2), z1 = 0, z2 = asin(1/3)/x2 "
                     "(inputs 0), scipy DOP853 rtol 1e-13")


REFERENCES = {"SimpleDAE": simple_dae_reference, "Robertson": robertson_reference,
              "Akzo": akzo_reference}


# ------------------------------------------------------------------------------- the FMUs

class SceneFmu(LoadedFmu):
    """A scene FMU loaded in process with lsdae's session, ready to simulate in either mode."""

    def simulate(self, mode: str, settings: Any, stop: float) -> tuple[Any, float]:
        """One run on a fresh instance: (Trajectory, wall seconds of the integration, from the
        initialised instance and the system's Jacobian colouring, which are left out)."""
        from conformance.runtime.modes import start_instance
        from conformance.numerics.dae import integrate_dae
        from conformance.numerics.ode import integrate_ode
        from conformance.simulate.system import FmuDae, FmuOde

        inst = start_instance(self.library, mode)
        try:
            t0 = float(self.layout.start_time)
            if mode == "dae":
                dae = FmuDae(inst, self.layout, self.manifest,
                             dense_up_to=settings.dense_up_to)
                y0 = inst.get_float64([*dae.states, *dae.algebraic])
                start = time.perf_counter()
                traj = integrate_dae(dae, settings, t0=t0, y0=y0, stop=stop)
            else:
                ode = FmuOde(inst, self.layout, self.model, dense_up_to=settings.dense_up_to)
                nominal = np.array([self.layout.scale(vr) for vr in ode.algebraic])
                x0 = inst.get_float64(ode.states)
                start = time.perf_counter()
                traj = integrate_ode(ode, settings, t0=t0, x0=x0, stop=stop,
                                     algebraic_nominal=nominal)
            return traj, time.perf_counter() - start
        finally:
            inst.free()


def settings_for(rtol: float, reference: Reference) -> Any:
    from conformance.report.catalogue import default_catalogue
    from conformance.numerics.settings import Settings

    options = dict(default_catalogue()["simulation-failed"].option_values)  # the defaults
    return Settings(**{**options, "mode": "both", "rtol": rtol, "stop_time": reference.times[-1],
                       "output_times": tuple(reference.times), "max_steps": MAX_STEPS,
                       "wall_seconds": WALL_SECONDS})


def errors(traj: Any, reference: Reference, nominal: dict[str, float]
           ) -> tuple[float, float, dict[str, float]]:
    """(final-time error, largest error over the output times, final error per variable);
    NaN where the run did not get there or a value could not be read."""
    per_time = []
    final_by_var: dict[str, float] = {}
    for k, t in enumerate(reference.times):
        row = next((i for i, s in enumerate(traj.times) if math.isclose(s, t, rel_tol=1e-12)),
                   None)
        worst = math.nan
        for name, ref in reference.values.items():
            value = traj.values[row, traj.names.index(name)] if row is not None else math.nan
            e = abs(value - ref[k]) / (abs(ref[k]) + nominal[name])
            worst = e if math.isnan(worst) or e > worst else worst
            if k == len(reference.times) - 1:
                final_by_var[name] = float(e)
        per_time.append(worst)
    final = per_time[-1]
    largest = math.nan if any(math.isnan(e) for e in per_time) else max(per_time)
    return float(final), float(largest), final_by_var


# ---------------------------------------------------------------------------- the sweep

def bench_scene(scene: str, runs: int, rtols: Sequence[float]) -> tuple[list[dict], Reference]:
    reference = REFERENCES[scene]()
    fmu = SceneFmu(build_scene(scene))
    rows = []
    try:
        nominal = {name: fmu.nominal(name) for name in reference.values}
        for rtol in rtols:
            settings = settings_for(rtol, reference)
            for mode in MODES:
                fmu.simulate(mode, settings, reference.times[-1])  # warm-up (imports, caches)
                seconds, traj = [], None
                for _ in range(runs):
                    traj, wall = fmu.simulate(mode, settings, reference.times[-1])
                    seconds.append(wall)
                final, largest, by_var = errors(traj, reference, nominal)
                rows.append({
                    "scene": scene, "mode": mode, "rtol": rtol, "status": traj.status,
                    "ok": traj.ok, "message": traj.message, "t_end": traj.t_end,
                    "steps": traj.steps, "function_calls": traj.function_calls,
                    "jacobian_calls": traj.jacobian_calls, "fmi_calls": traj.fmi_calls,
                    "seconds": statistics.median(seconds), "seconds_all": seconds,
                    "error_final": final, "error_max": largest, "error_final_by_variable": by_var,
                    "jacobian": traj.jacobian})
    finally:
        fmu.close()
    return rows, reference


def probe_methods(out: Path) -> dict[str, Any]:
    """The derivative-check table of bench.probe_bench (``probes.json`` in ``out``)."""
    path = out / "probes.json"
    if not path.is_file():
        return {"source": None, "methods": []}
    data = json.loads(path.read_text())
    return {"source": path.name, "date": data.get("date"), "runs": data.get("runs"),
            "methods": list(data.get("methods") or [])}


def run(args: argparse.Namespace, command: str) -> dict[str, Any]:
    scenes = ("SimpleDAE",) if args.quick else SCENES
    rtols = (1e-3, 1e-6) if args.quick else RTOLS
    results, references = [], {}
    for scene in scenes:
        rows, reference = bench_scene(scene, args.runs, rtols)
        results += rows
        references[scene] = {"times": list(reference.times), "source": reference.source,
                             "values": {k: list(v) for k, v in reference.values.items()}}
    import sksundae

    return {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "machine": machine_info(), "numpy": np.__version__,
            "scikit-sundae": getattr(sksundae, "__version__", "unknown"),
            "command": command, "runs": args.runs, "rtols": list(rtols),
            "error": "max over variables of |y - y_ref| / (|y_ref| + nominal)",
            "references": references, "results": results, "probes": probe_methods(args.out)}


# ------------------------------------------------------------------------------ the report

def _g(value: float | None, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    return f"{value:.{digits}g}"


def wrong(row: dict[str, Any]) -> bool:
    """A run that reached its stop time with an error far beyond its tolerance."""
    return bool(row["ok"] and row["error_final"] > max(1e3 * row["rtol"], 1e-2))


def notes(data: dict[str, Any]) -> list[str]:
    """What the numbers say, derived from them: failures, cost inversions, the cheapest run
    reaching an error of 1e-6."""
    out = []
    by = {}
    for r in data["results"]:
        by.setdefault((r["scene"], r["mode"]), []).append(r)
    for (scene, mode), rows in by.items():
        label = f"{scene}, {mode.upper()} mode"
        for r in rows:
            if not r["ok"]:
                out.append(f"{label}, rtol {r['rtol']:g}: **failed** ({r['status']}: "
                           f"{r['message']}) at t = {r['t_end']:.6g}.")
            elif wrong(r):
                out.append(f"{label}, rtol {r['rtol']:g}: reached the stop time but the final "
                           f"error is {r['error_final']:.2g}: the solver's error test did not "
                           "catch it.")
        costs = [(r["rtol"], r["fmi_calls"]) for r in rows]
        inversions = [f"{a[0]:g} -> {b[0]:g}" for a, b in pairwise(costs) if b[1] < a[1]]
        if inversions:
            out.append(f"{label}: a tighter rtol took fewer FMI calls at {', '.join(inversions)}.")
    for scene in dict.fromkeys(r["scene"] for r in data["results"]):
        good = [r for r in data["results"] if r["scene"] == scene and r["ok"]
                and r["error_max"] <= 1e-6]
        if good:
            best = min(good, key=lambda r: r["seconds"])
            out.append(f"{scene}: the cheapest run with every error below 1e-6 is "
                       f"{best['mode'].upper()} mode at rtol {best['rtol']:g} "
                       f"({best['seconds'] * 1e3:.1f} ms, {best['fmi_calls']} FMI calls).")
    return out


def render_markdown(data: dict[str, Any]) -> str:
    m = data["machine"]
    lines = [
        "# Simulation benchmark: DAE mode (IDA) against ODE mode (CVODE), error against cost",
        "",
        (f"Run {data['date']} on {m['cpu']} ({m['usable_cores']} usable cores), {m['platform']}, "
         f"Python {m['python']}, numpy {data['numpy']}, scikit-sundae {data['scikit-sundae']}, "
         f"fmpy {m['fmpy']}. Wall times are medians of {data['runs']} runs after a warm-up run; "
         "FMI calls do not vary between runs."),
        f"`{data['command']}`.",
        "",
        ("Error: per variable (states and algebraic variables) and output time, "
         "|y − y_ref| / (|y_ref| + nominal), the norm the tolerances control (atol_i = rtol · "
         "nominal_i): a run that meets its tolerance everywhere has an error of about rtol. "
         "*final*: at the last output time; *max*: the largest over all output times. "
         "DAE mode integrates states and algebraic variables with IDA and the FMU's directional "
         "derivatives; ODE mode integrates the states with CVODE and reads the algebraic "
         "variables the FMU solved. Cost: wall time of the integration (consistent "
         "initialisation included; instantiation and the Jacobian's colouring left out) and FMI "
         "calls. A failed run is marked **failed**; its errors "
         "are where it got to (– if it never reached an output time)."),
        "",
        "References:",
        "",
    ]
    for scene, ref in data["references"].items():
        times = ", ".join(f"{t:g}" for t in ref["times"])
        lines.append(f"* **{scene}** at t = {times}: {ref['source']}.")
    for scene in data["references"]:
        lines += ["", f"## {scene}", "",
                  ("| rtol | mode | status | steps | FMI calls | time (ms) | final error "
                   "| max error |"), "|---|---|---|---|---|---|---|---|"]
        for r in (r for r in data["results"] if r["scene"] == scene):
            status = "ok" if r["ok"] else f"**failed** ({r['status']})"
            status += " (error > 1000 rtol)" if wrong(r) else ""
            lines.append(f"| {r['rtol']:g} | {r['mode'].upper()} | {status} | {r['steps']} | "
                         f"{r['fmi_calls']} | {r['seconds'] * 1e3:.3g} | "
                         f"{_g(r['error_final'])} | {_g(r['error_max'])} |")
    lines += ["", "## What the numbers say", ""]
    lines += [f"* {n}" for n in notes(data)] or ["* Every run reached its stop time."]
    probes = data["probes"]
    lines += ["", "## Beside it: the probes' derivative checks", ""]
    if not probes["methods"]:
        lines.append("No `probes.json` found: run `python -m bench.probe_bench` first "
                     "(`make bench` does).")
    else:
        lines += [
            (f"From `{probes['source']}` ({probes['date']}, medians of {probes['runs']} runs): "
             "one derivative survey at the seeded sampling points (start + 3 near, seed 0) with "
             "each finite-difference method. Errors are relative to the row scale "
             "S_i = Σ_j |J_ij|·nominal_j: *measured* against the FMU's analytic directional "
             "derivatives, *estimated* is the bound the method gives itself."), "",
            ("| scene | method | FMI calls | time (ms) | measured error | estimated error "
             "| findings |"), "|---|---|---|---|---|---|---|"]
        for r in probes["methods"]:
            lines.append(f"| {r['scene']} | {r['method']} | {r['fmi_calls']} | "
                         f"{r['seconds'] * 1e3:.2g} | {_g(r['max_error'])} | "
                         f"{_g(r['max_estimate'])} | {r['findings']} |")
    lines += ["", "![error against wall time and FMI calls](simulation.png)", ""]
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    scenes = list(data["references"])
    columns = scenes + (["probes"] if data["probes"]["methods"] else [])
    fig, axes = plt.subplots(2, len(columns), figsize=(4.2 * len(columns), 7.5), squeeze=False)
    colours = {"dae": "tab:blue", "ode": "tab:orange"}
    for c, scene in enumerate(columns):
        for r, (key, label) in enumerate((("seconds", "wall time (s)"),
                                          ("fmi_calls", "FMI calls"))):
            ax = axes[r][c]
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(label)
            ax.grid(True, which="both", alpha=0.3)
            if scene == "probes":
                _plot_probes(ax, data["probes"]["methods"], key)
                continue
            ax.set_title(scene if r == 0 else "")
            ax.set_ylabel("error")
            for mode in MODES:
                rows = [x for x in data["results"] if x["scene"] == scene and x["mode"] == mode]
                xs = [x[key] for x in rows]
                ax.plot(xs, [x["error_final"] for x in rows], "-o", color=colours[mode],
                        ms=4, lw=1, label=f"{mode.upper()} final")
                ax.plot(xs, [x["error_max"] for x in rows], ":s", color=colours[mode], ms=4,
                        lw=1, mfc="none", label=f"{mode.upper()} max over times")
                for x in rows:
                    y = x["error_final"] if np.isfinite(x["error_final"]) else 1.0
                    if not x["ok"]:
                        ax.plot([x[key]], [y], "x", color="red", ms=10, mew=2)
                    elif wrong(x):
                        ax.plot([x[key]], [y], "o", color="red", ms=10, mfc="none", mew=1.5)
                for x in rows[::3]:
                    if np.isfinite(x["error_final"]):
                        ax.annotate(f"{x['rtol']:g}", (x[key], x["error_final"]), fontsize=6,
                                    xytext=(3, 3), textcoords="offset points")
            if r == 0 and c == 0:
                ax.legend(fontsize=7)
    for ax in axes.flat:   # minor labels only where no power of ten is in view
        lo, hi = ax.get_xlim()
        if math.floor(math.log10(hi)) > math.floor(math.log10(lo)):
            ax.xaxis.set_minor_formatter(NullFormatter())
        else:
            ax.tick_params(axis="x", which="minor", labelsize=6, labelrotation=30)
    fig.suptitle("Error against cost, rtol 1e-3 … 1e-10 (red x: failed run; red circle: reached "
                 f"the stop time with an error > 1000 rtol) — {data['date']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_probes(ax: Any, methods: list[dict[str, Any]], key: str) -> None:
    """One line per scene through its forward, central and extrapolated differences."""
    markers = {"forward": "v", "central": "o", "extrapolated": "^"}
    for scene in dict.fromkeys(row["scene"] for row in methods):
        rows = [row for row in methods if row["scene"] == scene]
        line, = ax.plot([row[key] for row in rows], [max(row["max_error"], 1e-17) for row in rows],
                        "-", lw=0.8, label=scene)
        for row in rows:
            ax.plot([row[key]], [max(row["max_error"], 1e-17)], markers.get(row["method"], "o"),
                    color=line.get_color(), ms=6)
    ax.set_title("derivative checks (probes)" if key == "seconds" else "")
    ax.set_ylabel("measured error (row-scaled)")
    if key == "seconds":
        ax.legend(fontsize=7, title="v forward, o central, ^ extrapolated", title_fontsize=7)


def _json_safe(value: Any) -> Any:
    """NaN and infinities as null (JSON has neither)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.sim_bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--quick", action="store_true",
                        help="SimpleDAE at two tolerances (for the tests)")
    args = parser.parse_args(argv)
    command = " ".join(["python -m bench.sim_bench",
                        *(sys.argv[1:] if argv is None else list(argv))])
    args.out.mkdir(parents=True, exist_ok=True)
    data = run(args, command)
    (args.out / "simulation.json").write_text(
        json.dumps(_json_safe(data), indent=2, allow_nan=False) + "\n")
    (args.out / "simulation.md").write_text(render_markdown(data))
    plot(data, args.out / "simulation.png")
    print(render_markdown(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
