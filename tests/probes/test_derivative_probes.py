"""The derivative probes against a fake Evaluator: analytic twins of the scenes, exact
derivatives by complex step, and defects injected one at a time.

Each defect must trigger exactly its rule, the clean twins none, for many seeds; the real FMUs
are covered by tests/probes/test_defects.py and tests/probes/test_clean_scenes.py.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
import pytest
from lxml import etree
from scipy.optimize import fsolve

from conformance.report.catalogue import default_catalogue
from conformance.model.manifest import read_manifest
from conformance.model.description import read_model_description
from conformance.probes.derivatives import partials as D
from conformance.probes.derivatives import dgdw
from conformance.probes.instruments.api import FmiError, Point, ProbeContext, ProbeSkipped
from tests.fixtures import SCENES_DIR

FAMILY = {**D.PROBES, **dgdw.PROBES}  # the derivative probes and the dg/dw probes
OPTIONS = {r.code: r.option_values for r in default_catalogue()}  # the one place of defaults

SCENES = SCENES_DIR
H = 1e-30  # complex step: exact first derivatives (Squire & Trapp 1998)


@dataclass
class Twin:
    """A scene's equations in numpy (complex-safe), by value reference."""

    t: int
    x: list[int]
    der: list[int]
    w: list[int]
    res: list[int]
    u: list[int]
    y: list[int]
    start: dict[int, float]
    f: Callable
    g: Callable
    h: Callable
    ode_offset: float = 0.0     # defect: ODE mode solves g = offset


def _simple() -> Twin:
    def f(t, x, w, u):
        (x1, x2), (z1, z2), (u1, u2) = x, w, u
        return [np.sin(x1) + np.sin(z1 * z2 * u1), np.sin(x1 * x2) + np.sin(z1 * z2 * u2) + u1**2]

    def g(t, x, w, u):
        (x1, x2), (z1, z2), (u1, u2) = x, w, u
        return [z1 * u1**2 + np.tanh(3 * z1) + u2 * x1**3,
                np.exp(z1 * z2 * u1) / 3 - np.sin(z2 * x2)]

    def h(t, x, w, u):
        (x1, x2), (z1, z2), (u1, u2) = x, w, u
        return [u1 * x1 * z1 + np.sin(u2), u2 * x2 * z2 + np.sin(u1 * u2)]

    return Twin(0, [1, 3], [2, 4], [5, 6], [11, 12], [7, 8], [9, 10],
                {1: 0.5, 3: 0.5, 5: 0.0, 6: 0.0, 7: 0.0, 8: 0.0}, f, g, h)


def _robertson() -> Twin:
    def f(t, x, w, u):
        return [-0.04 * x[0] + 1e4 * x[1] * w[0], 0.04 * x[0] - 1e4 * x[1] * w[0] - 3e7 * x[1]**2]

    return Twin(0, [2, 4], [3, 5], [6], [7], [], [], {2: 1.0, 4: 0.0, 6: 1.0}, f,
                lambda t, x, w, u: [x[0] + x[1] + w[0] - 1], lambda t, x, w, u: [])


def _hello() -> Twin:
    return Twin(0, [2], [3], [4, 5], [6, 7], [], [], {2: 1.0, 4: 1.4, 5: -0.2},
                lambda t, x, w, u: [w[0]],
                lambda t, x, w, u: [w[0] + 2 * w[1] - x[0], w[0] - 3 * w[1] - 2 * x[0]],
                lambda t, x, w, u: [])


TWINS = {"SimpleDAE": _simple, "Robertson": _robertson, "HelloWorldDAE": _hello}


@dataclass
class Fake:
    """An Evaluator over a twin; ``dd_hook`` distorts the partial derivatives behind both
    derivative functions, ``directional_hook``/``adj_hook`` those of one of them."""

    twin: Twin
    mode: str = "dae"
    calls: int = 0
    dd_hook: Callable | None = None
    adj_hook: Callable | None = None
    directional_hook: Callable | None = None
    refuse: Sequence[str] = ()

    def _state(self, point: Point, bump: tuple[int, complex] | None = None):
        tw = self.twin
        v: dict[int, complex] = {**tw.start, **point.values}
        t = complex(point.t)
        if bump is not None:
            vr, dz = bump
            if vr == tw.t:
                t += dz
            else:
                v[vr] = v[vr] + dz
        pick = lambda vrs: np.array([v[k] for k in vrs], dtype=complex)  # noqa: E731
        x, w, u = pick(tw.x), pick(tw.w), pick(tw.u)
        if self.mode == "ode" and tw.w:
            w = self._solve(t, x, w, u)
        out = dict(zip(tw.der, tw.f(t, x, w, u)))
        out.update(zip(tw.res, tw.g(t, x, w, u)))
        out.update(zip(tw.y, tw.h(t, x, w, u)))
        out.update(zip(tw.w, w))
        return out

    def _solve(self, t, x, w, u):
        tw = self.twin
        sol, _, ier, msg = fsolve(
            lambda ww: np.real(tw.g(t.real, x.real, ww, u.real)) - tw.ode_offset, w.real,
            xtol=1e-15, full_output=True)
        if ier != 1 and np.max(np.abs(np.real(tw.g(t.real, x.real, sol, u.real))
                                      - tw.ode_offset)) > 1e-12:
            raise FmiError("fmi3GetFloat64", "fmi3Error", [f"ODE mode: no solution ({msg})"])
        return sol.astype(complex)

    def evaluate(self, point: Point, unknowns: Sequence[int]) -> np.ndarray:
        self.calls += 1
        out = self._state(point)
        return np.array([out[k].real for k in unknowns])

    def jacobian(self, point, unknowns, knowns) -> np.ndarray:
        jac = np.zeros((len(unknowns), len(knowns)))
        for j, k in enumerate(knowns):
            out = self._state(point, (k, 1j * H))
            jac[:, j] = [out[q].imag / H for q in unknowns]
        return jac

    def directional(self, point, unknowns, knowns, seed):
        self.calls += 1
        if "directional" in self.refuse:
            raise FmiError("fmi3GetDirectionalDerivative", "fmi3Error", ["refused"])
        jac = self.jacobian(point, unknowns, knowns)
        if self.dd_hook:
            jac = self.dd_hook(jac, unknowns, knowns)
        if self.directional_hook:
            jac = self.directional_hook(jac, unknowns, knowns)
        return jac @ np.asarray(seed)

    def adjoint(self, point, unknowns, knowns, seed):
        self.calls += 1
        jac = self.jacobian(point, unknowns, knowns)
        if self.dd_hook:
            jac = self.dd_hook(jac, unknowns, knowns)
        if self.adj_hook:
            jac = self.adj_hook(jac, unknowns, knowns)
        return np.asarray(seed) @ jac


def _xml(scene: str, name: str, edits: Sequence[tuple[str, str]]) -> etree._ElementTree:
    text = (SCENES / scene / name).read_text()
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return etree.ElementTree(etree.fromstring(text.encode()))


def _points(twin: Twin, rng: np.random.Generator, count: int, spread: float) -> list[Point]:
    nominal = {2: 1.0, 4: 1e-5} if twin.x == [2, 4] else {}
    start = {k: float(v) for k, v in twin.start.items()}
    points = [Point(0.0, start, "start")]
    for k in range(count - 1):
        values = {vr: v + spread * nominal.get(vr, 1.0) * rng.uniform(-1, 1)
                  for vr, v in start.items()}
        points.append(Point(0.0, values, f"near-{k}"))
    return points


def make_ctx(scene: str, *, seed: int = 0, manifest_edits=(), md_edits=(), count: int = 4,
             spread: float = 0.3, twin: Twin | None = None, **fake) -> ProbeContext:
    twin = twin or TWINS[scene]()
    model = read_model_description(_xml(scene, "modelDescription.xml", md_edits))
    manifest = read_manifest(_xml(scene, "fmi-ls-manifest.xml", manifest_edits), draft="alpha1")
    rng = np.random.default_rng(seed)
    return ProbeContext(model=model, manifest=manifest, draft="alpha1", seed=seed, rng=rng,
                        points=_points(twin, rng, count, spread), dae=Fake(twin, **fake),
                        ode=Fake(twin, mode="ode"), new_instance=lambda mode: Fake(twin, mode))


def found(ctx: ProbeContext, skipped: dict[str, str] | None = None) -> dict[str, list]:
    out = {}
    for code, probe in FAMILY.items():
        try:
            violations = list(probe(ctx, **OPTIONS[code]))
        except ProbeSkipped as exc:
            if skipped is not None:
                skipped[code] = str(exc)
            continue
        if violations:
            out[code] = violations
    return out


# --------------------------------------------------------------------------------- clean

@pytest.mark.parametrize("seed", range(20))
@pytest.mark.parametrize("scene", sorted(TWINS))
def test_clean_twin_triggers_nothing(scene, seed):
    ctx = make_ctx(scene, seed=seed)
    skipped: dict[str, str] = {}
    assert found(ctx, skipped) == {}
    assert skipped == {}


def test_probes_say_why_they_cannot_run():
    skipped: dict[str, str] = {}
    ctx = make_ctx("SimpleDAE", count=1, md_edits=[(
        'providesDirectionalDerivatives="true"', 'providesDirectionalDerivatives="false"')])
    ctx.ode = None
    assert found(ctx, skipped) == {}
    assert set(skipped) == {"DAE740", "DAE743", "DAE744", "DAE747"}
    ctx = make_ctx("SimpleDAE")
    ctx.dae = None
    found(ctx, skipped)
    assert set(skipped) == set(FAMILY)
    assert skipped["DAE745"].startswith("DAE mode could not be started")


def test_survey_is_shared_and_publishes_the_jacobian():
    ctx = make_ctx("SimpleDAE")
    first = D.survey(ctx)
    assert D.survey(ctx) is first
    info = ctx.facts["info"]["jacobian"]
    assert info["rows"][:2] == ["__residual0", "__residual1"]
    assert "z1" in info["cols"]
    assert sorted(map(tuple, info["observed"])) == sorted(map(tuple, info["declared"]))


def test_colouring_saves_calls_on_a_sparse_model():
    ctx = make_ctx("HelloWorldDAE")
    calls = dict(D.survey(ctx).points[0].entries.calls)
    # 4 columns (x, y, z, time); x, y, z share rows, time is its own: 4 groups at most
    assert calls["directional"] <= 4 + 2
    plain = make_ctx("HelloWorldDAE")
    D.survey(plain, D.Settings(coloured=False))


# ------------------------------------------------------------------------------ defects

def _wrong(row_vr: int, col_vr: int, factor: float):
    def hook(jac, unknowns, knowns):
        jac = jac.copy()
        if row_vr in unknowns and col_vr in knowns:
            jac[list(unknowns).index(row_vr), list(knowns).index(col_vr)] *= factor
        return jac
    return hook


def test_wrong_directional_entry_is_a_directional_mismatch():
    ctx = make_ctx("SimpleDAE", directional_hook=_wrong(2, 1, -1.0))  # d der(x1)/d x1 flipped
    result = found(ctx)
    assert set(result) == {"DAE740"}
    (v,) = result["DAE740"]
    assert v.subject == "d(der(x1))/d(x1)"
    assert v.part == "dae-mode"     # fmi-ls-dae 3.4: residuals and algebraic variables
    ev = dict(v.evidence)
    assert ev["fmu"] == pytest.approx(-ev["finite_difference"], rel=1e-6)
    assert ev["tolerance"] > 0 and ev["error_estimate"] >= 0


def test_wrong_partial_behind_both_functions_is_reported_for_each():
    # the same wrong partial derivative behind fmi3GetDirectionalDerivative and
    # fmi3GetAdjointDerivative: an importer may call either, so each is a finding
    result = found(make_ctx("SimpleDAE", dd_hook=_wrong(2, 1, -1.0)))
    assert set(result) == {"DAE740", "DAE741"}
    assert [v.subject for v in result["DAE740"]] == ["d(der(x1))/d(x1)"]
    assert [v.subject for v in result["DAE741"]] == ["d(der(x1))/d(x1)"]


def _zeros(jac, unknowns, knowns):
    return np.zeros_like(jac)


@pytest.mark.parametrize("scene", sorted(TWINS))
def test_zero_derivatives_of_both_functions_are_both_findings_and_nothing_else(scene):
    # every scene claims both functions (providesDirectional/AdjointDerivatives)
    assert set(found(make_ctx(scene, dd_hook=_zeros))) == {"DAE740", "DAE741"}


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("scene", sorted(TWINS))
def test_zero_directional_derivatives_are_not_used_for_dgdw(scene, seed):
    # correct equations, directional derivatives all zero, the adjoint right: the derivative
    # finding only, not a singular dg/dw built from the zeros
    result = found(make_ctx(scene, seed=seed, directional_hook=_zeros))
    assert set(result) == {"DAE740"}


def test_singular_dgdw_is_found_from_finite_differences_when_the_derivatives_are_refuted():
    twin = _hello_with(lambda t, x, w, u: [w[0] + 2 * w[1] - x[0], 2 * w[0] + 4 * w[1] - 2 * x[0]])
    result = found(make_ctx("HelloWorldDAE", twin=twin, directional_hook=_zeros))
    assert set(result) == {"DAE740", "DAE746"}
    ev = dict(result["DAE746"][0].evidence)
    assert ev["source"] == "finite differences"
    assert "not used" in ev["note"] and ev["measurement_error"] >= 0
    assert set(ev["involved"]) == {"y", "z"}


def test_dgdw_uses_confirmed_directional_derivatives_without_a_note():
    twin = _hello_with(lambda t, x, w, u: [w[0] + 2 * w[1] - x[0], 2 * w[0] + 4 * w[1] - 2 * x[0]])
    (v,) = found(make_ctx("HelloWorldDAE", twin=twin))["DAE746"]
    ev = dict(v.evidence)
    assert ev["source"] == "fmi3GetDirectionalDerivative"
    assert "note" not in ev and "measurement_error" not in ev


def test_directional_verdict_uses_the_options_of_directional_derivative_mismatch():
    from conformance.probes.instruments.entry_comparison import OPTIONS_FACT, directional_verdict

    ctx = make_ctx("SimpleDAE", directional_hook=_wrong(2, 1, 1.0 + 1e-4))
    s = D.survey(ctx)
    assert directional_verdict(ctx, s)[0] is False      # the catalogue's rtol 1e-5
    ctx.facts[OPTIONS_FACT] = {**ctx.facts[OPTIONS_FACT], "rtol": 1e-2}
    assert directional_verdict(ctx, s) == (True, "")    # as DAE740 ran: confirmed


def test_wrong_adjoint_only_is_an_adjoint_mismatch():
    ctx = make_ctx("SimpleDAE", adj_hook=_wrong(12, 6, 2.0))
    result = found(ctx)
    assert set(result) == {"DAE741"}
    assert result["DAE741"][0].subject == "d(__residual1)/d(z2)"


def test_adjoint_wrong_at_an_undeclared_entry_is_an_adjoint_mismatch():
    def hook(jac, unknowns, knowns):
        jac = jac.copy()
        if 11 in unknowns and 6 in knowns:     # residual0 does not depend on z2
            jac[list(unknowns).index(11), list(knowns).index(6)] = 0.7
        return jac
    result = found(make_ctx("SimpleDAE", adj_hook=hook))
    assert set(result) == {"DAE741"}


def test_directional_nonzero_at_an_undeclared_entry_is_a_directional_mismatch():
    def hook(jac, unknowns, knowns):
        jac = jac.copy()
        if 11 in unknowns and 6 in knowns:
            jac[list(unknowns).index(11), list(knowns).index(6)] = 0.7
        return jac
    result = found(make_ctx("SimpleDAE", directional_hook=hook))
    assert set(result) == {"DAE740"}
    assert result["DAE740"][0].subject == "d(__residual0)/d(z2)"


def test_missing_dependency_is_undeclared():
    ctx = make_ctx("SimpleDAE", manifest_edits=[(
        '<Residual valueReference="12" dependencies="3 5 6 7" dependenciesKind="dependent '
        'dependent dependent dependent"/>',
        '<Residual valueReference="12" dependencies="3 5 7" dependenciesKind="dependent '
        'dependent dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE742"}
    assert [v.subject for v in result["DAE742"]] == ["d(__residual1)/d(z2)"]
    assert [v.part for v in result["DAE742"]] == ["residual-dependencies"]


def test_undeclared_inputs_of_the_residuals_do_not_leak_into_the_outputs_adjoint():
    # residual0 and residual1 without u1, u2: the row colouring seeds them with the outputs
    # (no declared column in common), and their real u-entries add to the outputs' u-entries;
    # the single-entry adjoint call clears the outputs
    ctx = make_ctx("SimpleDAE", manifest_edits=[
        ('<Residual valueReference="11" dependencies="1 5 7 8" dependenciesKind="dependent '
         'dependent dependent dependent"/>',
         '<Residual valueReference="11" dependencies="1 5" dependenciesKind="dependent '
         'dependent"/>'),
        ('<Residual valueReference="12" dependencies="3 5 6 7" dependenciesKind="dependent '
         'dependent dependent dependent"/>',
         '<Residual valueReference="12" dependencies="3 5 6" dependenciesKind="dependent '
         'dependent dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE742"}
    assert {v.subject for v in result["DAE742"]} >= {"d(__residual0)/d(u2)",
                                                      "d(__residual1)/d(u1)"}


def test_adjoint_mismatch_confirmed_by_the_single_entry_call_is_kept():
    calls = []
    ctx = make_ctx("SimpleDAE", adj_hook=_wrong(12, 6, 2.0))
    adjoint = ctx.dae.adjoint

    def spy(point, unknowns, knowns, seed):
        calls.append((list(unknowns), list(knowns)))
        return adjoint(point, unknowns, knowns, seed)

    ctx.dae.adjoint = spy
    (v,) = list(D.adjoint_derivative_mismatch(ctx, **OPTIONS["DAE741"]))
    assert ([12], [6]) in calls            # the row seeded, the column read, nothing else
    ev = dict(v.evidence)
    assert ev["confirmed"].startswith("single-entry")
    assert ev["fmu"] == pytest.approx(2 * ev["finite_difference"], rel=1e-6)


def test_missing_dependency_hidden_behind_a_declared_column_is_found():
    # Robertson: drop y3 from der(y1); y3 then shares a group with a declared column
    ctx = make_ctx("Robertson", manifest_edits=[(
        '<ContinuousStateDerivative valueReference="3" dependencies="2 4 6" '
        'dependenciesKind="constant dependent dependent"/>',
        '<ContinuousStateDerivative valueReference="3" dependencies="2 4" '
        'dependenciesKind="constant dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE742"}
    assert [v.subject for v in result["DAE742"]] == ["d(der(y1))/d(y3)"]
    assert [v.part for v in result["DAE742"]] == [None]    # the core's promise, not a residual


def test_extra_dependency_is_never_observed():
    ctx = make_ctx("SimpleDAE", manifest_edits=[(
        '<Output valueReference="9" dependencies="1 5 7 8" dependenciesKind="dependent '
        'dependent dependent dependent"/>',
        '<Output valueReference="9" dependencies="1 3 5 7 8" dependenciesKind="dependent '
        'dependent dependent dependent dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE743"}
    assert [v.subject for v in result["DAE743"]] == ["d(y1)/d(x2)"]
    assert [v.part for v in result["DAE743"]] == [None]


def test_time_listed_but_never_observed_is_its_part():
    ctx = make_ctx("SimpleDAE", manifest_edits=[(
        '<Output valueReference="9" dependencies="1 5 7 8" dependenciesKind="dependent '
        'dependent dependent dependent"/>',
        '<Output valueReference="9" dependencies="0 1 5 7 8" dependenciesKind="dependent '
        'dependent dependent dependent dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE743"}
    assert [(v.subject, v.part) for v in result["DAE743"]] == [("d(y1)/d(time)", "time-listed")]


def test_constant_on_a_nonlinear_term_violates_the_kind():
    ctx = make_ctx("SimpleDAE", manifest_edits=[(
        '<Residual valueReference="11" dependencies="1 5 7 8" dependenciesKind="dependent '
        'dependent dependent dependent"/>',
        '<Residual valueReference="11" dependencies="1 5 7 8" dependenciesKind="dependent '
        'constant dependent dependent"/>')])
    result = found(ctx)
    assert set(result) == {"DAE744"}
    assert [v.subject for v in result["DAE744"]] == ["d(__residual0)/d(z1)"]


def test_constant_on_a_linear_term_is_fine_even_when_stiff():
    ctx = make_ctx("Robertson")      # der(y1) is declared constant in y1, -0.04
    assert "DAE744" not in found(ctx)


def _hello_with(g: Callable) -> Twin:
    twin = _hello()
    twin.g = g
    return twin


def test_singular_dgdw():
    twin = _hello_with(lambda t, x, w, u: [w[0] + 2 * w[1] - x[0], 2 * w[0] + 4 * w[1] - 2 * x[0]])
    result = found(make_ctx("HelloWorldDAE", twin=twin))
    assert set(result) == {"DAE746"}
    ev = dict(result["DAE746"][0].evidence)
    assert set(ev["involved"]) == {"y", "z"}


def test_ill_conditioned_dgdw():
    delta = 1e-10
    twin = _hello_with(lambda t, x, w, u: [w[0] + 2 * w[1] - x[0],
                                           w[0] + (2 + delta) * w[1] - x[0] * (1 + delta / 2)])
    result = found(make_ctx("HelloWorldDAE", twin=twin))
    assert set(result) == {"DAE745"}
    assert dict(result["DAE745"][0].evidence)["condition_number"] > 1e8


def test_badly_scaled_but_well_posed_dgdw_is_not_ill_conditioned():
    # the second residual in other units (times 1e9): equilibration removes it
    twin = _hello_with(lambda t, x, w, u: [w[0] + 2 * w[1] - x[0],
                                           1e9 * (w[0] - 3 * w[1] - 2 * x[0])])
    assert found(make_ctx("HelloWorldDAE", twin=twin)) == {}


def test_ode_mode_solving_another_equation_is_inconsistent():
    twin = _simple()
    twin.ode_offset = 0.05
    result = found(make_ctx("SimpleDAE", twin=twin))
    assert set(result) == {"DAE747"}
    ev = dict(result["DAE747"][0].evidence)
    assert ev["newton_converged"] is True


def test_refused_directional_derivative_is_reported_once():
    result = found(make_ctx("SimpleDAE", refuse=["directional"]))
    assert set(result) == {"DAE740"}
    assert len(result["DAE740"]) == 1
    assert dict(result["DAE740"][0].evidence)["status"] == "fmi3Error"
    assert result["DAE740"][0].part == "refused-in-dae-mode"


def test_probe_errors_are_published_for_mismatches():
    ctx = make_ctx("SimpleDAE", dd_hook=_wrong(2, 1, -1.0))
    list(D.directional_derivative_mismatch(ctx, **OPTIONS["DAE740"]))
    errors = ctx.facts["info"]["probe_errors"]
    assert errors and errors[0]["rule"] == "DAE740"
    assert errors[0]["error"] > errors[0]["tolerance"]


# ------------------------------------------------------------------- the Chain scene (real)

def test_chain_xml_is_the_generators():
    from tests.fixtures import chain

    here = SCENES / "Chain"
    assert (here / "modelDescription.xml").read_text() == chain.model_description(4)
    assert (here / "fmi-ls-manifest.xml").read_text() == chain.manifest(4)


@pytest.mark.parametrize("seed", range(20))
def test_chain_fmu_is_clean_with_probes(seed):
    from conformance.run.engine import EngineOptions, check_fmu
    from tests.fixtures import chain

    # The simulation probes do not depend on the seed: run them once, as
    # tests/probes/test_clean_scenes.py does.
    ignore = () if seed == 0 else ("DAE8",)
    report = check_fmu(chain.build_chain(),
                       options=EngineOptions(probes=True, seed=seed, ignore=ignore))
    assert report.findings == (), [(f.code, f.subject, f.message) for f in report.findings]
    assert [c for c, _ in report.rules_skipped if c.startswith("DAE7")] == []


def test_larger_chain_fmu_is_clean_and_coloured_with_three_groups():
    from conformance.run.engine import EngineOptions, check_fmu
    from tests.fixtures import chain

    report = check_fmu(chain.build_chain(40), options=EngineOptions(probes=True))
    # In ODE mode der(x) = w[0] - x depends on u through 40 links of a diagonally dominant
    # chain, by about 4^-40: a real dependency no perturbation can show, which
    # dependency-never-observed says, as information, and nothing else.
    assert {(f.code, dict(f.evidence).get("mode")) for f in report.findings} <= {
        ("DAE743", "ODE mode")}
    info = dict(report.info)
    jac = dict(info["jacobian"]) if not isinstance(info["jacobian"], dict) else info["jacobian"]
    assert len(jac["rows"]) == 42 and len(jac["cols"]) == 43


# ------------------------------------------------------------------------- the benchmark

def test_probe_bench_smoke(tmp_path):
    from bench import probe_bench as pb

    methods = pb.bench_methods(1, ["HelloWorldDAE"])
    assert [r["method"] for r in methods] == ["forward", "central", "extrapolated"]
    assert all(r["findings"] == 0 and r["max_error"] <= r["max_estimate"] for r in methods)
    assert methods[0]["evaluate"] < methods[1]["evaluate"] < methods[2]["evaluate"]
    small, large = pb._twin_case(30, True, 1), pb._twin_case(300, True, 1)
    assert (small["evaluate"], small["directional"], small["adjoint"]) == (
        large["evaluate"], large["directional"], large["adjoint"])
    column = pb._twin_case(30, False, 1)
    assert column["evaluate"] == 1 + 4 * column["groups"] + 4 * 2
    data = {"date": "d", "machine": pb.machine_info(), "numpy": np.__version__, "runs": 1,
            "methods": methods, "scaling": [small, large, column]}
    assert "| numpy twin | 300 | coloured |" in pb.render_markdown(data)


def test_non_finite_values_are_left_to_nan_or_inf():
    twin = _simple()
    f = twin.f
    twin.f = lambda t, x, w, u: [f(t, x, w, u)[0], np.nan * x[0]]
    assert found(make_ctx("SimpleDAE", twin=twin)) == {}


def test_variable_dependencies_reported_by_the_fmu_are_checked_against_the_manifest():
    ctx = make_ctx("SimpleDAE", md_edits=[('providesAdjointDerivatives="true"',
                                           'providesAdjointDerivatives="true" '
                                           'providesPerElementDependencies="true"')])
    # the FMU says y1 (vr 9) depends on x2 (vr 3), which the manifest leaves out
    ctx.dae.variable_dependencies = lambda vr: ([(1, "dependent"), (3, "dependent")]
                                                if vr == 9 else [])
    result = found(ctx)
    assert set(result) == {"DAE742"}
    (v,) = result["DAE742"]
    assert v.subject == "d(y1)/d(x2)"
    assert dict(v.evidence)["source"] == "fmi3GetVariableDependencies"
    assert v.part == "reported-dependencies-dae-mode"
