"""Many FMUs over a CI job matrix: the share of one ``--shard I/N`` job and the ``--cache-dir``.

``lsdae check`` asks :func:`plan` which of its inputs to check (the shard's, by
:mod:`conformance.run.sharding`, minus those whose result the cache holds), checks them as always,
and hands the result to :meth:`Plan.finish`, which stores the new results in the cache and puts
the report together in input order. A shard's report carries a ``shard`` section (its place in
the whole input list, the fingerprints of its settings, the rule options, the durations) so that
``lsdae merge`` (:mod:`conformance.commands.merge`) can rebuild the report an unsharded run would
have written, and refuse shards that do not belong together.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import platform
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

from .. import __version__
from ..report.catalogue import Catalogue
from .options import EngineOptions
from ..report.findings import FmuReport, Report, evidence
from ..report.paths import schemas_dir
from .result_cache import ResultCache, content_hash
from .sharding import assign, input_names, input_size, inputs_digest, parse_shard

log = logging.getLogger(__name__)

#: Findings that say the check did not complete (a defect of ours, a slow machine): such a
#: result is not stored, the next run checks the FMU again.
NOT_CACHED = frozenset({"internal-error", "binary-timed-out"})


def catalogue_fingerprint(catalogue: Catalogue) -> str:
    """A digest of every rule as the run sees it (``rules/*.toml`` and the rule options)."""
    text = "\n".join(repr(rule) for rule in catalogue)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def settings_fingerprint(catalogue: Catalogue, options: EngineOptions) -> str:
    """A digest of what decides the findings apart from the FMU: lsdae's version, the
    catalogue with its options, and the engine options (but the probe workers at once, which
    decide how fast, not what)."""
    chosen = {k: v for k, v in dataclasses.asdict(options).items() if k != "probe_workers"}
    text = json.dumps({"version": __version__, "catalogue": catalogue_fingerprint(catalogue),
                       "options": chosen}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def platform_tag() -> str:
    """Where the probes ran: the same FMU's binary may behave (or exist) differently elsewhere."""
    return f"{sys.platform}-{platform.machine()}-py{sys.version_info[0]}.{sys.version_info[1]}"


#: The libraries whose behaviour reaches the findings (schemas, parsing, numbers, loading).
LIBRARIES = ("lxml", "fmpy", "numpy", "scipy", "scikit-sundae")


def code_fingerprint() -> str:
    """A digest of lsdae's own code and schemas and of the libraries' versions: a development
    checkout keeps its version number across edits, and a cached result must not outlive the
    code that produced it."""
    from importlib import metadata  # lazy: only a run with --cache-dir asks

    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]  # conformance/
    for root in (package, schemas_dir()):
        for file in sorted(root.rglob("*")):
            if file.suffix in (".py", ".xsd") and file.is_file():
                digest.update(file.relative_to(root).as_posix().encode() + b"\0")
                digest.update(file.read_bytes())
    for name in LIBRARIES:
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = "-"
        digest.update(f"{name}={version}\n".encode())
    return digest.hexdigest()


@dataclass
class Plan:
    """What one ``lsdae check`` run checks, what the cache already holds, and how to finish."""

    paths: tuple[str, ...]                   # every input, as given
    selected: tuple[int, ...]                # the positions this run is responsible for
    todo: list[str]                          # the paths to check (in position order)
    todo_positions: list[int]
    hits: dict[int, FmuReport]               # position -> cached result
    shard: tuple[int, int] | None = None
    settings: str = ""
    catalogue: str = ""
    rule_options: Mapping[str, Any] = field(default_factory=dict)
    names: list[str] = field(default_factory=list)
    sizes: list[int] = field(default_factory=list)
    cache: ResultCache | None = None
    hashes: dict[int, str] = field(default_factory=dict)   # position -> content hash

    def finish(self, checked: Report, durations: dict[str, float]) -> Report:
        """The run's report: cached and checked results in input order, the new results
        stored in the cache, and the shard section for a shard."""
        results = dict(self.hits)
        fmus = iter(checked.fmus)
        pending = next(fmus, None)
        not_checked: list[str] = []
        stored = failed = 0
        for position, path in zip(self.todo_positions, self.todo):
            if pending is None or pending.path != path:   # interrupted before this one
                not_checked.append(path)
                continue
            results[position] = pending
            pending = next(fmus, None)
            if self.cache is not None and self._storable(position, results[position]):
                if self.cache.put(self.hashes[position], results[position]):
                    stored += 1
                else:
                    failed += 1
        for position in self.hits:
            durations.setdefault(self.paths[position], 0.0)
        order = sorted(results)
        report = replace(checked, fmus=tuple(results[p] for p in order),
                         not_checked=tuple(not_checked))
        if self.cache is not None:
            _note(f"cache {self.cache.directory}: {len(self.hits)} of {len(self.selected)} "
                  f"FMU{'' if len(self.selected) == 1 else 's'} unchanged, not checked again; "
                  f"{stored} stored" + (f", {failed} could not be written" if failed else ""))
        if self.shard is None:
            return report
        index, count = self.shard
        return replace(report, shard=evidence(
            index=index, count=count, inputs=len(self.paths),
            inputs_digest=inputs_digest(self.names, self.sizes), settings=self.settings,
            catalogue=self.catalogue, rule_options=dict(self.rule_options),
            positions=order,
            durations=[round(durations.get(self.paths[p], 0.0), 3) for p in order]))

    def _storable(self, position: int, result: FmuReport) -> bool:
        if position not in self.hashes or any(f.name in NOT_CACHED for f in result.findings):
            return False
        # the FMU changed while it was checked: the result belongs to neither content
        return content_hash(self.paths[position]) == self.hashes[position]


def plan(paths: Sequence[str], *, shard: str | None, cache_dir: str | None,
         options: EngineOptions, catalogue: Catalogue,
         rule_options: Mapping[str, Any]) -> Plan:
    """Choose this run's FMUs and look them up in the cache.

    Raises ValueError for a ``--shard`` that is not I/N with 1 <= I <= N.
    """
    paths = tuple(paths)
    selected = tuple(range(len(paths)))
    chosen = parse_shard(shard) if shard is not None else None
    names: list[str] = []
    sizes: list[int] = []
    if chosen is not None:
        names, sizes = input_names(paths), [input_size(p) for p in paths]
        shard_of = assign(names, sizes, chosen[1])
        selected = tuple(i for i in selected if shard_of[i] == chosen[0])
        log.info("shard %d/%d: %d of %d FMUs", *chosen, len(selected), len(paths))
    settings = settings_fingerprint(catalogue, options)
    result = Plan(paths=paths, selected=selected, todo=[], todo_positions=[], hits={},
                  shard=chosen, settings=settings, catalogue=catalogue_fingerprint(catalogue),
                  rule_options=rule_options, names=names, sizes=sizes)
    if cache_dir is not None:
        result.cache = ResultCache(cache_dir, f"{settings} {code_fingerprint()} {platform_tag()}")
    for position in selected:
        path = paths[position]
        if result.cache is not None:
            started = time.perf_counter()
            digest = content_hash(path)
            hit = result.cache.get(digest) if digest is not None else None
            if digest is not None:
                result.hashes[position] = digest
            if hit is not None:
                result.hits[position] = replace(hit, path=path)
                log.info("cache hit: %s (%.3f s)", path, time.perf_counter() - started)
                continue
            log.info("cache miss: %s", path)
        result.todo.append(path)
        result.todo_positions.append(position)
    return result


def _note(text: str) -> None:
    print(f"lsdae: {text}", file=sys.stderr)
