"""The derivatives family: the FMU's partial derivatives, its dependencies and dg/dw.

``partials`` (directional and adjoint derivatives against finite differences, dependencies
undeclared, never observed or of the wrong kind) and ``dgdw`` (dg/dw ill-conditioned or
singular, and ODE mode against DAE mode at one point, with ``ode_dae``), both judging the
Jacobian survey of ``..instruments.jacobian``.

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
