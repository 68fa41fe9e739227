"""The probe stage: dynamic rules that load the FMU's binary in a worker process.

From the top: ``runner`` (parent side, what the engine calls), ``lanes`` (which probes run in
which of two workers at once, for a large FMU) and ``driver`` (one worker after another, deaths
as findings); ``job`` (what the parent sends the worker); ``stage`` (the
worker's entry point); ``registry`` (probes by rule code, each family imported on first use);
the families (``handshake``, ``start_values``, ``basic``, ``evaluation``, ``readback``,
``derivatives``, ``dgdw``, ``initial_unknowns``, ``simulation``, ``invariants``, ...), none
importing another; and what they share: ``jacobian`` (the survey of one mode),
``jacobian_layout`` (DAE mode: the manifest's promises; ODE mode: modelDescription's, for a DAE
FMU with the switch off and for any Model Exchange FMU without the layer), ``instantiation``,
``readable`` (every variable an importer may read, read once per state and mode), ``common``,
``sampling`` and ``api`` (the contract). The binary itself is ``conformance.runtime``; the
numbers ``conformance.numerics``.

Nothing is imported here: the engine imports ``runner`` only when it probes, and the runner plans
the run from the registry's codes alone: numpy and the families load in the worker process only.

It imports ``simulate``, ``runtime``, ``intake``, ``model``, ``report`` and ``numerics``; never
``checks``, ``fixes``, ``run`` or ``commands``.
"""
