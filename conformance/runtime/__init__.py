"""The FMU binary: loading it, instances and their modes, and the worker process around it.

``layout`` (which value references are states, w, residuals, ...), ``library`` (the shared
library loaded with ctypes), ``instance`` and ``modes`` (FMI calls and mode changes), ``point``;
the worker: ``protocol`` (the job), ``child`` (the worker's main, started as
``python -m conformance.runtime.child``), ``supervisor`` (limits and deaths), ``callrecord`` (the
FMI call in progress, shared with the parent), ``records``, ``errors``, ``host``.

It knows no rules: it imports ``model`` (attribute values), ``report`` and ``numerics`` only.
"""
