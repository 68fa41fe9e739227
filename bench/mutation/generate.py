"""The mutants: universalmutator's ``mutate`` on each target, restricted to its live lines, and
a seeded sample of them.

``mutate FILE c --noCheck --mutantDir DIR --lines LINES`` writes one full copy of the file per
mutant (``--noCheck``: we compile them ourselves, through ``scenes/build.py``, so a mutant that
does not compile is counted as stillborn rather than silently dropped). Each copy is compared
with the original to recover the mutated line (a rule may insert a line, e.g. ``break;``, so
the replacement can span two). Mutants that change only a comment or whitespace are dropped,
and identical ones are kept once. The list is sorted by (line, text), so the seeded sample
depends only on the file, the universalmutator version and the seed.

A mutant's id is stable while the file's lines do not move: ``<source>:<line>:<hash>``, the
hash being the first 10 hex digits of the SHA-1 of the mutated text. ``verdicts.toml`` is
keyed by it.
"""
from __future__ import annotations

import hashlib
import json
import random
import re
import subprocess
import sys
import tempfile
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any, Sequence

from .targets import _CACHE, Target, live_lines

_COMMENT = re.compile(r"/\*.*?\*/|//.*$")
GENERATE_VERSION = 1   # bump when the parsing or filtering of mutants changes (cache key)


@dataclass(frozen=True)
class Mutant:
    target: str
    source: str
    host: str
    line: int
    original: str
    mutated: str   # the text that replaces the line (without its newline; may hold one)

    @property
    def id(self) -> str:
        digest = hashlib.sha1(self.mutated.encode()).hexdigest()[:10]
        return f"{self.source}:{self.line}:{digest}"

    def apply(self, text: str) -> str:
        """``text`` (the target file) with this mutant's line replaced."""
        lines = text.splitlines(keepends=True)
        if lines[self.line - 1].rstrip("\n") != self.original:
            raise ValueError(f"{self.id}: line {self.line} is no longer {self.original!r}")
        lines[self.line - 1] = self.mutated + "\n"
        return "".join(lines)

    def to_json(self) -> dict[str, Any]:
        return {"id": self.id, **asdict(self)}


def universalmutator_version() -> str:
    try:
        return metadata.version("universalmutator")
    except metadata.PackageNotFoundError:
        return "not installed"


def _code(text: str) -> str:
    return re.sub(r"\s+", "", _COMMENT.sub("", text))


def _mutate_command() -> list[str]:
    """The ``mutate`` console script of the environment this interpreter runs in."""
    script = Path(sys.executable).parent / "mutate"
    return [str(script)] if script.is_file() else ["mutate"]


def _parse(target: Target, original: list[str], mutant_lines: list[str]) -> Mutant | None:
    """The one-line change from ``original`` to ``mutant_lines`` (None if nothing changed).

    A rule that inserts a line (``break;``, ``continue;``) keeps the mutated line and adds the
    new one after it: the mutant is then that line replaced by both."""
    extra = len(mutant_lines) - len(original)
    first = next((i for i, (a, b) in enumerate(zip(original, mutant_lines)) if a != b),
                 len(original))
    if first == len(original) and extra <= 0:
        return None
    start = first - 1 if extra > 0 else first
    replaced = "".join(mutant_lines[start:start + 1 + max(extra, 0)]).rstrip("\n")
    return Mutant(target.name, target.source, target.host, start + 1,
                  original[start].rstrip("\n"), replaced)


def generate(target: Target, *, jobs: int = 2) -> list[Mutant]:
    """Every distinct mutant universalmutator makes on the target's live lines (cached)."""
    text = target.text()
    lines = live_lines(target, jobs=jobs)
    key = hashlib.sha256(json.dumps([target.name, text, lines, universalmutator_version(),
                                     GENERATE_VERSION]).encode()).hexdigest()[:20]
    cache = _CACHE / f"mutants-{key}.json"
    if cache.is_file():
        return [Mutant(**{k: v for k, v in m.items() if k != "id"})
                for m in json.loads(cache.read_text())]
    original = text.splitlines(keepends=True)
    found: dict[tuple[int, str], Mutant] = {}
    with tempfile.TemporaryDirectory(prefix="lsdae-mutate-") as tmp:
        work = Path(tmp)
        source = work / Path(target.source).name
        source.write_text(text)
        (work / "lines.txt").write_text(" ".join(map(str, lines)))
        cmd = [*_mutate_command(), source.name, "c", "--noCheck", "--mutantDir", "out",
               "--lines", "lines.txt"]
        proc = subprocess.run(cmd, cwd=work, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"mutate failed on {target.source}:\n{proc.stdout[-2000:]}"
                               f"{proc.stderr[-2000:]}")
        for path in sorted((work / "out").iterdir()):
            mutant = _parse(target, original, path.read_text().splitlines(keepends=True))
            if mutant is None or _code(mutant.mutated) == _code(mutant.original):
                continue
            found.setdefault((mutant.line, mutant.mutated), mutant)
    mutants = [found[k] for k in sorted(found)]
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_text(json.dumps([m.to_json() for m in mutants]))
    return mutants


def sample(mutants: Sequence[Mutant], count: int, *, seed: int, target: str) -> list[Mutant]:
    """``count`` of ``mutants`` (all if fewer), chosen by a generator seeded with the campaign's
    seed and the target's name, in line order."""
    if count >= len(mutants):
        return list(mutants)
    rng = random.Random(f"{seed}/{target}")
    return [mutants[i] for i in sorted(rng.sample(range(len(mutants)), count))]
