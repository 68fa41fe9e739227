"""Static checks: index 1 (DAE601-). Is dg/dw structurally non-singular?

The residual/algebraic-variable graph comes from the manifest ``dependencies`` of each Residual
(an absent attribute means "depends on every algebraic variable", an empty one "on none", MS-20;
entries that are not algebraic variables do not count). Array variables are expanded into their
elements; since dependencies are per variable (MS-13), each element of a residual depends on every
element of the algebraic variables it lists. The graph work is in :mod:`conformance.numerics.graphs.bipartite`,
:mod:`conformance.numerics.graphs.matching` and :mod:`conformance.numerics.graphs.dulmage_mendelsohn`.
"""
from __future__ import annotations

import logging
from bisect import bisect_right
from itertools import accumulate
from math import prod
from operator import attrgetter
from typing import TYPE_CHECKING, Iterable, Iterator, Sequence

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.manifest import VrRef
from ..model.description import ModelDescription, Variable
from ..model.unknowns import Unknown
from .listing import Resolution, resolution
from .model_analysis import analyse

if TYPE_CHECKING:
    from ..numerics.graphs.dulmage_mendelsohn import DulmageMendelsohn

log = logging.getLogger(__name__)


def _size(var: Variable, model: ModelDescription) -> int | None:
    """Number of elements of ``var`` at its start dimensions, or None if a size is unknown."""
    sizes = []
    for dim in var.dimensions:
        text = dim.start
        if text is None and dim.vr is not None:
            target = model.by_vr.get(dim.vr)
            text = target.start if target is not None else None
        if text is None or not text.strip().isdigit():
            return None
        sizes.append(int(text))
    return prod(sizes)


class _Elements:
    """Variables laid out element by element: variable i owns indices offsets[i]..offsets[i+1]-1."""

    def __init__(self, variables: Sequence[Variable], sizes: Sequence[int]) -> None:
        self.vars = variables
        self.offsets: list[int] = list(accumulate(sizes, initial=0))

    def ranges(self) -> Iterator[range]:
        """The element indices of each variable, in order."""
        return map(range, self.offsets, self.offsets[1:])

    def __len__(self) -> int:
        return self.offsets[-1]

    def owner(self, index: int) -> int:
        """Position (in ``vars``) of the variable that owns element ``index``."""
        return bisect_right(self.offsets, index) - 1

    def name(self, index: int) -> str:
        i = self.owner(index)
        var = self.vars[i]
        return f"{var.name}[{index - self.offsets[i] + 1}]" if var.dimensions else var.name

    def names(self, indices: Iterable[int]) -> list[str]:
        return [self.name(int(k)) for k in indices]


def _listing(names: Sequence[str], total: int) -> str:
    """Quoted names, then "and N more" when ``total`` exceeds the names given."""
    shown = ", ".join(f"'{n}'" for n in names)
    return shown + (f" and {total - len(names)} more" if total > len(names) else "")


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _s(n: int, verb: str) -> str:
    """The verb agreeing with a subject of ``n`` items ("depend" -> "depends" for one)."""
    return verb + "s" if n == 1 else verb


def _of_them(k: int) -> str:
    return "1 of them is" if k == 1 else f"{k} of them are"


def _explain(dm: DulmageMendelsohn, rows: _Elements, cols: _Elements, limit: int) -> str:
    """One clause per non-square part, naming at most ``limit`` elements of each list."""
    parts = []
    n_rows, n_cols = int(dm.over_rows.size), int(dm.over_cols.size)
    if n_rows:
        res = _listing(rows.names(dm.over_rows[:limit]), n_rows)
        if n_cols:
            parts.append(f"{_plural(n_rows, 'residual')} {res} together depend only on "
                         f"{_plural(n_cols, 'algebraic variable')} "
                         f"{_listing(cols.names(dm.over_cols[:limit]), n_cols)}, so "
                         f"{_of_them(n_rows - n_cols)} structurally redundant")
        else:
            parts.append(f"{_plural(n_rows, 'residual')} {res} {_s(n_rows, 'depend')} on no "
                         "algebraic variable")
    n_rows, n_cols = int(dm.under_rows.size), int(dm.under_cols.size)
    if n_cols:
        alg = _listing(cols.names(dm.under_cols[:limit]), n_cols)
        if n_rows:
            parts.append(f"{_plural(n_cols, 'algebraic variable')} {alg} together appear only "
                         f"in {_plural(n_rows, 'residual')} "
                         f"{_listing(rows.names(dm.under_rows[:limit]), n_rows)}, so "
                         f"{_of_them(n_cols - n_rows)} determined by no residual")
        else:
            parts.append(f"{_plural(n_cols, 'algebraic variable')} {alg} "
                         f"{_s(n_cols, 'appear')} in no residual")
    return "; ".join(parts)


def _resolve(listed: Resolution) -> tuple[Sequence[VrRef | Unknown], list[Variable]] | None:
    """The first entry of each distinct variable of a list, and the variables; None when one
    does not resolve (reported elsewhere)."""
    if not listed.complete:
        return None
    if listed.distinct:
        return listed.entries, listed.variables  # type: ignore[return-value]  # the usual case
    out: dict[int, tuple[VrRef | Unknown, Variable]] = {}
    for ref, var in zip(listed.entries, listed.variables):
        out.setdefault(ref.vr, (ref, var))  # type: ignore[arg-type]
    return [ref for ref, _ in out.values()], [var for _, var in out.values()]


def _sizes(variables: Sequence[Variable], model: ModelDescription) -> list[int | None]:
    """:func:`_size` of each variable."""
    if not analyse(model).has_arrays:
        return [1] * len(variables)  # all scalars, the usual case
    return [_size(var, model) for var in variables]


def _row_deps(res_refs: Sequence[Unknown], res_vars: Sequence[Variable],
              row_sizes: Sequence[int | None], cols: _Elements, max_edges: int
              ) -> list[list[int] | None] | None:
    """The columns each residual element depends on (None: all); None when a size is unknown
    or the graph has more than ``max_edges`` element edges (the check is then skipped)."""
    alg_vrs = map(attrgetter("vr"), cols.vars)
    if row_sizes.count(1) == len(row_sizes) and len(cols) == len(cols.vars):
        # All scalars, the usual case: column i is algebraic variable i, and a residual's list
        # is no longer than its dependencies attribute, so the edges are counted afterwards.
        col = dict(zip(alg_vrs, range(len(cols))))
        rows = [None if deps is None else [col[vr] for vr in deps if vr in col]
                for deps in map(attrgetter("dependencies"), res_refs)]
        if sum(map(len, filter(None, rows))) > max_edges:
            log.warning("index-1 check skipped: more than %d element edges", max_edges)
            return None
        return rows
    col_of = dict(zip(alg_vrs, cols.ranges()))
    row_deps: list[list[int] | None] = []
    edges = 0
    for ref, var, size in zip(res_refs, res_vars, row_sizes):
        if size is None:
            log.info("index-1 check skipped: size of %s is not known", var.name)
            return None
        deps = ref.dependencies
        mine = None if deps is None else [c for vr in deps if vr in col_of for c in col_of[vr]]
        edges += size * (len(mine) if mine is not None else 0)
        if edges > max_edges:
            log.warning("index-1 check skipped: more than %d element edges", max_edges)
            return None
        row_deps.extend([mine] * size)
    return row_deps


def _greedy_matching_size(row_deps: Sequence[list[int] | None], n_cols: int) -> int:
    """Size of a greedy matching: each row takes its first free column, full rows take what is
    left. Any matching is at most maximum, so when this one already has full size the graph
    is structurally non-singular; it does for the usual near-diagonal patterns, which spares
    loading scipy. Otherwise Hopcroft-Karp and Dulmage-Mendelsohn decide
    (conformance.numerics.graphs.dulmage_mendelsohn).
    """
    taken = bytearray(n_cols)
    size = full = 0
    for deps in row_deps:
        if deps is None:
            full += 1
            continue
        for c in deps:
            if not taken[c]:
                taken[c] = 1
                size += 1
                break
    return size + min(full, n_cols - size)


def index1_structurally_singular(ctx: CheckContext, *, max_names: int, max_evidence: int,
                                 max_edges: int) -> Iterator[Violation]:
    """The residual/algebraic-variable graph has a matching of size min(#residuals, #algebraic)."""
    model, manifest = ctx.model, ctx.manifest
    assert model is not None and manifest is not None
    algebraic = _resolve(resolution(ctx, "algebraic"))
    residuals = _resolve(resolution(ctx, "residuals"))
    if algebraic is None or residuals is None or not algebraic[0] or not residuals[0]:
        return
    (alg_refs, alg_vars), (res_refs, res_vars) = algebraic, residuals
    col_sizes = _sizes(alg_vars, model)
    if None in col_sizes:
        log.info("index-1 check skipped: size of %s is not known",
                 alg_vars[col_sizes.index(None)].name)
        return
    cols = _Elements(alg_vars, col_sizes)  # type: ignore[arg-type]
    row_sizes = _sizes(res_vars, model)
    row_deps = _row_deps(res_refs, res_vars, row_sizes, cols, max_edges)  # type: ignore[arg-type]
    if row_deps is None:
        return
    rows = _Elements(res_vars, row_sizes)  # type: ignore[arg-type]
    needed = min(len(rows), len(cols))
    if _greedy_matching_size(row_deps, len(cols)) >= needed:
        return  # a matching of full size was found without the graph machinery
    from ..numerics.graphs.bipartite import BipartitePattern  # scipy: only when needed
    from ..numerics.graphs.dulmage_mendelsohn import dulmage_mendelsohn  # scipy: only when needed

    dm = dulmage_mendelsohn(BipartitePattern.from_rows(row_deps, len(cols)))
    if dm.rank >= needed:
        return
    yield _violation(dm, needed, rows, cols, res_refs, alg_refs, manifest.file, max_names,
                     max_evidence)


def _violation(dm: DulmageMendelsohn, needed: int, rows: _Elements, cols: _Elements,
               res_refs: Sequence[VrRef | Unknown], alg_refs: Sequence[VrRef | Unknown],
               manifest_file: str, max_names: int, max_evidence: int) -> Violation:
    if dm.over_rows.size:
        ref = res_refs[rows.owner(int(dm.over_rows[0]))]
        location = Location(file=ref.file, line=ref.line, path=ref.path)  # type: ignore[union-attr]
        subject = rows.name(int(dm.over_rows[0]))
    else:
        ref = alg_refs[cols.owner(int(dm.under_cols[0]))]
        location = Location(file=manifest_file, line=ref.line, path=ref.path)
        subject = cols.name(int(dm.under_cols[0]))
    return Violation(
        "the Jacobian dg/dw of the residuals with respect to the algebraic variables is "
        f"structurally singular (structural rank {dm.rank} of {needed}): "
        f"{_explain(dm, rows, cols, max_names)}; give each algebraic variable a "
        "residual that determines it, or correct the residual dependencies",
        location,
        evidence(
            structural_rank=dm.rank, residuals=len(rows), algebraic_variables=len(cols),
            over_determined_residuals=rows.names(dm.over_rows[:max_evidence]),
            over_determined_variables=cols.names(dm.over_cols[:max_evidence]),
            under_determined_variables=cols.names(dm.under_cols[:max_evidence]),
            under_determined_residuals=rows.names(dm.under_rows[:max_evidence]),
            over_determined_size=[int(dm.over_rows.size), int(dm.over_cols.size)],
            under_determined_size=[int(dm.under_rows.size), int(dm.under_cols.size)],
            well_determined_size=int(dm.square_rows.size)),
        subject=subject)


CHECKS: dict[str, Check] = {
    "DAE601": index1_structurally_singular,
}
