"""The read-back family: what an importer reads, and the calls it makes now and then.

``start_values`` (start-value-not-applied: a fresh instance holds the XML's start values, run
first), ``getters`` (the vector getters, the state nominals, values read on their own),
``importer_paths`` (states set through fmi3SetFloat64) and ``rare_calls`` (stop-time-refused,
illegal-call-accepted: run last but for the endurance probes).

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
