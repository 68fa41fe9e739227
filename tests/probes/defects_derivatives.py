"""Defect variants for the derivative probes (Jacobians, dependencies, dependenciesKind...).

Each entry must trigger exactly its rule (plus ``also``); see tests/probes/test_defects.py.
"""
from __future__ import annotations

from tests.probes.variants import Defect

# Chain (N = 4) with x and u dropped from the residuals and the last residual replaced by one
# built from the one before it (see tests/scenes/Chain/model.c): the manifest says so.
_CHAIN_DECOUPLED = (
    ('<Residual valueReference="11" dependencies="2 10 12" '
     'dependenciesKind="constant dependent constant"/>',
     '<Residual valueReference="11" dependencies="10 12" '
     'dependenciesKind="dependent constant"/>'),
    ('<Residual valueReference="17" dependencies="4 14 16" '
     'dependenciesKind="constant constant dependent"/>',
     '<Residual valueReference="17" dependencies="12 14 16" '
     'dependenciesKind="constant dependent constant"/>'),
)

DEFECTS: list[Defect] = [
    Defect("DAE740", "SimpleDAE", defines=("DEFECT_WRONG_JACOBIAN",),
           note="d der(x1)/d x1 has the wrong sign in the partial derivatives"),
    # Needs the DEFECT_WRONG_ADJOINT hook in tests/scenes/common/fmi3_framework.c: the adjoint
    # and the directional derivative share the model's partials(), so no model.c can get one
    # wrong without the other.
    Defect("DAE741", "SimpleDAE", defines=("DEFECT_WRONG_ADJOINT",),
           note="the adjoint alone doubles d(__residual0)/d(z1)"),
    Defect("DAE742", "SimpleDAE", manifest_edits=((
        '<ContinuousStateDerivative valueReference="2" dependencies="1 5 6 7" '
        'dependenciesKind="dependent dependent dependent dependent"/>',
        '<ContinuousStateDerivative valueReference="2" dependencies="1 5 7" '
        'dependenciesKind="dependent dependent dependent"/>'),),
           note="der(x1) = sin(x1) + sin(z1*z2*u1) depends on z2, which the manifest leaves out"),
    # fmi3GetVariableDependencies against the manifest: Chain declares
    # providesPerElementDependencies and its framework reports the model's pattern.
    Defect("DAE742", "Chain", defines=("DEFECT_EXTRA_DEPENDENCY",),
           note="in DAE mode fmi3GetVariableDependencies says y depends on x, which the "
                "manifest leaves out"),
    Defect("DAE743", "SimpleDAE", manifest_edits=((
        '<Output valueReference="9" dependencies="1 5 7 8" '
        'dependenciesKind="dependent dependent dependent dependent"/>',
        '<Output valueReference="9" dependencies="1 3 5 7 8" '
        'dependenciesKind="dependent dependent dependent dependent dependent"/>'),),
           note="y1 = u1*x1*z1 + sin(u2) does not depend on x2, which the manifest lists"),
    Defect("DAE744", "SimpleDAE", manifest_edits=((
        '<Residual valueReference="11" dependencies="1 5 7 8" '
        'dependenciesKind="dependent dependent dependent dependent"/>',
        '<Residual valueReference="11" dependencies="1 5 7 8" '
        'dependenciesKind="dependent constant dependent dependent"/>'),),
           note="__residual0 is declared constant in z1 but contains tanh(3*z1)"),
    Defect("DAE745", "Chain", defines=("DEFECT_ILL_CONDITIONED",),
           manifest_edits=_CHAIN_DECOUPLED,
           note="the last residual is the one before it plus 1e-10*w[3]: cond(dg/dw) ~ 1e11"),
    Defect("DAE746", "Chain", defines=("DEFECT_SINGULAR_GW",), manifest_edits=_CHAIN_DECOUPLED,
           note="the last residual is twice the one before it: dg/dw is singular"),
    # Needs the DEFECT_ODE_DAE_INCONSISTENT hook in fmi3_framework.c: model.c cannot tell the
    # modes apart, the framework's ODE-mode solve can.
    Defect("DAE747", "SimpleDAE", defines=("DEFECT_ODE_DAE_INCONSISTENT",),
           note="ODE mode solves g = 0.05 instead of the residuals DAE mode exposes"),
]
