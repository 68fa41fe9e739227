"""The simulation family: the FMU integrated in DAE mode (IDA) and ODE mode (CVODE).

``runs`` starts the runs every rule reads (``simulate.integrate``), ``verdicts`` judges
them (simulation-failed and the rules after it) and ``invariants`` reads them for
invariant-drift.

It imports ``..instruments``, ``simulate``, ``runtime``, ``model``, ``report`` and
``numerics``; never another family.
"""
