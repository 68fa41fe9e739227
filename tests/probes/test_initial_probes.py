"""The InitialUnknown probes (DAE750-DAE752) against fake instances in Initialization Mode.

The twin: a parameter p, a state x, an input u and time as the knowns; the algebraic variable w
solved from 0 = w - p*x - sin(u) at initialisation; der(x) = 0.1*t - w, y = 3*x + 2*u. Exact
derivatives by complex step. Each defect must trigger exactly its rule, the clean twin none,
for many seeds; the real FMUs are covered by tests/probes/test_defects.py and
tests/probes/test_clean_scenes.py.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pytest
from lxml import etree

from conformance.report.catalogue import default_catalogue
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description
from conformance.probes.initialization import unknowns as I
from conformance.probes.instruments.api import FmiError, ProbeContext, ProbeSkipped
from conformance.probes.initialization.layout import build_initial_layout
from conformance.probes.initialization.survey import FACT, initial_survey
from conformance.runtime.layout import Layout

OPTIONS = {r.code: r.option_values for r in default_catalogue()}  # the one place of defaults
H = 1e-30  # complex step: exact first derivatives (Squire & Trapp 1998)

MD = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="InitTwin" instantiationToken="{twin}">
  <ModelExchange modelIdentifier="InitTwin" providesDirectionalDerivatives="true"/>
  <DefaultExperiment startTime="0.5" stopTime="2"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Float64 name="p" valueReference="1" causality="parameter" variability="fixed" start="2" min="0.5" max="4"/>
    <Float64 name="x" valueReference="2" causality="local" variability="continuous" initial="exact" start="0.5"/>
    <Float64 name="der(x)" valueReference="3" causality="local" variability="continuous" initial="calculated" derivative="2"/>
    <Float64 name="w" valueReference="4" causality="local" variability="continuous" initial="approx" start="0"/>
    <Float64 name="g" valueReference="5" causality="local" variability="continuous"/>
    <Float64 name="u" valueReference="6" causality="input" variability="continuous" start="0.3"/>
    <Float64 name="y" valueReference="7" causality="output" variability="continuous" initial="calculated"/>
    <Boolean name="dae" valueReference="8" causality="structuralParameter" variability="fixed" start="false"/>
    <Float64 name="k" valueReference="9" causality="local" variability="constant" start="7"/>
  </ModelVariables>
  <ModelStructure>
    <Output valueReference="7" dependencies="2 6"/>
    <ContinuousStateDerivative valueReference="3" dependencies="0 1 2 6"/>
    <InitialUnknown valueReference="3" dependencies="0 1 2 6"/>
    <InitialUnknown valueReference="7" dependencies="2 6" dependenciesKind="constant constant"/>
  </ModelStructure>
</fmiModelDescription>
"""

INITIAL_UNKNOWNS = """
    <InitialUnknown valueReference="3" dependencies="0 1 2 6"/>
    <InitialUnknown valueReference="4" dependencies="1 2 6" dependenciesKind="dependent dependent dependent"/>
    <InitialUnknown valueReference="7" dependencies="2 6" dependenciesKind="constant constant"/>"""

MANIFEST = """<?xml version="1.0" encoding="UTF-8"?>
<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="twin">
  <EnableDAEParameter valueReference="8"/>
  <AlgebraicVariables><AlgebraicVariable valueReference="4"/></AlgebraicVariables>
  <ModelStructure>
    <Output valueReference="7" dependencies="2 6"/>
    <ContinuousStateDerivative valueReference="3" dependencies="0 4"/>{initial}
    <Residual valueReference="5" dependencies="1 2 4 6"/>
  </ModelStructure>
</fmiDAEManifest>
"""


@dataclass
class Twin:
    """What the fake FMU does; each hook breaks one thing."""

    extra: Callable | None = None           # (knowns) -> additions to the unknowns
    dd_hook: Callable | None = None         # (jac, unknowns, knowns) -> jac
    refuse: Sequence[str] = ()               # "set", "init-dae", "directional"
    opened: list = field(default_factory=list)   # (mode, values, t) of every instance

    def values(self, k: Mapping[int, complex], t: complex) -> dict[int, complex]:
        p, x, u = k.get(1, 2.0), k.get(2, 0.5), k.get(6, 0.3)
        w = p * x + np.sin(u)
        out = {3: 0.1 * t - w, 4: w, 7: 3 * x + 2 * u, 1: p, 2: x, 6: u, 0: t}
        if self.extra:
            for vr, v in self.extra(k, t).items():
                out[vr] = out[vr] + v
        return out


class FakeInit:
    """A fake instance in Initialization Mode (the protocol of runtime.modes'
    start_initialization: get_float64, directional_as_set, free)."""

    def __init__(self, twin: Twin, mode: str, values: Mapping[int, float], t: float):
        if "set" in twin.refuse and values:
            raise FmiError("fmi3SetFloat64", "fmi3Error", ["variable 1 cannot be set"])
        if "init-dae" in twin.refuse and mode == "dae":
            raise FmiError("fmi3EnterInitializationMode", "fmi3Error", ["no DAE init"])
        twin.opened.append((mode, dict(values), t))
        self.twin, self.k, self.t = twin, dict(values), t
        self.freed = False

    def get_float64(self, vrs: Sequence[int]) -> np.ndarray:
        out = self.twin.values(self.k, self.t)
        return np.array([out[vr].real if isinstance(out[vr], complex) else out[vr]
                         for vr in vrs], dtype=float)

    def directional_as_set(self, unknowns, knowns, seed) -> np.ndarray:
        if "directional" in self.twin.refuse:
            raise FmiError("fmi3GetDirectionalDerivative", "fmi3Error", ["refused"])
        jac = np.zeros((len(unknowns), len(knowns)))
        for j, vr in enumerate(knowns):
            k = {key: complex(v) for key, v in self.k.items()}
            t = complex(self.t)
            if vr == 0:
                t += 1j * H
            else:
                k[vr] = k[vr] + 1j * H
            out = self.twin.values(k, t)
            jac[:, j] = [complex(out[q]).imag / H for q in unknowns]
        if self.twin.dd_hook:
            jac = self.twin.dd_hook(jac, list(unknowns), list(knowns))
        return jac @ np.asarray(seed)

    def free(self) -> None:
        self.freed = True


def _xml(text: str, edits: Sequence[tuple[str, str]]) -> etree._ElementTree:
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return etree.ElementTree(etree.fromstring(text.encode()))


def make_ctx(*, seed: int = 0, twin: Twin | None = None, md_edits=(), manifest_edits=(),
             initial: str = INITIAL_UNKNOWNS, provides: bool = True) -> ProbeContext:
    twin = twin or Twin()
    md_text = MD if provides else MD.replace('providesDirectionalDerivatives="true"', "")
    model = read_model_description(_xml(md_text, md_edits))
    manifest = read_manifest(_xml(MANIFEST.replace("{initial}", initial), manifest_edits),
                             draft="alpha1")
    ctx = ProbeContext(model=model, manifest=manifest, draft="alpha1", seed=seed,
                       rng=np.random.default_rng(seed), points=[], dae=None, ode=None,
                       new_instance=lambda mode: None,
                       new_initialization=lambda mode, values, t: FakeInit(twin, mode, values, t))
    ctx.facts["layout"] = Layout.build(model, manifest)
    ctx.facts["twin"] = twin
    return ctx


def found(ctx: ProbeContext, skipped: dict[str, str] | None = None) -> dict[str, list]:
    out = {}
    for code, probe in I.PROBES.items():
        try:
            violations = list(probe(ctx, **OPTIONS[code]))
        except ProbeSkipped as exc:
            if skipped is not None:
                skipped[code] = str(exc)
            continue
        if violations:
            out[code] = violations
    return out


def _drop(vr: int, old: str, new: str) -> list[tuple[str, str]]:
    return [(f'<InitialUnknown valueReference="{vr}" {old}/>',
             f'<InitialUnknown valueReference="{vr}" {new}/>')]


# ------------------------------------------------------------------------------------ clean

@pytest.mark.parametrize("seed", range(20))
def test_clean_twin_triggers_nothing(seed):
    skipped: dict[str, str] = {}
    assert found(make_ctx(seed=seed), skipped) == {}
    assert skipped == {}


def test_layout_knows_the_knowns_of_initialization_mode():
    ctx = make_ctx()
    layout, start, reason = build_initial_layout(ctx, ctx.facts["layout"], "dae")
    assert (layout.mode, reason) == ("dae", "")
    assert [(c.name, c.role) for c in layout.cols] == [
        ("p", "parameter"), ("x", "state"), ("u", "input"), ("time", "time")]
    assert start == {1: 2.0, 2: 0.5, 6: 0.3}     # no w (approx), no constant k, no enable
    assert [r.name for r in layout.rows] == ["der(x)", "w", "y"]
    assert layout.cols[-1].lower == 0.5          # never before the DefaultExperiment start
    assert layout.dd_columns.tolist() == [True, True, True, True]   # der(x) lists time


def test_a_clocked_variable_is_no_known_set_as_a_start_value():
    # FMI 3.0.2 §2.2.7.2: a clocked variable is set only in Event Mode while its clock ticks,
    # or in Initialization Mode; the start values are set in Instantiated
    clocked = ('<Clock name="tick" valueReference="10" causality="input" '
               'intervalVariability="triggered"/>\n'
               '    <Float64 name="cu" valueReference="11" causality="input" '
               'variability="discrete" start="1" clocks="10"/>\n'
               '    <Float64 name="cx" valueReference="12" causality="local" '
               'variability="discrete" initial="exact" start="2" clocks="10"/>\n'
               '  </ModelVariables>')
    ctx = make_ctx(md_edits=[("</ModelVariables>", clocked)])
    layout, start, _ = build_initial_layout(ctx, ctx.facts["layout"], "dae")
    assert [c.name for c in layout.cols] == ["p", "x", "u", "time"]
    assert start == {1: 2.0, 2: 0.5, 6: 0.3}


def test_the_survey_is_shared_seeded_and_within_bounds():
    ctx = make_ctx(seed=3)
    first = initial_survey(ctx)
    assert initial_survey(ctx) is first and ctx.facts[FACT] is first
    twin: Twin = ctx.facts["twin"]  # type: ignore[assignment]
    assert len(first.points) == OPTIONS["DAE750"]["points"]
    assert first.instances == len(twin.opened) <= OPTIONS["DAE750"]["max_instances"]
    for mode, values, t in twin.opened:
        assert mode == "dae" and t >= 0.5
        assert 0.5 <= values[1] <= 4.0
    again = make_ctx(seed=3)
    initial_survey(again)
    assert again.facts["twin"].opened == twin.opened  # type: ignore[attr-defined]


# ---------------------------------------------------------------------------------- defects

def test_missing_parameter_dependency_is_undeclared_at_its_element():
    ctx = make_ctx(manifest_edits=_drop(
        4, 'dependencies="1 2 6" dependenciesKind="dependent dependent dependent"',
        'dependencies="2 6" dependenciesKind="dependent dependent"'))
    result = found(ctx)
    assert set(result) == {"DAE750"}
    (v,) = result["DAE750"]
    assert v.subject == "d(w)/d(p)"
    ev = dict(v.evidence)
    assert (ev["element"], ev["known_role"], ev["mode"]) == ("InitialUnknown", "parameter",
                                                            "DAE mode")
    assert v.location.file == ctx.manifest.file
    assert v.location.line == next(u.line for u in ctx.manifest.unknowns("InitialUnknown")
                                   if u.vr == 4)
    x = dict(ev["point"])["values"]
    assert ev["finite_difference"] == pytest.approx(dict(x)["x"], rel=1e-6)   # dw/dp = x


def test_missing_start_time_dependency_is_undeclared():
    result = found(make_ctx(manifest_edits=_drop(3, 'dependencies="0 1 2 6"',
                                                 'dependencies="1 2 6"')))
    assert set(result) == {"DAE750"}
    assert [v.subject for v in result["DAE750"]] == ["d(der(x))/d(time)"]


def test_hidden_dependency_behind_a_declared_column_is_found():
    # y also depends on p; p shares a colour group with the columns y declares. The twin does
    # it in both modes, and both lists leave p out: one finding per mode, at its own element.
    twin = Twin(extra=lambda k, t: {7: 0.2 * k.get(1, 2.0) ** 2})
    ctx = make_ctx(twin=twin, manifest_edits=_drop(
        7, 'dependencies="2 6" dependenciesKind="constant constant"',
        'dependencies="2 6" dependenciesKind="dependent dependent"'), md_edits=_drop(
        7, 'dependencies="2 6" dependenciesKind="constant constant"',
        'dependencies="2 6" dependenciesKind="dependent dependent"'))
    result = found(ctx)
    assert set(result) == {"DAE750"}
    assert [(v.subject, dict(v.evidence)["mode"], v.location.file) for v in result["DAE750"]] \
        == [("d(y)/d(p)", "DAE mode", ctx.manifest.file),
            ("d(y)/d(p)", "ODE mode", ctx.model.file)]
    assert [v.part for v in result["DAE750"]] == ["dae-mode", None]   # the manifest's list


@pytest.mark.parametrize("where", ["manifest", "model", "both"])
def test_a_row_without_dependencies_claims_nothing(where):
    # the mode whose row still claims "2 6" reports p; the one without dependencies does not
    twin = Twin(extra=lambda k, t: {7: 0.2 * k.get(1, 2.0) ** 2})
    drop = _drop(7, 'dependencies="2 6" dependenciesKind="constant constant"', "")
    ctx = make_ctx(twin=twin, manifest_edits=drop if where != "model" else (),
                   md_edits=drop if where != "manifest" else ())
    modes = {dict(v.evidence)["mode"] for v in found(ctx).get("DAE750", [])}
    assert modes == {"manifest": {"ODE mode"}, "model": {"DAE mode"}, "both": set()}[where]


def test_a_known_that_cannot_move_is_never_blamed():
    # p pinned by min = max: the perturbation cannot excite it, so nothing is reported
    twin = Twin(extra=lambda k, t: {7: 0.2 * k.get(1, 2.0) ** 2})
    ctx = make_ctx(twin=twin, md_edits=[('min="0.5" max="4"', 'min="2" max="2"')],
                   manifest_edits=_drop(7, 'dependencies="2 6" dependenciesKind="constant '
                                        'constant"', 'dependencies="2 6"'))
    assert found(ctx) == {}
    assert all(values[1] == 2.0 for _, values, _ in ctx.facts["twin"].opened)  # type: ignore[attr-defined]


def test_constant_kind_that_depends_on_a_parameter_is_violated():
    # dw/dx = p: linear in x, but the factor changes with the parameter
    result = found(make_ctx(manifest_edits=_drop(
        4, 'dependencies="1 2 6" dependenciesKind="dependent dependent dependent"',
        'dependencies="1 2 6" dependenciesKind="dependent constant dependent"')))
    assert set(result) == {"DAE751"}
    (v,) = result["DAE751"]
    assert v.subject == "d(w)/d(x)"
    ev = dict(v.evidence)
    assert ev["largest"] - ev["smallest"] > ev["tolerance"]


def test_kinds_of_the_wrong_length_claim_nothing():
    ctx = make_ctx(manifest_edits=_drop(
        4, 'dependencies="1 2 6" dependenciesKind="dependent dependent dependent"',
        'dependencies="1 2 6" dependenciesKind="constant constant"'))
    assert found(ctx) == {}


def _wrong(row_vr: int, col_vr: int, factor: float):
    def hook(jac, unknowns, knowns):
        jac = jac.copy()
        if row_vr in unknowns and col_vr in knowns:
            jac[unknowns.index(row_vr), knowns.index(col_vr)] *= factor
        return jac
    return hook


def test_wrong_directional_derivative_in_initialization_mode():
    result = found(make_ctx(twin=Twin(dd_hook=_wrong(4, 2, -1.0))))
    assert set(result) == {"DAE752"}
    assert [v.subject for v in result["DAE752"]] == ["d(w)/d(x)"]


def test_refused_directional_derivative_is_a_reason_to_skip_that_rule_only():
    # a singular initial problem has no derivative: the FMU may refuse it
    skipped: dict[str, str] = {}
    ctx = make_ctx(twin=Twin(refuse=("directional",)), manifest_edits=_drop(
        4, 'dependencies="1 2 6" dependenciesKind="dependent dependent dependent"',
        'dependencies="2 6" dependenciesKind="dependent dependent"'))
    result = found(ctx, skipped)
    assert set(result) == {"DAE750"}                 # the finite differences still count
    assert set(skipped) == {"DAE752"} and "fmi3GetDirectionalDerivative" in skipped["DAE752"]


def test_fatal_stops_the_survey_at_once():
    class Fatal(Twin):
        def values(self, k, t):
            if len(self.opened) > 3:
                raise FmiError("fmi3GetFloat64", "fmi3Fatal", ["corrupted"])
            return super().values(k, t)
    twin = Fatal()
    skipped: dict[str, str] = {}
    assert found(make_ctx(twin=twin), skipped) == {}
    assert len(twin.opened) == 4           # no instance after the fatal call, in either mode
    assert set(skipped) == set(I.PROBES) and all("SM-04" in r for r in skipped.values())


def test_no_directional_derivatives_skips_only_that_rule():
    skipped: dict[str, str] = {}
    assert found(make_ctx(provides=False), skipped) == {}
    assert set(skipped) == {"DAE752"}


# ------------------------------------------------------------------------ what cannot run

def test_a_refusal_is_a_reason_to_skip_never_a_finding():
    skipped: dict[str, str] = {}
    assert found(make_ctx(twin=Twin(refuse=("set",))), skipped) == {}
    assert set(skipped) == set(I.PROBES)
    assert all("rejects the start values" in reason for reason in skipped.values()), skipped


def test_a_refused_dae_initialization_leaves_ode_mode_verified():
    # DAE-14: alpha.1 lets the FMU refuse DAE mode in Initialization Mode; ODE mode's list is
    # still verified, and nothing is reported
    skipped: dict[str, str] = {}
    twin = Twin(refuse=("init-dae",))
    assert found(make_ctx(twin=twin), skipped) == {}
    assert skipped == {} and {mode for mode, _, _ in twin.opened} == {"ode"}


@pytest.mark.parametrize("budget, words", [
    ({"max_instances": 5}, "max_instances = 5"),
    ({"max_instances": 30}, "max_instances = 30"),    # one point fits, not two
    ({"max_seconds": 0.0}, "max_seconds = 0"),
])
def test_a_small_budget_is_a_reason_to_skip(budget, words):
    ctx = make_ctx()
    options = dict(OPTIONS["DAE750"], **budget)
    try:
        assert list(I.PROBES["DAE750"](ctx, **options)) == []
    except ProbeSkipped as exc:
        assert words in str(exc)
    assert len(ctx.facts["twin"].opened) <= options["max_instances"]  # type: ignore[attr-defined]
    skipped: dict[str, str] = {}
    found(ctx, skipped)
    assert "DAE751" in skipped and words in skipped["DAE751"]


def test_without_manifest_list_the_model_description_is_verified_in_ode_mode():
    ctx = make_ctx(initial="", md_edits=[(
        '<InitialUnknown valueReference="3" dependencies="0 1 2 6"/>',
        '<InitialUnknown valueReference="3" dependencies="0 2 6"/>')])
    result = found(ctx)
    assert set(result) == {"DAE750"}
    (v,) = result["DAE750"]
    assert v.subject == "d(der(x))/d(p)"
    assert v.location.file == ctx.model.file
    assert dict(v.evidence)["mode"] == "ODE mode"
    assert {mode for mode, _, _ in ctx.facts["twin"].opened} == {"ode"}  # type: ignore[attr-defined]


def test_without_manifest_list_and_without_ode_mode_nothing_is_claimed():
    ctx = make_ctx(initial="", manifest_edits=[('<EnableDAEParameter valueReference="8"/>', "")])
    skipped: dict[str, str] = {}
    assert found(ctx, skipped) == {}
    assert set(skipped) == set(I.PROBES)
    assert all("Q-02" in reason for reason in skipped.values())


def test_not_finite_start_value_is_not_sampled():
    ctx = make_ctx(md_edits=[('start="0.3"/>', 'start="nan"/>')])
    layout, start, _ = build_initial_layout(ctx, ctx.facts["layout"], "dae")
    assert "u" not in [c.name for c in layout.cols] and 6 not in start
    survey = initial_survey(ctx)
    assert survey.points and all(math.isfinite(v) for ps in survey.points for v in ps.x)
    assert all(6 not in values for _, values, _ in ctx.facts["twin"].opened)  # type: ignore[attr-defined]


# ------------------------------------------------------------------- solver error, confirmed

def _solver_error(amplitude: float, spacing: float):
    """An error of the FMU's inner solve in w: pseudo-random values at nodes ``spacing`` apart
    in x, linear in between. Over a survey step (much less than ``spacing``) it is smooth, so
    the two step sizes of the error estimate can agree on a wrong derivative; over a step many
    nodes wide it averages out, as the error of an ill-conditioned solve does."""
    def node(k: int) -> float:
        return amplitude * (2.0 * ((math.sin(k * 12.9898) * 43758.5453) % 1.0) - 1.0)

    def extra(k, t):
        x = complex(k.get(2, 0.5)).real / spacing
        base = math.floor(x)
        return {4: node(base) + (x - base) * (node(base + 1) - node(base))}
    return extra


SOLVER_ERROR = _solver_error(3e-6, 1.2e-4)   # slopes ~0.05 against dw/dx ~ 2


def _in_y(k, t):
    return {7: SOLVER_ERROR(k, t)[4]}   # y is declared constant in x and u


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("extra", [SOLVER_ERROR, _in_y], ids=["w", "y"])
def test_solver_error_correlated_over_a_step_is_not_blamed(seed, extra):
    skipped: dict[str, str] = {}
    assert found(make_ctx(seed=seed, twin=Twin(extra=extra)), skipped) == {}
    assert skipped == {}


@pytest.mark.parametrize("code, extra, subject", [
    ("DAE752", SOLVER_ERROR, "d(w)/d(x)"),
    ("DAE751", _in_y, "d(y)/d(x)"),
])
def test_without_the_larger_step_that_solver_error_would_be_blamed(code, extra, subject):
    # the same twins, confirmed at the survey's own step: the larger step is what saves them
    blamed = 0
    for seed in range(10):
        ctx = make_ctx(seed=seed, twin=Twin(extra=extra))
        options = dict(OPTIONS[code], confirm_factor=1.0)
        blamed += any(v.subject == subject for v in I.PROBES[code](ctx, **options))
    assert blamed >= 5
