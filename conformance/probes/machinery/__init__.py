"""The machinery that runs any probe: the parent side plans and survives, the worker side runs.

Parent side (the engine's process; no numpy, no family is loaded): ``runner`` (what the engine
calls: the plan, the first-cause fold), ``lanes`` (one worker or two at once for a large FMU),
``driver`` (one worker after another, deaths as findings), ``deaths`` (what a death or a limit
means: the binary's fault or lsdae's own), ``job`` (what the parent sends the worker). Worker
side: ``stage`` (the worker's entry: loads the binary, samples the points, runs each probe) and
``registry`` (the probe families by rule code, each family package imported on first use).

It imports the instruments below it (``..instruments``), ``runtime``, ``model``, ``report`` and
``numerics``; the families only through the registry, by name, never by an import statement.
"""
