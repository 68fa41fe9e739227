"""Is an instance of this process independent of the others? The survey of the first cause.

An FMU that keeps state in C globals (the results of the last evaluation, cached partial
derivatives, the DAE switch, the inputs) lets one instance shift what another computes. Every
probe that compares two instances, or two modes (each mode is an instance of its own), then sees
a fault that is not the one it checks: a directional derivative that finite differences on
another instance do not confirm, an ODE mode that disagrees with DAE mode, a reset that keeps
the switch. ``instances-not-independent`` (DAE762) is the first cause; this module measures it.

:func:`survey` compares the process's own instances with instances **alone**: each made from a
twin of the library that loads a copy of the binary of its own (``Library.alone``), so that no
C global is shared. At the same points (P, the start point, and Q, a near point) it compares

* the process's first instance (the DAE-mode instance the stage made first) at P, before and
  after a later instance was set to Q: values (residuals, derivatives, outputs), the inputs
  read back, the directional derivatives of every unknown along every known, the DAE switch;
* a later DAE-mode instance at Q: the same;
* the process's ODE-mode instance and a later one at P: values, inputs and the switch (false).

An instance alone that does not repeat its own values at P after Q (a history the FMU keeps,
``evaluation-not-repeatable``'s finding) gives no reference: the survey then says so and finds
nothing.

The survey is memoised in ``ctx.facts`` and is not a family: it registers no probe. The probe
stage calls it when a rule that DAE762 may explain found something (the first-cause mechanism,
``conformance.probes.machinery.stage``), and DAE762 reports it
(``conformance.probes.endurance.sustained``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ...report.findings import Violation, evidence
from ...runtime.instance import Instance
from ...runtime.layout import Layout
from ...runtime.library import Library
from ...runtime.modes import start_instance
from .api import FmiError, Point, ProbeContext, ProbeSkipped
from .common import layout_of, unknowns_of

FACT = "independence.survey"
FIRST = "independence.first"      # the stage keeps the process's first instance here
MAX_LISTED = 10


@dataclass
class Shared:
    """What the survey found: the comparisons that differ (empty: independent), or why it
    could not be made (``reason``)."""

    found: list[dict[str, Any]] = field(default_factory=list)
    reason: str = ""


class _Compare:
    def __init__(self, layout: Layout, rtol: float, atol: float):
        self.layout, self.rtol, self.atol = layout, rtol, atol
        self.found: list[dict[str, Any]] = []

    def __call__(self, what: str, instance: str, point: str, names: Sequence[str],
                 scales: np.ndarray, expected: Any, actual: Any) -> None:
        a, b = np.asarray(expected, dtype=float), np.asarray(actual, dtype=float)
        with np.errstate(invalid="ignore"):
            off = np.isfinite(a) & np.isfinite(b) & ~(np.abs(a - b) <= self.atol + self.rtol * (
                np.maximum(scales, np.maximum(np.abs(a), np.abs(b)))))
        hits = np.flatnonzero(off).tolist()
        if hits:
            self.found.append({
                "compared": what, "instance": instance, "point": point, "count": len(hits),
                "differences": [{"item": names[k], "alone": float(a[k]), "actual": float(b[k])}
                                for k in hits[:MAX_LISTED]]})

    def values(self, mode: str, instance: str, point: str, vrs: Sequence[int],
               expected: np.ndarray, actual: np.ndarray) -> None:
        """Values, the inputs among them compared apart (what an input reads back)."""
        inputs = set(self.layout.inputs)
        for what, keep in (("inputs", True), ("values", False)):
            idx = [k for k, vr in enumerate(vrs) if (vr in inputs) == keep]
            if idx:
                self(what if what == "inputs" else f"values ({mode} mode)", instance, point,
                     [self.layout.name(vrs[k]) for k in idx],
                     np.array([self.layout.scale(vrs[k]) for k in idx]),
                     np.asarray(expected)[idx], np.asarray(actual)[idx])


def survey(ctx: ProbeContext, *, copies: int, rtol: float, atol: float) -> Shared:
    """The survey, made once per worker (memoised in ``ctx.facts``)."""
    memo = ctx.facts.get(FACT)
    if isinstance(memo, Shared):
        return memo
    try:
        result = _survey(ctx, copies=copies, rtol=rtol, atol=atol)
    except (FmiError, ProbeSkipped) as exc:
        result = Shared(reason=str(exc.cause() if isinstance(exc, FmiError) else exc))
    ctx.facts[FACT] = result
    return result


def _survey(ctx: ProbeContext, *, copies: int, rtol: float, atol: float) -> Shared:
    layout = layout_of(ctx)
    library: Library = ctx.facts["library"]  # type: ignore[assignment]
    first: Any = ctx.facts.get(FIRST) or ctx.dae
    if first is None or getattr(first, "component", None) is None or first.failure is not None:
        return Shared(reason="the process's first instance is no longer usable")
    cmp = _Compare(layout, rtol, atol)
    p, q = ctx.points[0], ctx.points[1 % len(ctx.points)]
    vals = list(dict.fromkeys([*unknowns_of(layout), *layout.inputs]))
    twin = library.alone(copies)
    made: list[Instance] = []
    try:
        alone = _started(twin, "dae", made)
        ref_p, ref_q = alone.evaluate(p, vals), alone.evaluate(q, vals)
        again = _Compare(layout, rtol, atol)
        again.values("DAE", "alone", p.label, vals, ref_p, alone.evaluate(p, vals))
        if again.found:   # no reference to compare with: the history matters, not the others
            return Shared(reason=f"an instance alone does not repeat its own values at "
                                 f"{p.label} after {q.label}: evaluation-not-repeatable's "
                                 "finding, not one about instances")
        d_p = _directional(alone, p, layout)
        d_q = _directional(alone, q, layout) if d_p is not None else None
        switch = _switch(alone, layout)
        # the process's instances are asked for derivatives only when the alone one gave
        # them: a call that fails there (fmi3Fatal ends every instance) spares the process's
        first_name = "the process's first instance"
        cmp.values("DAE", first_name, p.label, vals, ref_p, first.evaluate(p, vals))
        if d_p is not None:
            _derivatives(cmp, layout, first_name, p.label, d_p, _directional(first, p, layout))
        _mode(cmp, layout, first_name, switch, _switch(first, layout))
        later = _started(library, "dae", made)
        name = "a later instance of the process"
        cmp.values("DAE", name, q.label, vals, ref_q, later.evaluate(q, vals))
        if d_q is not None:
            _derivatives(cmp, layout, name, q.label, d_q, _directional(later, q, layout))
        _mode(cmp, layout, name, switch, _switch(later, layout))
        after = f"{first_name}, read again after a later one was set to {q.label}"
        cmp.values("DAE", after, p.label, vals, ref_p, first.get_float64(vals))
        if d_p is not None:
            _derivatives(cmp, layout, after, p.label, d_p, _directional(first, None, layout))
        _ode(ctx, cmp, layout, twin, library, p, made)
    finally:
        for inst in made:
            inst.free()
    return Shared(found=cmp.found)


def _started(library: Library, mode: str, made: list[Instance]) -> Instance:
    inst = start_instance(library, mode)
    made.append(inst)
    return inst


def _ode(ctx: ProbeContext, cmp: _Compare, layout: Layout, twin: Library, library: Library,
         p: Point, made: list[Instance]) -> None:
    """The ODE-mode instances of the process against one alone, at P."""
    if layout.enable is None or ctx.ode is None:
        return
    vals = list(dict.fromkeys([*unknowns_of(layout, "ode"), *layout.inputs]))
    alone = _started(twin, "ode", made)
    ref, switch = alone.evaluate(p, vals), _switch(alone, layout)
    for name, inst in (("the process's ODE-mode instance", ctx.ode),
                       ("a later ODE-mode instance of the process",
                        _started(library, "ode", made))):
        if getattr(inst, "failure", None) is not None:
            continue
        cmp.values("ODE", name, p.label, vals, ref, inst.evaluate(p, vals))  # type: ignore
        _mode(cmp, layout, name, switch, _switch(inst, layout))  # type: ignore[arg-type]


def _knowns(layout: Layout) -> list[int]:
    return list(dict.fromkeys([*layout.states, *layout.algebraic, *layout.inputs]))


def _directional(inst: Any, point: Point | None, layout: Layout) -> np.ndarray | None:
    """The directional derivative of every DAE-mode unknown along all knowns at once (a
    seed of ones), at ``point`` (None: at the values already set), or None when the FMU
    gives none."""
    if not layout.provides_directional:
        return None
    knowns, seed = _knowns(layout), np.ones(len(_knowns(layout)))
    try:
        if point is None:
            return np.asarray(inst.directional_as_set(unknowns_of(layout), knowns, seed),
                              dtype=float)
        return np.asarray(inst.directional(point, unknowns_of(layout), knowns, seed),
                          dtype=float)
    except (FmiError, ProbeSkipped):   # refused, or not called again (it hung or was fatal)
        return None


def _derivatives(cmp: _Compare, layout: Layout, instance: str, point: str,
                 expected: np.ndarray | None, actual: np.ndarray | None) -> None:
    if expected is None or actual is None:
        return
    rows = unknowns_of(layout)
    cmp("derivatives", instance, point, [f"d({layout.name(vr)}) along every known"
                                         for vr in rows],
        np.array([layout.scale(vr) for vr in rows]), expected, actual)


def _switch(inst: Instance, layout: Layout) -> float | None:
    if layout.enable is None:
        return None
    try:
        return float(inst.get_boolean(layout.enable))
    except FmiError:
        return None


def _mode(cmp: _Compare, layout: Layout, instance: str, expected: float | None,
          actual: float | None) -> None:
    if expected is None or actual is None or layout.enable is None:
        return
    cmp("mode", instance, "", [layout.name(layout.enable)], np.ones(1), [expected], [actual])


def shared_violation(ctx: ProbeContext, shared: Shared, location: Any, **more: Any
                     ) -> Violation:
    """instances-not-independent's finding from the survey: the first comparison that differs,
    every one in the evidence."""
    first = shared.found[0]
    shown = ", ".join(f"{d['item']} {d['actual']:.9g} instead of {d['alone']:.9g}"
                      for d in first["differences"][:3])
    where = f" at {first['point']}" if first["point"] else ""
    return Violation(
        f"instances are not independent: {first['instance']} gives other {first['compared']}"
        f"{where} than an instance alone in the process ({shown}); the FMU keeps state "
        "outside its instance (C globals or statics) that other instances change",
        location, evidence(first, comparisons=shared.found, reference=(
            "an instance alone: made from a copy of the binary of its own, so no C global "
            "is shared"), **more),
        subject=f"shared-{first['compared'].split(' ')[0]}")
