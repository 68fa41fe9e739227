"""The run: one FMU through every stage, and many FMUs through the engine.

``engine`` (archive -> XML -> schema -> static checks -> probes; attaches code and severity),
``options`` (EngineOptions and the rule selection), ``reading`` (each XML file read once and
validated beside the reading), ``collector`` (violations -> grouped findings with their source
line), ``source_texts``, ``background``, ``heap``; for many FMUs ``parallel`` and
``process_pool`` (-j N), ``fleet`` (which FMUs a run checks), ``sharding`` (--shard),
``result_cache`` (--cache-dir) and ``progress``; ``simulate_fmu`` runs the simulation probes for
``lsdae simulate``.

It imports the stages below it (``checks``, ``probes``, ``fixes``, ``intake``, ``model``,
``reporters``, ``report``, ``numerics``), never ``commands``.
"""
