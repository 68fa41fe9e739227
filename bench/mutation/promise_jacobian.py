"""The derivative promises, measured with fmpy: partial derivatives against finite differences,
structural zeros against the declared dependencies, and the declared kinds across points.

Only the helpers of :mod:`promises`; no lsdae code. Each function takes a :class:`Session` in
Continuous-Time Mode at a point and returns ``(key, detail)`` violations: the key names the
promise, mode, point and entry without numbers (so the original's violations can be subtracted
from a mutant's), the detail carries the numbers.

Finite differences are central, with steps h and 2h, h = 1e-6 max(|v|, nominal); their
difference estimates the truncation and rounding error. An entry of the directional derivative
is wrong when it differs from the difference quotient by more than 1e-6 of the entry's size
(at least 1) plus ten times that estimate (PD-06); the adjoint must agree with the directional
derivative to 1e-9 (vT (J s) = (JT v)T s). A known left out of an unknown's ``dependencies``
must give exactly 0 in the directional derivative and a difference quotient within its noise
(MS-20). An entry declared ``constant``, ``fixed``, ``tunable`` or ``discrete`` must have the
same value at every point (MS-31).
"""
from __future__ import annotations

from typing import Sequence

from .fmu_view import Failure, SceneLayout, Session

Violation = tuple[str, str]
REL = 1e-6
ADJ_REL = 1e-9


def _names(lay: SceneLayout, vrs: Sequence[int]) -> list[str]:
    return [lay.variables[vr].name if vr in lay.variables else str(vr) for vr in vrs]


def knowns_unknowns(lay: SceneLayout, mode: str) -> tuple[list[int], list[int]]:
    unknowns = [*lay.derivatives, *lay.outputs, *(lay.residuals if mode == "dae" else ())]
    knowns = [*lay.states, *lay.inputs, *(lay.algebraic if mode == "dae" else ())]
    return unknowns, knowns


def _set_known(s: Session, lay: SceneLayout, vr: int, value: float) -> None:
    if vr in lay.states:
        x = [float(v) for v in s.vector("states", len(lay.states))]
        x[lay.states.index(vr)] = value
        s.set_point(None, x, [float(v) for v in s.read(lay.inputs)], None)
    else:
        s.call("fmi3SetFloat64", s.model.setFloat64, [vr], [value])


def finite_differences(s: Session, lay: SceneLayout, unknowns: list[int],
                       knowns: list[int]) -> tuple[list[list[float]], list[list[float]]]:
    """(quotients with step h, error estimates), rows unknowns, columns knowns."""
    fd = [[0.0] * len(knowns) for _ in unknowns]
    est = [[0.0] * len(knowns) for _ in unknowns]
    for j, vr in enumerate(knowns):
        v0 = float(s.read([vr])[0])
        nominal = lay.variables[vr].nominal or 1.0
        h = 1e-6 * max(abs(v0), abs(nominal))
        quotients = []
        for step in (h, 2 * h):
            values = []
            for sign in (1.0, -1.0):
                _set_known(s, lay, vr, v0 + sign * step)
                values.append([float(v) for v in s.read(unknowns)])
            quotients.append([(a - b) / (2 * step) for a, b in zip(*values)])
        _set_known(s, lay, vr, v0)
        for i in range(len(unknowns)):
            fd[i][j] = quotients[0][i]
            est[i][j] = abs(quotients[0][i] - quotients[1][i])
    return fd, est


def derivative_violations(s: Session, lay: SceneLayout, mode: str,
                          where: str) -> tuple[list[Violation], list[list[float]]]:
    """PD-06 and MS-20 at the current point; also returns the directional Jacobian."""
    unknowns, knowns = knowns_unknowns(lay, mode)
    rows, cols = _names(lay, unknowns), _names(lay, knowns)
    out: list[Violation] = []
    try:
        jac = s.jacobian(unknowns, knowns)
        adj = s.jacobian(unknowns, knowns, adjoint=True)
        fd, est = finite_differences(s, lay, unknowns, knowns)
    except (Failure, ValueError, TypeError) as exc:
        return [(f"PD-06 derivatives computable ({mode} {where})", str(exc)[:200])], []
    if isinstance(jac, str) or isinstance(adj, str):
        return [(f"PD-06 derivatives computable ({mode} {where})", str(jac)[:200])], []
    structure = lay.structure(mode)
    for i, uvr in enumerate(unknowns):
        declared = structure.get(uvr)
        for j, kvr in enumerate(knowns):
            entry = f"d({rows[i]})/d({cols[j]})"
            d, a, q, e = float(jac[i][j]), float(adj[i][j]), fd[i][j], est[i][j]
            if not abs(d - q) <= REL * max(1.0, abs(d), abs(q)) + 10 * e:   # NaN too
                out.append((f"PD-06 directional = finite difference ({mode} {where} {entry})",
                            f"directional {d!r}, finite difference {q!r} (noise {e:.1e})"))
            if not abs(a - d) <= ADJ_REL * max(1.0, abs(d)):
                out.append((f"PD-06 adjoint = directional ({mode} {where} {entry})",
                            f"adjoint {a!r}, directional {d!r}"))
            listed = declared is None or declared.dependencies is None or \
                kvr in declared.dependencies
            if not listed and (d != 0.0 or abs(q) > 10 * e + 1e-9 * max(1.0, abs(q))):
                out.append((f"MS-20 undeclared dependency is zero ({mode} {where} {entry})",
                            f"directional {d!r}, finite difference {q!r}"))
    return out, [[float(v) for v in row] for row in jac]


def kind_violations(lay: SceneLayout, mode: str,
                    jacobians: list[list[list[float]]]) -> list[Violation]:
    """MS-31: entries with a linear kind have one value at every point."""
    unknowns, knowns = knowns_unknowns(lay, mode)
    out: list[Violation] = []
    structure = lay.structure(mode)
    for i, uvr in enumerate(unknowns):
        declared = structure.get(uvr)
        if declared is None or declared.dependencies is None:
            continue
        for kvr, kind in zip(declared.dependencies, declared.kinds):
            if kind == "dependent" or kvr not in knowns:
                continue
            j = knowns.index(kvr)
            values = [jac[i][j] for jac in jacobians if jac]
            if values and not max(values) - min(values) <= 1e-9 * max(1.0, *map(abs, values)):
                entry = f"d({_names(lay, [uvr])[0]})/d({_names(lay, [kvr])[0]})"
                out.append((f"MS-31 {kind} entry constant across points ({mode} {entry})",
                            f"values {values}"))
    return out
