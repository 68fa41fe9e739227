"""Plots for the HTML report, drawn with matplotlib's Agg/SVG backends and returned as data URIs.

Two pictures, both from the probes' per-FMU ``info`` (keys in
conformance/probes/instruments/api.py):

* the sparsity pattern of the DAE Jacobian, declared (ModelStructure and manifest) against
  observed (non-zero directional derivatives at the sampled points);
* each probe's measured error divided by its tolerance, on a log scale with the tolerance at 1.

Output is reproducible: the object-oriented API only (no pyplot, no global state), a fixed SVG
hash salt, and no date or software metadata. Small plots are SVG; plots with many markers are
PNG, which stays small where SVG would grow with every marker.
"""
from __future__ import annotations

import base64
import io
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

SVG_MAX_MARKERS = 3000     # above this a PNG is smaller than an SVG with one path per marker
MAX_LABELLED = 40          # rows/columns named on the axes; beyond this only indices
MAX_BARS = 40              # probe entries drawn; the worst ones first
_RC = {"svg.hashsalt": "lsdae", "svg.fonttype": "path", "font.size": 9,
       "axes.titlesize": 10, "font.family": "DejaVu Sans"}

# Colours readable by people with the common colour-vision deficiencies (Okabe-Ito), each
# category with its own marker shape too.
_BOTH, _DECLARED, _UNDECLARED = "#0072B2", "#7f7f7f", "#D55E00"
_PASS, _FAIL = "#009E73", "#D55E00"


@dataclass(frozen=True)
class Plot:
    """An embedded image: the data URI, its alt text, and a one-line caption."""

    uri: str
    alt: str
    caption: str


def _figure(width: float, height: float):
    from matplotlib.figure import Figure  # imported only when there is something to draw

    return Figure(figsize=(width, height), dpi=100, layout="constrained")


def _encode(fig, *, png: bool) -> str:
    import matplotlib  # heavy: imported only when there is something to draw

    buffer = io.BytesIO()
    with matplotlib.rc_context(_RC):
        if png:
            fig.savefig(buffer, format="png", dpi=110, metadata={"Software": None},
                        bbox_inches="tight", pad_inches=0.08)
            mime = "image/png"
        else:
            fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None},
                        bbox_inches="tight", pad_inches=0.08)
            mime = "image/svg+xml"
    return f"data:{mime};base64,{base64.b64encode(buffer.getvalue()).decode('ascii')}"


def _pairs(value: Any, rows: int, cols: int) -> set[tuple[int, int]]:
    out = set()
    for item in value or ():
        i, j = (int(v) for v in item)
        if not (0 <= i < rows and 0 <= j < cols):
            raise ValueError(f"entry ({i}, {j}) outside a {rows}x{cols} matrix")
        out.add((i, j))
    return out


def sparsity(jacobian: Mapping[str, Any]) -> Plot:
    """Declared versus observed sparsity of the DAE Jacobian (rows unknowns, columns knowns)."""
    import matplotlib  # heavy: imported only when there is something to draw

    rows = [str(r) for r in jacobian.get("rows", ())]
    cols = [str(c) for c in jacobian.get("cols", ())]
    declared = _pairs(jacobian.get("declared"), len(rows), len(cols))
    observed = _pairs(jacobian.get("observed"), len(rows), len(cols))
    both, only_declared = declared & observed, declared - observed
    undeclared = observed - declared
    cell = min(0.42, 9.0 / max(len(cols), 1), 9.0 / max(len(rows), 1))
    label_room = 1.6 if max(len(rows), len(cols)) <= MAX_LABELLED else 0.6
    with matplotlib.rc_context(_RC):
        fig = _figure(max(4.5, cell * len(cols) + label_room + 2.2),
                      max(3.0, cell * len(rows) + label_room + 0.8))
        ax = fig.add_subplot()
        size = max(2.0, (cell * 72 * 0.8) ** 2)
        for points, style in (
                (both, dict(marker="s", c=_BOTH, label=f"declared and observed ({len(both)})")),
                (only_declared, dict(marker="s", facecolors="none", edgecolors=_DECLARED,
                                     linewidths=1.4,
                                     label=f"declared, not observed ({len(only_declared)})")),
                (undeclared, dict(marker="X", c=_UNDECLARED,
                                  label=f"observed, NOT declared ({len(undeclared)})"))):
            ordered = sorted(points)
            # the faults are drawn at least legibly large, however small the cells get
            marker = max(size, 36.0) if style["marker"] == "X" else size
            ax.scatter([j for _, j in ordered], [i for i, _ in ordered], s=marker,
                       **{"linewidths": 0.8, **style})
        ax.set_xlim(-0.5, len(cols) - 0.5)
        ax.set_ylim(len(rows) - 0.5, -0.5)
        ax.set_aspect("equal" if max(len(rows), len(cols)) <= 4 * min(len(rows), len(cols))
                      else "auto")
        _ticks(ax, rows, cols)
        ax.grid(True, color="#e5e5e5", linewidth=0.5)
        ax.set_axisbelow(True)
        ax.set_xlabel(f"knowns: states, algebraic variables, inputs ({len(cols)})")
        ax.set_ylabel(f"unknowns: derivatives, residuals ({len(rows)})")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False,
                  markerscale=9.0 / math.sqrt(size), labelspacing=0.8)
        uri = _encode(fig, png=len(declared | observed) > SVG_MAX_MARKERS)
    caption = (f"{len(rows)}×{len(cols)} Jacobian: {len(declared)} entries declared, "
               f"{len(observed)} observed; {len(undeclared)} observed but not declared, "
               f"{len(only_declared)} declared but not observed.")
    which = "ODE-mode" if jacobian.get("mode") == "ode" else "DAE"
    return Plot(uri, f"Declared versus observed sparsity pattern of the {which} Jacobian. "
                + caption,
                caption)


def _ticks(ax, rows: Sequence[str], cols: Sequence[str]) -> None:
    if len(cols) <= MAX_LABELLED:
        ax.set_xticks(range(len(cols)), cols, rotation=90)
    if len(rows) <= MAX_LABELLED:
        ax.set_yticks(range(len(rows)), rows)
    ax.tick_params(axis="x", top=True, labeltop=True, bottom=False, labelbottom=False)
    ax.xaxis.set_label_position("top")


@dataclass(frozen=True)
class _Bar:
    label: str
    ratio: float     # error / tolerance; inf when the error is not finite
    error: float
    tolerance: float


def _bars(entries: Sequence[Mapping[str, Any]]) -> list[_Bar]:
    bars = []
    for e in entries:
        error, tol = float(e.get("error", math.nan)), float(e.get("tolerance", math.nan))
        if not math.isfinite(error) or not tol > 0:
            ratio = math.inf
        else:
            ratio = abs(error) / tol
        label = f"{e.get('rule', '?')} {e.get('entry', '')}".strip()
        bars.append(_Bar(label, ratio, error, tol))
    return sorted(bars, key=lambda b: (-b.ratio, b.label))


def probe_errors(entries: Sequence[Mapping[str, Any]]) -> Plot:
    """Each probe entry's error relative to its tolerance; above 1 is a failure."""
    import matplotlib  # heavy: imported only when there is something to draw

    bars = _bars(entries)
    shown = bars[:MAX_BARS]
    finite = [b.ratio for b in shown if math.isfinite(b.ratio) and b.ratio > 0]
    low = min([*finite, 1.0]) / 10
    high = max([*finite, 1.0]) * 10
    values = [high if not math.isfinite(b.ratio) else max(b.ratio, low) for b in shown]
    with matplotlib.rc_context(_RC):
        fig = _figure(8.0, 1.2 + 0.24 * len(shown))
        ax = fig.add_subplot()
        y = list(range(len(shown)))
        colours = [_FAIL if b.ratio > 1 else _PASS for b in shown]
        ax.barh(y, [v - low for v in values], left=low, color=colours, height=0.65)
        ax.set_xscale("log")
        ax.set_xlim(low, high)
        ax.set_ylim(len(shown) - 0.5, -0.5)
        ax.set_yticks(y, [b.label for b in shown])
        ax.axvline(1.0, color="#222222", linewidth=1.2, linestyle="--")
        ax.text(1.0, -0.5, " tolerance", va="bottom", ha="left", fontsize=8)
        for yi, b in zip(y, shown, strict=True):
            if not math.isfinite(b.ratio):
                ax.text(high, yi, "not finite ", va="center", ha="right", fontsize=8,
                        color="white")
            elif b.ratio == 0:
                ax.text(low, yi, " exactly 0", va="center", ha="left", fontsize=8)
        ax.set_xlabel("measured error / tolerance (log scale; left of the dashed line passes)")
        ax.grid(True, axis="x", color="#e5e5e5", linewidth=0.5)
        ax.set_axisbelow(True)
        uri = _encode(fig, png=False)
    failing = sum(1 for b in bars if b.ratio > 1)
    more = f" The {len(bars) - len(shown)} smallest are not drawn." if len(bars) > len(shown) \
        else ""
    caption = f"{len(bars)} probe measurements, {failing} above tolerance.{more}"
    return Plot(uri, "Probe error relative to tolerance, per measurement. " + caption, caption)


MAX_SERIES = 8             # trajectory panels drawn; states first, then algebraic variables


def trajectory(simulation: Mapping[str, Any]) -> Plot:
    """The simulated trajectories: one small panel per variable, DAE mode solid, ODE dashed.

    ``simulation`` is ``info["simulation"]`` (docs/simulate.md): ``times``, ``series`` by name,
    ``status``, ``t_end``, ``rtol``, ``steps``, and optionally ``ode`` with the same shape.
    """
    import matplotlib  # heavy: imported only when there is something to draw

    times = [float(t) for t in simulation.get("times", [])]
    series = dict(simulation.get("series", {}))
    ode = simulation.get("ode") if isinstance(simulation.get("ode"), dict) else None
    names = list(series)[:MAX_SERIES]
    positive = [t for t in times if t > 0]
    log_time = bool(positive) and max(positive) / min(positive) > 1e3
    cols = 2 if len(names) > 1 else 1
    rows = max(1, math.ceil(len(names) / cols))
    with matplotlib.rc_context(_RC):
        fig = _figure(8.0, 0.6 + 1.7 * rows)
        axes = fig.subplots(rows, cols, squeeze=False)
        for k, name in enumerate(names):
            ax = axes[k // cols][k % cols]
            _line(ax, times, series[name], log_time, "-", _BOTH, "DAE (IDA)")
            if ode and name in ode.get("series", {}):
                _line(ax, [float(t) for t in ode.get("times", [])], ode["series"][name],
                      log_time, "--", _UNDECLARED, "ODE (CVODE)")
            if simulation.get("status") not in (None, "ok"):
                ax.axvline(float(simulation.get("t_end", times[-1] if times else 0)),
                           color=_FAIL, linewidth=1.0, linestyle=":")
            ax.set_title(name, loc="left")
            ax.grid(True, color="#e5e5e5", linewidth=0.5)
        for k in range(len(names), rows * cols):
            axes[k // cols][k % cols].set_visible(False)
        if ode:
            axes[0][0].legend(loc="best", fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time" + (" (log scale)" if log_time else ""))
        uri = _encode(fig, png=False)
    status = simulation.get("status", "?")
    caption = (f"{simulation.get('mode', 'dae').upper()} mode, rtol {simulation.get('rtol')}, "
               f"{simulation.get('steps', '?')} steps, status {status}"
               + (f", stopped at t = {simulation.get('t_end')}" if status != "ok" else "")
               + (f"; {len(series) - len(names)} more variables not drawn"
                  if len(series) > len(names) else "") + ".")
    return Plot(uri, "Simulated trajectories. " + caption, caption)


def _line(ax, times: Sequence[float], values: Sequence[Any], log_time: bool, style: str,
          colour: str, label: str) -> None:
    pairs = [(t, float(v)) for t, v in zip(times, values)
             if v is not None and math.isfinite(float(v)) and (t > 0 or not log_time)]
    if pairs:
        ax.plot([p[0] for p in pairs], [p[1] for p in pairs], style, color=colour,
                linewidth=1.2, label=label)
    if log_time:
        ax.set_xscale("log")
