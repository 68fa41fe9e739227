"""Probe benchmark: what the derivative check costs in FMU calls and time, against its error.

Two tables, side by side in one run, medians over ``--runs`` runs (calls do not vary):

1. **Methods.** For every scene FMU, the derivative survey (conformance.probes.derivatives.partials:
   coloured finite differences, directional and adjoint derivatives, verification of the
   declared zeros) at the seeded sampling points, with forward, central and extrapolated
   differences: FMI calls, wall time, the largest finite-difference error measured against the
   FMU's analytic directional derivatives, and the largest error the method *estimated*, both
   relative to the row scale S_i = sum_j |J_ij| nominal_j; and the findings the rules would
   report (all scenes are correct, so any is a false positive).
2. **Scaling.** The Chain scene (tridiagonal dg/dw) with coloured against column-by-column
   Jacobians, at one point, on the C FMU at N = 1000 and 10000 (``--chain-fmu-sizes``; the
   framework works in O(nnz) for a model that declares its pattern). Coloured needs the same
   number of calls for every N; column by column runs up to ``--full-by-column-up-to`` and is
   marked, with an estimate from the largest N run, above it. ``--chain-twin-sizes`` adds a
   numpy twin of the same equations through the same
   :func:`conformance.numerics.measure.measure` (the checker's own cost, no FMI calls).
3. **Calls.** The cost of one fmi3GetDirectionalDerivative / fmi3GetAdjointDerivative call of
   the Chain FMU, through fmpy's ctypes with the arrays prepared: DAE mode with every residual,
   derivative and output against every state, algebraic variable and input (the whole Jacobian
   times a vector), and ODE mode (total derivatives through a solve with dg/dw).

The C FMUs are loaded in process (our own scenes, no isolation needed). Writes ``probes.md``,
``probes.json`` and ``probes.png`` into ``--out``.

    python -m bench.probe_bench [--out reports/bench] [--runs 5] [--quick]
"""
from __future__ import annotations

import argparse
import ctypes
import datetime as dt
import json
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from lxml import etree

from bench.inprocess import LoadedFmu
from bench.static_bench import machine_info
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description
from conformance.numerics import colouring as col
from conformance.numerics import measure
from conformance.report.catalogue import default_catalogue
from conformance.probes.machinery.registry import PROBES
from conformance.probes.instruments import jacobian as J
from conformance.numerics import numdiff
from conformance.probes.instruments.api import ProbeContext
from scenes.build import build_scene
from scenes.Chain import chain

SCENES = ("SimpleDAE", "Robertson", "HelloWorldDAE", "Chain")
RULES = ("DAE740", "DAE741", "DAE742", "DAE743", "DAE744", "DAE745", "DAE746")
OPTIONS = {r.code: r.option_values for r in default_catalogue()}  # the catalogue's defaults


class Fmu(LoadedFmu):
    """A scene FMU loaded in process with lsdae's own session, with an instance in DAE mode."""

    def __init__(self, path: Path):
        from conformance.runtime.modes import start_instance

        super().__init__(path)
        self.dae = start_instance(self.library, "dae")

    def context(self, seed: int = 0, points: int | None = None) -> ProbeContext:
        from conformance.probes.instruments.sampling import near_points, start_point

        rng = np.random.default_rng(seed)
        start = start_point(self.dae, self.layout)
        pts = [start, *near_points(start, self.layout, rng)][:points]
        return ProbeContext(self.model, self.manifest, "alpha1", seed, rng, pts, self.dae,
                            None, lambda mode: None, {})


def scaled_errors(survey: J.Survey, ulps: float = numdiff.DEFAULT_ULPS) -> tuple[float, float]:
    """Largest |fd - dd| and largest estimated error, both times nominal_j / S_i."""
    assert survey.layout is not None
    nominal = survey.layout.nominal
    actual, estimate = 0.0, 0.0
    for ps in survey.points:
        e = ps.entries
        ok = ~np.isnan(e.dd)
        scale = np.bincount(e.rows[ok], weights=np.abs(e.dd[ok]) * nominal[e.cols[ok]],
                            minlength=len(survey.layout.rows))[e.rows]
        use = ok & (scale > 0)
        factor = nominal[e.cols[use]] / scale[use]
        actual = max(actual, float(np.max(np.abs(e.fd - e.dd)[use] * factor, initial=0.0)))
        estimate = max(estimate, float(np.max(e.error(ulps)[use] * factor, initial=0.0)))
    return actual, estimate


def _timed(fn: Callable[[], Any], runs: int) -> tuple[Any, list[float]]:
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, times


def bench_methods(runs: int, scenes: Sequence[str]) -> list[dict[str, Any]]:
    rows = []
    for scene in scenes:
        fmu = Fmu(chain.build_chain() if scene == "Chain" else build_scene(scene))
        try:
            for method in numdiff.METHODS:
                settings = J.Settings(method=method)
                before = fmu.dae.calls

                def once(fmu: Fmu = fmu, settings: J.Settings = settings
                         ) -> tuple[J.Survey, ProbeContext]:
                    ctx = fmu.context()
                    return J.run_survey(ctx, settings), ctx

                (survey, ctx), times = _timed(once, runs)
                calls = (fmu.dae.calls - before) // runs
                ctx.facts[J.FACT] = survey
                findings = sum(len(list(PROBES[code](ctx, **OPTIONS[code]))) for code in RULES)
                per = {k: sum(dict(p.entries.calls)[k] for p in survey.points)
                       for k in ("evaluate", "directional", "adjoint")}
                actual, estimate = scaled_errors(survey)
                rows.append({"scene": scene, "method": method, "points": len(survey.points),
                             "fmi_calls": calls, **per, "seconds": statistics.median(times),
                             "seconds_all": times, "max_error": actual,
                             "max_estimate": estimate, "findings": findings})
        finally:
            fmu.close()
    return rows


# --------------------------------------------------------------------------- Chain scaling

@dataclass
class ChainTwin:
    """Chain's equations in numpy on the layout's vectors: cols [x, w, u, t], rows [r, der, y]."""

    n: int
    base: np.ndarray

    def _split(self, v: np.ndarray):
        return v[0], v[1:self.n + 1], v[self.n + 1]

    def fun(self, delta: np.ndarray) -> np.ndarray:
        x, w, u = self._split(self.base + delta)
        r = 4 * w + np.sin(w)
        r[1:] -= w[:-1]
        r[:-1] -= w[1:]
        r[0] -= x
        r[-1] -= u
        return np.concatenate([r, [w[0] - x, w[-1]]])

    def directional(self, s: np.ndarray) -> np.ndarray:
        _, w, _ = self._split(self.base)
        sx, sw, su = self._split(s)
        r = (4 + np.cos(w)) * sw
        r[1:] -= sw[:-1]
        r[:-1] -= sw[1:]
        r[0] -= sx
        r[-1] -= su
        return np.concatenate([r, [sw[0] - sx, sw[-1]]])

    def adjoint(self, v: np.ndarray) -> np.ndarray:
        _, w, _ = self._split(self.base)
        vr, vd, vy = v[:self.n], v[self.n], v[self.n + 1]
        gw = (4 + np.cos(w)) * vr
        gw[:-1] -= vr[1:]
        gw[1:] -= vr[:-1]
        gw[0] += vd
        gw[-1] += vy
        return np.concatenate([[-vr[0] - vd], gw, [-vr[-1], 0.0]])


def _chain_layout(n: int) -> J.JacobianLayout:
    model = read_model_description(etree.ElementTree(etree.fromstring(
        chain.model_description(n).encode())))
    manifest = read_manifest(etree.ElementTree(etree.fromstring(chain.manifest(n).encode())),
                             draft="alpha1")
    ctx = ProbeContext(model, manifest, "alpha1", 0, np.random.default_rng(0), [], None, None,
                       lambda mode: None, {})
    layout, reason = J.build_layout(ctx)
    assert layout is not None, reason
    return layout


def _twin_case(n: int, coloured: bool, runs: int) -> dict[str, Any]:
    layout = _chain_layout(n)
    rng = np.random.default_rng(0)
    base = np.concatenate([[1.0], rng.uniform(-0.3, 0.3, n), [0.2], [0.0]])
    twin = ChainTwin(n, base)
    colouring = col.colour_columns(layout.pattern) if coloured else col.one_per_group(
        layout.pattern)
    rows = col.colour_rows(layout.pattern) if coloured else col.one_per_group(
        layout.pattern, rows=True)
    steps = numdiff.step_sizes(base, layout.nominal, method="central")
    sources = measure.Sources(twin.fun, twin.directional, twin.adjoint, layout.dd_columns)

    def once() -> measure.Entries:
        return measure.measure(sources, layout.pattern, colouring, steps, base,
                           np.random.default_rng(1), row_colouring=rows)

    entries, times = _timed(once, runs)
    scale = np.bincount(entries.rows, weights=np.abs(entries.dd) * layout.nominal[entries.cols],
                        minlength=len(layout.rows))[entries.rows]
    err = np.abs(entries.fd - entries.dd) * layout.nominal[entries.cols] / scale
    return {"backend": "numpy twin", "n": n, "jacobian": "coloured" if coloured else "by column",
            "derivatives": "fd+dd+adjoint", "groups": colouring.count, **dict(entries.calls),
            "seconds": statistics.median(times), "seconds_all": times,
            "max_error": float(err.max()), "localised": int(entries.localised.size)}


def _fmu_case(fmu: Fmu, n: int, coloured: bool, derivatives: bool, runs: int) -> dict[str, Any]:
    settings = J.Settings(coloured=coloured, use_derivatives=derivatives)
    before = fmu.dae.calls

    def once() -> J.Survey:
        return J.run_survey(fmu.context(points=1), settings)

    survey, times = _timed(once, runs)
    entries = survey.points[0].entries
    layout = survey.layout
    assert layout is not None
    groups = (col.colour_columns(layout.pattern).count if coloured else len(layout.cols))
    out = {"backend": "C FMU", "n": n, "jacobian": "coloured" if coloured else "by column",
           "derivatives": "fd+dd+adjoint" if derivatives else "fd only", "groups": groups,
           **dict(entries.calls), "fmi_calls": (fmu.dae.calls - before) // runs,
           "seconds": statistics.median(times), "seconds_all": times,
           "max_error": scaled_errors(survey)[0] if derivatives else None,
           "localised": int(entries.localised.size)}
    return out


def _not_run(n: int, derivatives: bool, measured: dict[str, Any] | None) -> dict[str, Any]:
    """A column-by-column row above --full-by-column-up-to: calls as the colouring gives them
    (one group per column), time estimated as O(N^2) from the largest N measured."""
    row = {"backend": "C FMU", "n": n, "jacobian": "by column",
           "derivatives": "fd+dd+adjoint" if derivatives else "fd only", "groups": n + 3,
           "evaluate": None, "directional": None, "adjoint": None, "seconds": None,
           "max_error": None, "not_run": True, "estimate_seconds": None}
    if measured is not None:
        scale = (n / measured["n"]) ** 2
        row.update(evaluate=measured["evaluate"] - 4 * measured["groups"] + 4 * (n + 3),
                   estimate_seconds=measured["seconds"] * scale)
        if derivatives:
            row.update(directional=measured["directional"] - measured["groups"] + n + 3,
                       adjoint=measured["adjoint"] - measured["groups"] + n + 3)
    return row


def bench_scaling(runs: int, fmu_sizes: Sequence[int], twin_sizes: Sequence[int],
                  full_by_column_up_to: int) -> list[dict[str, Any]]:
    rows = []
    largest: dict[bool, dict[str, Any]] = {}
    for n in fmu_sizes:
        fmu = Fmu(chain.build_chain(n))
        try:
            for derivatives in (True, False):
                for coloured in (True, False):
                    if not coloured and n > full_by_column_up_to:
                        rows.append(_not_run(n, derivatives, largest.get(derivatives)))
                        continue
                    row = _fmu_case(fmu, n, coloured, derivatives,
                                    runs if coloured or n <= 100 else max(1, runs // 3))
                    if not coloured:
                        largest[derivatives] = row
                    rows.append(row)
        finally:
            fmu.close()
    for n in twin_sizes:
        for coloured in (True, False):
            rows.append(_twin_case(n, coloured, runs))
    return rows


# ------------------------------------------------------------------------------ one call

def _call_case(fmu: Fmu, n: int, mode: str, repeats: int) -> list[dict[str, Any]]:
    """Seconds per fmi3GetDirectionalDerivative / fmi3GetAdjointDerivative call (median of
    ``repeats`` batches of 20 calls), arrays prepared beforehand."""
    from conformance.runtime.modes import start_instance

    inst = start_instance(fmu.library, mode)
    try:
        if mode == "dae":
            unknowns = [chain.vr_r(i) for i in range(n)] + [3, 5]
            knowns = [2, *(chain.vr_w(i) for i in range(n)), 4]
        else:
            unknowns, knowns = [3, 5], [2, 4]
        rng = np.random.default_rng(0)
        u_vrs = (ctypes.c_uint32 * len(unknowns))(*unknowns)
        k_vrs = (ctypes.c_uint32 * len(knowns))(*knowns)
        rows = []
        for fname, n_in, n_out in (("fmi3GetDirectionalDerivative", len(knowns), len(unknowns)),
                                   ("fmi3GetAdjointDerivative", len(unknowns), len(knowns))):
            seed = (ctypes.c_double * n_in)(*rng.normal(size=n_in))
            out = (ctypes.c_double * n_out)()

            args = (u_vrs, len(unknowns), k_vrs, len(knowns), seed, n_in, out, n_out)
            _, times = _timed(lambda fname=fname, args=args: [inst._fmi(fname, *args)
                                                             for _ in range(20)], repeats)
            seconds = statistics.median(times) / 20
            nnz = 3 * n + 3
            rows.append({"n": n, "mode": mode, "call": fname, "unknowns": len(unknowns),
                         "knowns": len(knowns), "nnz": nnz, "seconds": seconds,
                         "ns_per_nonzero": 1e9 * seconds / nnz})
        return rows
    finally:
        inst.free()


def bench_calls(runs: int, sizes: Sequence[int]) -> list[dict[str, Any]]:
    rows = []
    for n in sizes:
        fmu = Fmu(chain.build_chain(n))
        try:
            for mode in ("dae", "ode"):
                rows.extend(_call_case(fmu, n, mode, max(runs, 3)))
        finally:
            fmu.close()
    return rows


# ------------------------------------------------------------------------------ the report

def _fmt(value: Any, spec: str = ".2g") -> str:
    return "–" if value is None else format(value, spec)


def _count(value: Any, not_run: bool) -> str:
    return "–" if value is None else f"{value} (counted)" if not_run else str(value)


def _scaling_line(r: dict[str, Any]) -> str:
    not_run = bool(r.get("not_run"))
    if not not_run:
        seconds = f"{r['seconds']:.3g}"
    elif r.get("estimate_seconds") is not None:
        seconds = f"not run (≈ {r['estimate_seconds']:.0f} estimated)"
    else:
        seconds = "not run"
    return (f"| {r['backend']} | {r['n']} | {r['jacobian']} | {r['derivatives']} | "
            f"{r['groups']} | {_count(r['evaluate'], not_run)} | "
            f"{_count(r['directional'], not_run)} | {_count(r['adjoint'], not_run)} | "
            f"{seconds} | {_fmt(r['max_error'])} |")


def render_markdown(data: dict[str, Any]) -> str:
    mach = data["machine"]
    command = data.get("command", "python -m bench.probe_bench --out reports/bench")
    lines = [
        "# Probe benchmark: derivative check, calls and time against error",
        "",
        f"Run {data['date']} on {mach['cpu']} ({mach['usable_cores']} usable cores), "
        f"{mach['platform']}, Python {mach['python']}, numpy {data['numpy']}, "
        f"fmpy {mach['fmpy']}. Medians of {data['runs']} runs; calls do not vary between runs.",
        f"`{command}`.",
        "",
        "## 1. Finite-difference methods, per scene",
        "",
        "Survey at the seeded sampling points (start + 3 near, seed 0). Errors are relative to "
        "the row scale S_i = Σ_j |J_ij|·nominal_j: *measured* = largest |FD − FMU directional "
        "derivative| (the scenes' derivatives are analytic), *estimated* = largest error bound "
        "the method gave itself (truncation from a second step size + rounding for 100 ulps). "
        "*Findings*: what the rules would report (all scenes are correct).",
        "",
        "| scene | method | points | FMI calls | evaluations | directional | adjoint | "
        "time (ms) | measured error | estimated error | findings |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["methods"]:
        lines.append(
            f"| {r['scene']} | {r['method']} | {r['points']} | {r['fmi_calls']} | "
            f"{r['evaluate']} | {r['directional']} | {r['adjoint']} | "
            f"{1000 * r['seconds']:.1f} | {_fmt(r['max_error'])} | {_fmt(r['max_estimate'])} | "
            f"{r['findings']} |")
    lines += [
        "",
        "## 2. Chain: coloured against column-by-column Jacobians",
        "",
        "One point, DAE mode, the C FMU (it declares its Jacobian's pattern, so the framework's "
        "derivative calls cost O(N); see section 3). *groups*: perturbations per Jacobian "
        "(Curtis–Powell–Reid from the declared sparsity, or one per column). Evaluations "
        "include the base point and the two random verification directions; directional/"
        "adjoint include the verification and dot-product calls. Coloured needs the same calls "
        "for every N; column by column costs O(N) calls of O(N) each"
        + (": rows marked *not run* have their calls counted from the colouring and their "
           "time extrapolated as N² from the largest N measured" if any(
               r.get("not_run") for r in data["scaling"]) else "")
        + ". Most of the time per call is the checker's side (setting N algebraic variables "
        "and reading N + 2 unknowns through ctypes at every evaluation), not the FMU's.",
        "",
        "| backend | N | Jacobian | derivatives | groups | evaluations | directional | adjoint |"
        " time (s) | measured error |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [_scaling_line(r) for r in data["scaling"]]
    if data.get("calls"):
        lines += [
            "",
            "## 3. Chain: one derivative call of the C FMU",
            "",
            "Through fmpy's ctypes with the arrays prepared (no conversions in Python), median "
            "of batches of 20 calls. DAE mode: every residual, derivative and output against "
            "every state, algebraic variable and input (the whole Jacobian, 3N + 3 nonzeros, "
            "times a vector). ODE mode: der(x) and y against x and u, total derivatives through "
            "one band-LU solve with dg/dw.",
            "",
            "| N | mode | call | unknowns × knowns | time per call (µs) | ns per nonzero |",
            "|---|---|---|---|---|---|",
        ]
        for r in data["calls"]:
            lines.append(
                f"| {r['n']} | {r['mode'].upper()} | {r['call'].removeprefix('fmi3Get')} | "
                f"{r['unknowns']} × {r['knowns']} | {1e6 * r['seconds']:.1f} | "
                f"{r['ns_per_nonzero']:.1f} |")
    lines += ["", "![calls against error and size](probes.png)", ""]
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
    markers = {"forward": "v", "central": "o", "extrapolated": "*"}
    colours = dict(zip(SCENES, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    for r in data["methods"]:
        left.loglog(r["fmi_calls"], max(r["max_error"], 1e-17), markers[r["method"]],
                    color=colours.get(r["scene"]), markersize=9)
        left.loglog(r["fmi_calls"], max(r["max_estimate"], 1e-17), markers[r["method"]],
                    color=colours.get(r["scene"]), markersize=9, fillstyle="none")
    for scene, colour in colours.items():
        left.plot([], [], "s", color=colour, label=scene)
    for method, marker in markers.items():
        left.plot([], [], marker, color="grey", label=method)
    left.set_xlabel("FMI calls of the derivative survey")
    left.set_ylabel("largest FD error / row scale (filled: measured, open: estimated)")
    left.set_title("Methods: calls against error")
    left.legend(fontsize=8)
    for (backend, jac, ders), style in {("C FMU", "coloured", "fd+dd+adjoint"): "o-",
                                        ("C FMU", "by column", "fd+dd+adjoint"): "o--",
                                        ("C FMU", "coloured", "fd only"): "s-",
                                        ("C FMU", "by column", "fd only"): "s--",
                                        ("numpy twin", "coloured", "fd+dd+adjoint"): "^-",
                                        ("numpy twin", "by column", "fd+dd+adjoint"): "^--"
                                        }.items():
        rows = sorted((r for r in data["scaling"] if r["evaluate"] is not None and
                       (r["backend"], r["jacobian"], r["derivatives"]) == (backend, jac, ders)),
                      key=lambda r: r["n"])
        if not rows:
            continue
        calls = [r["evaluate"] + (r["directional"] or 0) + (r["adjoint"] or 0) for r in rows]
        line, = right.loglog([r["n"] for r in rows], calls, style,
                             label=f"{backend}, {jac}, {ders}")
        counted = [(r["n"], c) for r, c in zip(rows, calls) if r.get("not_run")]
        if counted:  # calls counted from the colouring, not run: open markers
            right.loglog(*zip(*counted), style[0], color=line.get_color(), markersize=11,
                         fillstyle="none")
    right.set_xlabel("N (algebraic variables)")
    right.set_ylabel("calls per point (evaluate + directional + adjoint)")
    right.set_title("Chain: coloured against column by column" + (
        "\n(open markers: calls counted, not run)" if any(
            r.get("not_run") for r in data["scaling"]) else ""))
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(args: argparse.Namespace, command: str = "") -> dict[str, Any]:
    scenes = SCENES if not args.quick else ("HelloWorldDAE", "Chain")
    fmu_sizes = [int(s) for s in args.chain_fmu_sizes.split(",") if s]
    twin_sizes = [int(s) for s in args.chain_twin_sizes.split(",") if s]
    return {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": machine_info(), "numpy": np.__version__, "runs": args.runs,
        "command": command or "python -m bench.probe_bench",
        "methods": bench_methods(args.runs, scenes),
        "scaling": bench_scaling(args.runs, fmu_sizes, twin_sizes, args.full_by_column_up_to),
        "calls": bench_calls(args.runs, fmu_sizes),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.probe_bench", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--chain-fmu-sizes", default="1000,10000")
    parser.add_argument("--chain-twin-sizes", default="",
                        help="N of the numpy twin rows (none by default)")
    parser.add_argument("--full-by-column-up-to", type=int, default=1000,
                        help="largest N of the C FMU run column by column (above: counted)")
    parser.add_argument("--quick", action="store_true", help="two scenes (for the tests)")
    args = parser.parse_args(argv)
    command = " ".join(["python -m bench.probe_bench",
                        *(sys.argv[1:] if argv is None else list(argv))])
    result = run(args, command)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "probes.json").write_text(json.dumps(result, indent=2) + "\n")
    (args.out / "probes.md").write_text(render_markdown(result))
    plot(result, args.out / "probes.png")
    print(render_markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
