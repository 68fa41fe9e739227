"""Unit tests of the DAE-form rules (conformance/checks/dae_form.py): fully-implicit-form
(DAE406) and state-derivatives-unlisted (DAE407), on in-memory XML."""
from __future__ import annotations

from conformance.checks import dae_form
from tests.checks.test_structure_rules import _ctx, _run

MANIFEST_FILE = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"


def test_registered():
    assert set(dae_form.CHECKS) == {"DAE406", "DAE407"}


def test_fully_implicit_without_algebraic_variables_is_told_by_derivative_dependencies():
    # one state x, no algebraic variable, one residual that depends on der(x): the implicit
    # form 0 = F(der(x), x); the count alone (1 residual = 1 state + 0) would not tell
    ctx = _ctx('<Residual valueReference="6" dependencies="3 2"/>', algebraic=())
    [v] = _run("DAE406", ctx)
    assert v.subject == "fmiDAEManifest"
    assert (v.location.file, v.location.line, v.location.path) == (
        MANIFEST_FILE, 4, "/fmiDAEManifest/ModelStructure/Residual[1]")
    assert dict(v.evidence) == {"states": 1, "algebraic_variables": 0, "residuals": 1,
                                "residual_dependencies_on_derivatives": ("der(x)",)}
    assert _run("DAE407", ctx) == []   # fully-implicit-form says what it is


def test_semi_explicit_with_a_residual_too_many_is_not_fully_implicit():
    # the same counts, but the residual does not depend on der(x): a semi-explicit manifest
    ctx = _ctx('<Residual valueReference="6" dependencies="2"/>', algebraic=())
    assert _run("DAE406", ctx) == []
    [v] = _run("DAE407", ctx)
    assert v.location.path == "/fmiDAEManifest/ModelStructure/Residual[1]"


def test_state_derivatives_unlisted_without_residuals_points_at_the_root():
    ctx = _ctx("", algebraic=("4",))
    [v] = _run("DAE407", ctx)
    assert v.subject == "fmiDAEManifest"
    assert (v.location.file, v.location.line, v.location.path) == (MANIFEST_FILE, 1, None)
    assert dict(v.evidence) == {"states": ("x",), "state_count": 1}
