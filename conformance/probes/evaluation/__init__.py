"""The evaluation family: switching DAE mode on, setting the knowns, evaluating, reading.

``handshake`` (enable-handshake, dae-initialization-refused, reset-incomplete: the switch and
fmi3Reset), ``basic`` (algebraic-not-settable, initial-residual-nonzero,
evaluation-not-repeatable) and ``failures`` (nan-or-inf, evaluation-failed,
input-not-settable), with ``readable`` (every variable an importer may read, read once per
state and mode, for evaluation-failed).

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
