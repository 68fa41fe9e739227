"""The HTML report's plots, read from the figure drawn: markers, colours, sizes, texts, captions.

``_encode`` is replaced by a stand-in that keeps the figure, so each test reads what was drawn
(matplotlib's own objects) instead of decoding an image.
"""
from __future__ import annotations

import math

import pytest
from matplotlib.colors import to_rgba

from conformance.reporters import html_plots
from conformance.reporters.html_plots import _BOTH, _DECLARED, _FAIL, _PASS, _UNDECLARED

ROWS = ["der(x1)", "der(x2)", "r1", "r2"]
COLS = ["x1", "x2", "w1", "w2", "u"]
DECLARED = [[0, 1], [1, 0], [1, 2], [2, 0], [2, 2], [3, 1], [3, 3], [3, 4]]
OBSERVED = [[0, 1], [1, 0], [1, 2], [2, 0], [2, 2], [2, 3], [3, 1], [3, 3]]


@pytest.fixture
def figures(monkeypatch):
    """The figures the plots hand to ``_encode``, with whether a PNG was asked for."""
    drawn: list = []

    def keep(fig, *, png):
        drawn.append((fig, png))
        return "data:image/test;base64,"

    monkeypatch.setattr(html_plots, "_encode", keep)
    return drawn


def _jacobian(rows, cols, declared, observed) -> dict:
    return {"rows": rows, "cols": cols, "declared": declared, "observed": observed}


def test_sparsity_draws_three_categories_each_in_its_colour_and_says_how_many(figures):
    plot = html_plots.sparsity(_jacobian(ROWS, COLS, DECLARED, OBSERVED))
    assert plot.caption == ("4×5 Jacobian: 8 entries declared, 8 observed; 1 observed but not "
                            "declared, 1 declared but not observed.")
    assert plot.alt == ("Declared versus observed sparsity pattern of the DAE Jacobian. "
                        + plot.caption)
    (fig, png), = figures
    assert png is False
    both, declared, undeclared = fig.axes[0].collections
    assert both.get_label() == "declared and observed (7)"
    assert declared.get_label() == "declared, not observed (1)"
    assert undeclared.get_label() == "observed, NOT declared (1)"
    assert [tuple(c) for c in both.get_facecolor()] == [to_rgba(_BOTH)]
    assert len(declared.get_facecolor()) == 0          # hollow squares
    assert [tuple(c) for c in declared.get_edgecolor()] == [to_rgba(_DECLARED)]
    assert [tuple(c) for c in undeclared.get_facecolor()] == [to_rgba(_UNDECLARED)]
    assert [tuple(p) for p in undeclared.get_offsets()] == [(3.0, 2.0)]   # column w2, row r1
    assert [tuple(p) for p in declared.get_offsets()] == [(4.0, 3.0)]     # column u, row r2
    ax = fig.axes[0]
    assert ax.get_xlim() == (-0.5, 4.5) and ax.get_ylim() == (3.5, -0.5)   # one cell per entry
    assert [t.get_text() for t in ax.get_xticklabels()] == COLS
    assert {t.get_rotation() for t in ax.get_xticklabels()} == {90.0}
    assert [t.get_text() for t in ax.get_yticklabels()] == ROWS


@pytest.mark.filterwarnings("ignore:Attempting to set identical low and high xlims")
def test_sparsity_without_columns_draws_an_empty_matrix(figures):
    plot = html_plots.sparsity({"rows": ["r"], "declared": [], "observed": []})
    assert plot.caption.startswith("1×0 Jacobian: 0 entries declared, 0 observed;")


def test_sparsity_mode_names_the_jacobian(figures):
    plot = html_plots.sparsity({**_jacobian(ROWS, COLS, DECLARED, OBSERVED), "mode": "ode"})
    assert plot.alt.startswith("Declared versus observed sparsity pattern of the ODE-mode "
                               "Jacobian. ")


@pytest.mark.parametrize("n, labelled", [(40, True), (41, False)])
def test_axes_are_labelled_up_to_forty_rows_and_columns(n, labelled, figures):
    names = [f"v{i}" for i in range(n)]
    html_plots.sparsity(_jacobian(names, names, [[0, 0]], [[0, 0]]))
    (fig, _), = figures
    ax = fig.axes[0]
    cell = min(0.42, 9.0 / n)
    room = 1.6 if labelled else 0.6
    assert tuple(fig.get_size_inches()) == pytest.approx(
        (max(4.5, cell * n + room + 2.2), max(3.0, cell * n + room + 0.8)))
    shown = [t.get_text() for t in ax.get_xticklabels()]
    assert (shown == names) is labelled
    assert ([t.get_text() for t in ax.get_yticklabels()] == names) is labelled


def test_an_undeclared_entry_stays_legible_in_a_large_matrix(figures):
    n = 100
    names = [f"v{i}" for i in range(n)]
    html_plots.sparsity(_jacobian(names, names, [[0, 0]], [[0, 0], [5, 7]]))
    (fig, _), = figures
    both, _, undeclared = fig.axes[0].collections
    size = (min(0.42, 9.0 / n) * 72 * 0.8) ** 2
    assert size < 36.0
    assert list(both.get_sizes()) == pytest.approx([max(2.0, size)])
    assert list(undeclared.get_sizes()) == [36.0]


ENTRIES = [
    {"rule": "DAE701", "entry": "r1 at start", "error": 3e-13, "tolerance": 1e-8},
    {"rule": "DAE702", "entry": "d(r1)/d(w2)", "error": -0.5, "tolerance": 1e-6},
    {"rule": "DAE703", "entry": "der(x1)", "error": 0.0, "tolerance": 1e-8},
    {"rule": "DAE703", "entry": "der(x2)", "error": float("nan"), "tolerance": 1e-8},
    {"entry": "no rule", "error": 1e-9, "tolerance": 0.0},
]


def test_bars_are_labelled_by_rule_and_entry_worst_first():
    bars = html_plots._bars(ENTRIES)
    assert [(b.label, b.error if math.isfinite(b.error) else "nan", b.tolerance)
            for b in bars] == [
        ("? no rule", 1e-9, 0.0),
        ("DAE703 der(x2)", "nan", 1e-8),
        ("DAE702 d(r1)/d(w2)", -0.5, 1e-6),
        ("DAE701 r1 at start", 3e-13, 1e-8),
        ("DAE703 der(x1)", 0.0, 1e-8),
    ]
    assert [b.ratio for b in bars] == pytest.approx([math.inf, math.inf, 5e5, 3e-5, 0.0])
    assert html_plots._bars([{"rule": "DAE701", "error": 1.0, "tolerance": 1.0}])[0].label \
        == "DAE701"


def test_probe_errors_colour_failures_and_mark_zero_and_non_finite(figures):
    plot = html_plots.probe_errors(ENTRIES)
    assert plot.caption == "5 probe measurements, 3 above tolerance."
    (fig, png), = figures
    assert png is False
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == [
        "? no rule", "DAE703 der(x2)", "DAE702 d(r1)/d(w2)", "DAE701 r1 at start",
        "DAE703 der(x1)"]
    assert [tuple(p.get_facecolor()) for p in ax.patches] == [
        to_rgba(c) for c in (_FAIL, _FAIL, _FAIL, _PASS, _PASS)]
    low, high = 3e-5 / 10, 5e5 * 10
    assert ax.get_xlim() == pytest.approx((low, high))
    texts = [(t.get_text(), tuple(t.get_position()), t.get_fontsize()) for t in ax.texts]
    assert texts[0] == (" tolerance", (1.0, -0.5), 8.0)
    assert texts[1:] == [("not finite ", (pytest.approx(high), 0), 8.0),
                         ("not finite ", (pytest.approx(high), 1), 8.0),
                         (" exactly 0", (pytest.approx(low), 4), 8.0)]
    assert ax.xaxis.get_gridlines()[0].get_color() == "#e5e5e5"
    assert ax.xaxis.get_gridlines()[0].get_visible()


def test_probe_errors_beyond_forty_say_how_many_are_not_drawn(figures):
    entries = [{"rule": "DAE701", "entry": f"e{i}", "error": float(i), "tolerance": 10.0}
               for i in range(45)]
    plot = html_plots.probe_errors(entries)
    assert plot.caption == ("45 probe measurements, 34 above tolerance. The 5 smallest are not "
                            "drawn.")
    assert len(figures[0][0].axes[0].patches) == 40


def _simulation(**kw) -> dict:
    return {"mode": "dae", "status": "ok", "rtol": 1e-6, "steps": 40,
            "times": [0.0, 0.5, 1.0], "series": {"y1": [2.0, 1.7, 1.0]}, **kw}


@pytest.mark.filterwarnings("error")   # matplotlib warns of a grid turned off with properties
def test_trajectory_draws_every_point_on_a_linear_time_axis(figures):
    plot = html_plots.trajectory(_simulation())
    assert plot.caption == "DAE mode, rtol 1e-06, 40 steps, status ok."
    (fig, _), = figures
    ax = fig.axes[0]
    assert ax.get_title(loc="left") == "y1"
    assert ax.get_xscale() == "linear" and ax.get_xlabel() == "time"
    line, = ax.lines
    assert list(line.get_xdata()) == [0.0, 0.5, 1.0]
    assert line.get_label() == "DAE (IDA)"
    assert ax.xaxis.get_gridlines()[0].get_visible()


def test_trajectory_over_decades_is_on_a_log_time_axis_without_time_zero(figures):
    sim = _simulation(times=[0.0, 1e-4, 1.0, 10.0], series={"y1": [1.0, 2.0, 3.0, 4.0]},
                      ode={"times": [0.0, 1e-4, 10.0], "series": {"y1": [1.0, 2.0, 4.0]}})
    html_plots.trajectory(sim)
    (fig, _), = figures
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "time (log scale)"
    dae, ode = ax.lines
    assert list(dae.get_xdata()) == [1e-4, 1.0, 10.0]
    assert list(ode.get_xdata()) == [1e-4, 10.0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["DAE (IDA)", "ODE (CVODE)"]


def test_a_stopped_trajectory_says_where_it_stopped_and_what_is_not_drawn(figures):
    sim = _simulation(status="failed", t_end=0.8,
                      series={f"y{i}": [1.0, 2.0, 3.0] for i in range(10)})
    plot = html_plots.trajectory(sim)
    assert plot.caption == ("DAE mode, rtol 1e-06, 40 steps, status failed, stopped at t = 0.8; "
                            "2 more variables not drawn.")
    (fig, _), = figures
    assert [ax.get_title(loc="left") for ax in fig.axes] == [f"y{i}" for i in range(8)]
    stops = [line for line in fig.axes[0].lines if list(line.get_xdata()) == [0.8, 0.8]]
    assert len(stops) == 1


def test_a_stopped_trajectory_without_an_end_time_is_marked_at_its_last_time(figures):
    html_plots.trajectory(_simulation(status="failed"))
    (fig, _), = figures
    stops = [line for line in fig.axes[0].lines if list(line.get_xdata()) == [1.0, 1.0]]
    assert len(stops) == 1   # at the last time, since the simulation gave no t_end


def _encoded(png: bool, **rc) -> bytes:
    import base64

    import matplotlib

    fig = html_plots._figure(2.0, 1.0)
    fig.add_subplot().plot([0, 1], [0, 1])
    with matplotlib.rc_context(rc):
        uri = html_plots._encode(fig, png=png)
    mime, _, payload = uri.partition(";base64,")
    assert mime == ("data:image/png" if png else "data:image/svg+xml")
    return base64.b64decode(payload)


def test_a_png_is_a_png_with_a_narrow_margin_and_no_software_stamp():
    data = _encoded(True, **{"savefig.format": "svg"})   # whatever the user's matplotlibrc
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    # the 2 x 1 inch figure at 110 dpi, cut to its content, plus 0.08 inch on each side
    assert width <= (2.0 + 2 * 0.08) * 110 + 1 and height <= (1.0 + 2 * 0.08) * 110 + 1
    assert b"Software" not in data and b"atplotlib" not in data


def test_an_svg_has_no_date_or_creator():
    data = _encoded(False)
    assert data.lstrip().startswith(b"<?xml")
    assert b"<dc:date>" not in data and b"<dc:creator>" not in data
