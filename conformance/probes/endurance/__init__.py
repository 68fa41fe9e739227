"""The endurance family: what sustained use shows, run last at the ``--endurance`` level.

``sustained`` (evaluation-fails-late, instances-not-independent) and ``memory``
(memory-grows), on the path run of ``run`` and its calls (``calls``).

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
