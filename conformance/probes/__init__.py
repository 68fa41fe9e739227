"""The probe stage: dynamic rules that load the FMU's binary in a worker process.

Three floors. On top, ``machinery``: what runs any probe (``runner``, what the engine calls;
``lanes``, one worker or two at once; ``driver`` and ``deaths``, a worker after another and what
its death means; ``job``; ``stage``, the worker's entry; ``registry``, the families by rule
code). In the middle, the families, side by side, each a package named for what it probes and
none importing another: ``evaluation`` (the switch, setting the knowns, evaluating),
``readback`` (what an importer reads: start values, getters, importers' paths, rare calls),
``events``, ``derivatives`` (the partial derivatives, dependencies, dg/dw), ``initialization``
(the InitialUnknowns), ``endurance`` and ``simulation``. A family reads what another found only
through ``ctx.facts``, as the registry's plan passes it. At the bottom, ``instruments``: the
contract (``api``) and what several families measure with (the Jacobian survey, the entry
comparison, the Event Mode walk, the sampling, the independence survey, ...). The binary
itself is ``conformance.runtime``; the numbers ``conformance.numerics``.

Nothing is imported here: the engine imports ``machinery.runner`` only when it probes, and the
runner plans the run from the registry's codes alone: numpy and the families load in the worker
process only.

It imports ``simulate``, ``runtime``, ``intake``, ``model``, ``report`` and ``numerics``; never
``checks``, ``fixes``, ``run`` or ``commands``.
"""
