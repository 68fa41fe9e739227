"""The ODE-mode contract, probed like the DAE one (issue 21.1): modelDescription's
ModelStructure in ODE mode, whatever the manifest says, with one rule per promise and the mode
in each finding.

The family of each defect: other element kinds (Output, ContinuousStateDerivative,
EventIndicator, InitialUnknown), other knowns (a state, an input), other kinds
(dependenciesKind), both modes at once, other sizes (Chain at N = 4 and 64); and what must stay
clean (a constant kind that is true, the scenes themselves in tests/probes/test_clean_scenes.py).
The colouring keeps the calls of ODE mode independent of N, as in DAE mode: measured on the
ODE-mode layout of a generated Model Exchange model with N states and an event indicator.
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.numerics import colouring as col
from conformance.numerics import measure, numdiff
from conformance.probes.instruments.api import ProbeContext
from conformance.probes.instruments.jacobian_layout import build_layout
from conformance.report.findings import Severity, thaw
from conformance.run.engine import EngineOptions
from tests.checkkit import checked
from tests.fixtures import build_scene, chain, variant

MD = MODEL_DESCRIPTION

# SimpleDAE's modelDescription (ODE mode: the FMU solves z1, z2 from g = 0 itself)
DER_X1 = ('<ContinuousStateDerivative valueReference="2" dependencies="1 3 7 8" '
          'dependenciesKind="dependent dependent dependent dependent"/>')
DER_X2 = ('<ContinuousStateDerivative valueReference="4" dependencies="1 3 7 8" '
          'dependenciesKind="dependent dependent dependent dependent"/>')
Y1 = ('<Output valueReference="9" dependencies="1 7 8" '
      'dependenciesKind="dependent dependent dependent"/>')
Y2 = ('<Output valueReference="10" dependencies="1 3 7 8" '
      'dependenciesKind="dependent dependent dependent dependent"/>')
INIT_DER_X2 = ('<InitialUnknown valueReference="4" dependencies="1 3 7 8" '
               'dependenciesKind="dependent dependent dependent dependent"/>')


def _without(element: str, vr: int) -> str:
    """``element`` with the known ``vr`` (and its kind) left out of its dependencies."""
    deps = element.split('dependencies="')[1].split('"')[0].split()
    k = deps.index(str(vr))
    kinds = element.split('dependenciesKind="')[1].split('"')[0].split()
    new_deps = " ".join(d for i, d in enumerate(deps) if i != k)
    new_kinds = " ".join(d for i, d in enumerate(kinds) if i != k)
    return element.replace(f'dependencies="{" ".join(deps)}"', f'dependencies="{new_deps}"'
                           ).replace(f'dependenciesKind="{" ".join(kinds)}"',
                                     f'dependenciesKind="{new_kinds}"')


def _kind(element: str, vr: int, kind: str) -> str:
    deps = element.split('dependencies="')[1].split('"')[0].split()
    kinds = element.split('dependenciesKind="')[1].split('"')[0].split()
    kinds[deps.index(str(vr))] = kind
    return element.replace(element.split('dependenciesKind="')[1].split('"')[0],
                           " ".join(kinds))


def _bad(report) -> list[tuple[str, str | None, str | None, str | None]]:
    """(rule, subject, mode, file) of every warning or error."""
    return sorted((f.name, f.subject, f.evidence_dict().get("mode"), f.location.file)
                  for f in report.findings if f.severity >= Severity.WARNING)


def _line(fmu: Path, text: str) -> int:
    with zipfile.ZipFile(fmu) as zf:
        lines = zf.read(MD).decode().splitlines()
    return next(i for i, line in enumerate(lines, 1) if text in line)


# ------------------------------------------------------------ dependencies, in ODE mode only

@pytest.mark.parametrize("element, known, subject", [
    (DER_X1, 3, "d(der(x1))/d(x2)"),     # a state, through the z the FMU solves
    (DER_X2, 7, "d(der(x2))/d(u1)"),     # an input
    (Y1, 7, "d(y1)/d(u1)"),              # an output, an input
    (Y2, 1, "d(y2)/d(x1)"),              # an output, a state through z
])
def test_a_dependency_modeldescription_leaves_out_is_found_in_ode_mode(element, known, subject):
    fmu = variant("SimpleDAE", md_edits=((element, _without(element, known)),))
    report = checked(fmu, options=EngineOptions(probes=True))
    assert _bad(report) == [("dependency-undeclared", subject, "ODE mode", MD)]
    (finding,) = [f for f in report.findings if f.name == "dependency-undeclared"]
    assert finding.location.line == _line(fmu, _without(element, known))
    assert finding.evidence_dict()["declared_in"] == MD
    assert "(ODE mode)" in finding.message


@pytest.mark.parametrize("n", [4, 64])
def test_the_same_fault_at_other_sizes(tmp_path, n):
    # Chain: der(x) = w[0] - x depends on x itself in ODE mode, at any N
    old = 'ContinuousStateDerivative valueReference="3" dependencies="2 4"'
    fmu = _rewrite_md(chain.build_chain(n), tmp_path / f"chain{n}.fmu", old,
                      'ContinuousStateDerivative valueReference="3" dependencies="4"')
    report = checked(fmu, options=EngineOptions(probes=True))
    assert set(_bad(report)) == {("dependency-undeclared", "d(der(x))/d(x)", "ODE mode", MD)}
    # measured, and reported by fmi3GetVariableDependencies too (Chain declares
    # providesPerElementDependencies; in ODE mode it reports modelDescription's pattern)
    sources = {f.evidence_dict().get("source") for f in report.findings
               if f.name == "dependency-undeclared"}
    assert sources == {None, "fmi3GetVariableDependencies"}


def _rewrite_md(source: Path, target: Path, old: str, new: str) -> Path:
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == MD:
                text = data.decode()
                assert text.count(old) == 1, old
                # dependenciesKind follows the dependencies it describes
                text = text.replace(old, new).replace(
                    new + ' dependenciesKind="dependent dependent"',
                    new + ' dependenciesKind="dependent"')
                data = text.encode()
            zout.writestr(item, data)
    return target


def test_an_event_indicator_dependency_left_out_is_found_by_finite_differences():
    # EventDAE, ODE mode: z = (w - b)/k - s(k) with w = k x + b solved by the FMU: z = x - s
    fmu = variant("EventDAE", md_edits=((
        '<EventIndicator valueReference="6" dependencies="1" dependenciesKind="dependent"/>',
        '<EventIndicator valueReference="6" dependencies=""/>'),))
    report = checked(fmu, options=EngineOptions(probes=True))
    assert _bad(report) == [("dependency-undeclared", "d(z)/d(x)", "ODE mode", MD)]


# ----------------------------------------------------------------------------------- kinds

@pytest.mark.parametrize("element, known, kind, subject", [
    (DER_X1, 1, "constant", "d(der(x1))/d(x1)"),    # sin(x1)
    (DER_X2, 3, "fixed", "d(der(x2))/d(x2)"),       # sin(x1 x2)
    (Y2, 7, "tunable", "d(y2)/d(u1)"),              # sin(u1 u2)
])
def test_a_kind_the_ode_mode_breaks_is_found(element, known, kind, subject):
    fmu = variant("SimpleDAE", md_edits=((element, _kind(element, known, kind)),))
    report = checked(fmu, options=EngineOptions(probes=True))
    assert _bad(report) == [("dependencies-kind-violated", subject, "ODE mode", MD)]


def test_a_constant_kind_that_is_true_stays_clean():
    # EventDAE, ODE mode: z = x - s(k), affine in x between events: "constant" is a true claim
    fmu = variant("EventDAE", md_edits=((
        '<EventIndicator valueReference="6" dependencies="1" dependenciesKind="dependent"/>',
        '<EventIndicator valueReference="6" dependencies="1" dependenciesKind="constant"/>'),))
    report = checked(fmu, options=EngineOptions(probes=True))
    assert _bad(report) == []


# --------------------------------------------------------------------- Initialization Mode

def test_an_initial_unknown_of_modeldescription_is_verified_beside_the_manifests():
    # SimpleDAE's manifest lists its own InitialUnknowns: modelDescription's are verified too
    fmu = variant("SimpleDAE", md_edits=((INIT_DER_X2, _without(INIT_DER_X2, 7)),))
    report = checked(fmu, options=EngineOptions(probes=True))
    assert _bad(report) == [("initial-dependency-undeclared", "d(der(x2))/d(u1)", "ODE mode",
                             MD)]


# ------------------------------------------------------------------------------- both modes

def test_a_wrong_partial_derivative_behind_both_modes_is_one_finding_that_names_each():
    """One defect, one finding (issue 29): the same entry and deviation in both modes, in the
    directional and the adjoint derivative and in Initialization Mode is DAE740's finding in
    DAE mode, and its evidence names the five other places."""
    report = checked(build_scene("SimpleDAE", defines=["DEFECT_WRONG_JACOBIAN"]),
                       options=EngineOptions(probes=True))
    (finding,) = [f for f in report.findings if f.severity >= Severity.WARNING]
    assert (finding.code, finding.subject) == ("DAE740", "d(der(x1))/d(x1)")
    ev = thaw(finding.evidence)
    assert ev["mode"] == "DAE mode" and ev["place"] == "fmi3GetDirectionalDerivative, DAE mode"
    assert [(a["rule"], a["where"]) for a in ev["also"]] == [
        ("DAE740", "fmi3GetDirectionalDerivative, ODE mode"),
        ("DAE741", "fmi3GetAdjointDerivative, DAE mode"),
        ("DAE741", "fmi3GetAdjointDerivative, ODE mode"),
        ("DAE752", "fmi3GetDirectionalDerivative, Initialization Mode, DAE mode"),
        ("DAE752", "fmi3GetDirectionalDerivative, Initialization Mode, ODE mode")]
    assert "in 5 more places" in finding.message


def test_a_fault_of_ode_mode_alone_leaves_dae_mode_clean():
    report = checked(build_scene("SimpleDAE", defines=["DEFECT_ODE_DIRECTIONAL_OFF"]),
                       options=EngineOptions(probes=True))
    assert _bad(report) == [("directional-derivative-mismatch", "d(der(x1))/d(x1)", "ODE mode",
                             MD)]
    assert dict(dict(report.info)["modes"]) == {"DAE mode": "probed", "ODE mode": "probed"}


# ------------------------------------------------------------------------------ colouring

def _heat(n: int, *, indicator: bool) -> str:
    """A Model Exchange model: der(x_i) = x_{i-1} - 2 x_i + x_{i+1} (i = 0..n-1, x_{-1} = u),
    an output y = x_{n-1} and, optionally, an event indicator e = x_0 - 0.5."""
    x = [2 * i + 1 for i in range(n)]
    variables = ['<Float64 name="time" valueReference="0" causality="independent"/>']
    structure = ['<Output valueReference="900001" dependencies="%d"/>' % x[-1]]
    for i, vr in enumerate(x):
        variables += [f'<Float64 name="x{i}" valueReference="{vr}" initial="exact" '
                      f'start="{i / n}"/>',
                      f'<Float64 name="der(x{i})" valueReference="{vr + 1}" derivative="{vr}"/>']
        near = [x[j] for j in (i - 1, i, i + 1) if 0 <= j < n] + ([900000] if i == 0 else [])
        structure.append(f'<ContinuousStateDerivative valueReference="{vr + 1}" '
                         f'dependencies="{" ".join(map(str, near))}"/>')
    variables += ['<Float64 name="u" valueReference="900000" causality="input" start="0"/>',
                  '<Float64 name="y" valueReference="900001" causality="output"/>']
    if indicator:
        variables.append('<Float64 name="e" valueReference="900002"/>')
        structure.append(f'<EventIndicator valueReference="900002" dependencies="{x[0]}"/>')
    outputs = [s for s in structure if s.startswith("<Output")]
    others = [s for s in structure if not s.startswith("<Output")]
    return (f'<fmiModelDescription fmiVersion="3.0" modelName="Heat" instantiationToken="t">'
            f'<ModelExchange modelIdentifier="Heat" providesDirectionalDerivatives="true"/>'
            f'<ModelVariables>{"".join(variables)}</ModelVariables>'
            f'<ModelStructure>{"".join(outputs + others)}</ModelStructure>'
            f'</fmiModelDescription>')


def _heat_jacobian(n: int) -> np.ndarray:
    """Rows: der(x_0..n-1), y, e; columns: x_0..n-1, u, time (as the ODE layout orders them)."""
    jac = np.zeros((n + 2, n + 2))
    for i in range(n):
        for j, a in ((i - 1, 1.0), (i, -2.0), (i + 1, 1.0)):
            if 0 <= j < n:
                jac[i, j] = a
    jac[0, n] = 1.0
    jac[n, n - 1] = 1.0
    jac[n + 1, 0] = 1.0
    return jac


@pytest.mark.parametrize("indicator", [False, True])
def test_ode_mode_calls_do_not_grow_with_n(indicator):
    calls = {}
    for n in (20, 200):
        model = read_model_description(etree.ElementTree(etree.fromstring(
            _heat(n, indicator=indicator).encode())))
        ctx = ProbeContext(model=model, manifest=None, draft=None, seed=0,
                           rng=np.random.default_rng(0), points=[], dae=None, ode=None,
                           new_instance=lambda mode: None)
        layout, reason = build_layout(ctx, "ode")
        assert layout is not None and reason == ""
        assert [r.role for r in layout.rows] == (
            ["derivative"] * n + ["output"] + (["indicator"] if indicator else []))
        assert [c.role for c in layout.cols] == ["state"] * n + ["input", "time"]
        jac = _heat_jacobian(n)[: len(layout.rows)]
        derivable = layout.dd_rows
        assert derivable.tolist() == [True] * (n + 1) + ([False] if indicator else [])

        def directional(seed, jac=jac, derivable=derivable):
            return np.where(derivable, jac @ seed, np.nan)   # never asked for an indicator

        def adjoint(v, jac=jac, derivable=derivable):
            return (v * derivable) @ jac

        x = np.linspace(0, 1, len(layout.cols))
        entries = measure.measure(
            measure.Sources(lambda d, jac=jac: jac @ (x + d), directional, adjoint,
                            layout.dd_columns, derivable),
            layout.pattern, col.colour_columns(layout.pattern),
            numdiff.step_sizes(x, layout.nominal, method="central"), x,
            np.random.default_rng(1), row_colouring=col.colour_rows(layout.pattern))
        calls[n] = dict(entries.calls)
        assert entries.localised.size == 0          # nothing under suspicion
        rows = entries.rows
        if indicator:   # measured by finite differences, never by the FMU's derivatives
            last = rows == len(layout.rows) - 1
            assert last.any() and np.all(np.isnan(entries.dd[last]))
            assert np.all(np.isnan(entries.adj[last]))
            assert np.allclose(entries.fd[last], 1.0)
        assert np.all(np.isfinite(entries.dd[~np.isin(rows, [len(layout.rows) - 1])]
                                  if indicator else entries.dd))
    assert calls[20] == calls[200]
