"""The initialization family: the InitialUnknowns of Initialization Mode.

``unknowns`` (initial-dependency-undeclared, initial-dependencies-kind-violated,
initial-directional-derivative-mismatch) on the survey of ``survey``, with its ``layout``
(rows, columns, promises) and ``instances`` (a fresh instance per function value).

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
