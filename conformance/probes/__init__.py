"""The probe stage: dynamic rules that load the FMU's binary in a worker process.

From the top: ``runner`` (parent side, what the engine calls) and ``driver`` (one worker after
another, deaths as findings); ``stage`` (the worker's entry point); ``registry`` (probes by rule
code); the families ``handshake``, ``basic``, ``derivatives``, ``dgdw`` and ``simulation``, none
importing another; and what they share: ``jacobian`` (the survey), ``common``, ``sampling`` and
``api`` (the contract). The binary itself is ``conformance.runtime``; the numbers
``conformance.numerics``.

Nothing is imported here: the engine imports ``runner`` only when it probes (numpy and the worker
machinery are not needed for a static check).
"""
