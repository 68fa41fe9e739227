"""Narrowing a crash to the variable that causes it, in a worker of its own.

A worker that died during a getter of several variables (``fmi3GetFloat64`` of the residuals,
say) left their value references in the call record (:class:`~conformance.runtime.callrecord.
CallRecord`). Once the lane's probes are done, the driver starts one more worker with the pseudo
probe :data:`.job.NARROW`: it reads each of those variables alone with the same getter, in
Continuous-Time Mode in DAE mode and then in ODE mode (the instances every probe starts from).
The first read that crashes kills this worker too, and its call record names one variable: the
death is diagnosed as any other (:mod:`.deaths`), and the crash's finding names that variable
(``conformance.run.causes`` makes the narrowest call the finding of the crash). A crash that
needs a state the probes reached on their way (an event, a failed call before it) may not
happen again here: then nothing is added, and the finding names the call's variables.
"""
from __future__ import annotations

from typing import Any, Iterator

from ...runtime.records import GETTERS
from ..instruments.api import FmiError, ProbeContext
from ..instruments.instantiation import element_count

from .job import NARROW

_TYPE_OF = {fname: type_ for type_, (fname, _) in GETTERS.items()}


def narrow(ctx: ProbeContext, record: Any, *, call: str, refs: list[int]) -> Iterator[Any]:
    """Read each of ``refs`` alone with ``call``, in DAE mode and then in ODE mode; yields
    nothing (a crash is the result, diagnosed by the driver)."""
    type_ = _TYPE_OF[call]
    by_vr = ctx.model.by_vr if ctx.model is not None else {}
    for mode in ("dae", "ode"):
        inst = getattr(ctx, mode)
        if inst is None:
            continue
        record.set_probe(f"{NARROW} {mode}")
        for vr in refs:
            var = by_vr.get(vr)
            size = element_count(ctx.model, var) if var is not None else 1
            try:
                inst.get_typed(type_, [vr], max(1, size or 1))
            except FmiError:
                continue
    return
    yield

