"""The probe stage: dynamic rules that load the FMU's binary in a worker process.

``run_probes`` (the runner, parent side) is what the engine calls; ``api`` is the contract
between the runner and the probes; ``session`` is the Evaluator on fmpy used in the worker;
``registry.PROBES`` maps rule codes to probe functions.

Nothing is imported eagerly: the worker process (``python -m conformance.probes.worker``)
imports this package first and must not load the runner with it.
"""
from __future__ import annotations

from typing import Any

__all__ = ["ProbeOutcome", "run_probes"]


def run_probes(*args: Any, **kwargs: Any) -> Any:
    """See :func:`conformance.probes.runner.run_probes`."""
    from .runner import run_probes as run

    return run(*args, **kwargs)


def __getattr__(name: str) -> Any:
    if name == "ProbeOutcome":
        from .runner import ProbeOutcome

        return ProbeOutcome
    raise AttributeError(name)
