"""lsdae: conformance checker for FMUs that implement the fmi-ls-dae layered standard.

The package is built in floors, each a subpackage that imports only from the floors below it
(docs/architecture.md; tests/unit/test_layers.py holds the code to it), top first:

    commands/   the command line: arguments, configuration, each subcommand, exit codes
    run/        the engine (archive -> schema -> static checks -> probes), parallel runs,
                shards, the result cache, progress
    checks/  probes/  fixes/
                static rules; probe rules (the binary in a worker); ``lsdae fix``
    simulate/   one simulation run of an FMU instance (DAE with IDA, ODE with CVODE)
    runtime/    the FMU binary: loading, instances, modes, the worker process; knows no rules
    intake/  reporters/
                opening an FMU and reading its XML without trusting either; output formats
    model/      the parsed model and manifest, and the manifest drafts (model/drafts/)
    report/  numerics/
                findings, the catalogue, baselines; finite differences, colouring, integrators
                and the structural graph algorithms (numerics/graphs/)
"""
from __future__ import annotations

__version__ = "0.1.0"
