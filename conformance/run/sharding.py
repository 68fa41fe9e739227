"""``lsdae check --shard I/N``: a deterministic, size-balanced share of the FMUs.

Every FMU lands in exactly one of the N shards, and the same inputs give the same split on every
machine: an FMU is known by its path relative to the common folder of all the inputs (so
``fmus/*.fmu`` and ``/home/runner/work/repo/fmus/*.fmu`` name the FMUs alike) and weighed by its
size in bytes (the ``.fmu`` file, or the files of an unpacked folder), neither of which depends on
the machine. The assignment is greedy longest-processing-time: the FMUs sorted by size (largest
first, then by name) each go to the shard with the least bytes so far (then the fewest FMUs,
then the lowest number). Which shard an FMU lands in does not depend on the order of the
arguments; the order of the arguments only decides the order of the merged report.
"""
from __future__ import annotations

import hashlib
import heapq
import json
import os
import re
import stat
from pathlib import Path
from typing import Sequence

_SHARD = re.compile(r"\s*(\d+)\s*/\s*(\d+)\s*")


def parse_shard(text: str) -> tuple[int, int]:
    """``"2/8"`` -> ``(2, 8)``; ValueError unless it reads I/N with 1 <= I <= N."""
    match = _SHARD.fullmatch(text)
    index, count = (int(match.group(1)), int(match.group(2))) if match else (0, 0)
    if not 1 <= index <= count:
        raise ValueError(f"--shard takes I/N with 1 <= I <= N (e.g. 2/8), not {text!r}")
    return index, count


def input_size(path: str | Path) -> int:
    """The bytes of an FMU: the ``.fmu`` file's size, or the total of the files in a folder
    (symbolic links are not followed); 0 for a path that cannot be read."""
    try:
        info = os.lstat(path)
    except OSError:
        return 0
    if not stat.S_ISDIR(info.st_mode):
        return info.st_size
    total = 0
    for folder, _dirs, files in os.walk(path, onerror=lambda _: None):
        for name in files:
            try:
                total += os.lstat(os.path.join(folder, name)).st_size
            except OSError:
                pass
    return total


def input_names(paths: Sequence[str]) -> list[str]:
    """Each path relative to the common folder of all the paths' parents, with ``/``."""
    if not paths:
        return []
    absolute = [os.path.abspath(p) for p in paths]
    try:
        root = os.path.commonpath([os.path.dirname(a) for a in absolute])
    except ValueError:  # paths on different drives (Windows): nothing in common
        return [a.replace(os.sep, "/") for a in absolute]
    return [os.path.relpath(a, root).replace(os.sep, "/") for a in absolute]


def assign(names: Sequence[str], sizes: Sequence[int], count: int) -> list[int]:
    """The shard (1 to ``count``) of each input: largest first, each to the lightest shard."""
    order = sorted(range(len(names)), key=lambda i: (-sizes[i], names[i], i))
    heap = [(0, 0, k) for k in range(1, count + 1)]   # (bytes, FMUs, shard)
    shard_of = [0] * len(names)
    for i in order:
        load, members, k = heapq.heappop(heap)
        shard_of[i] = k
        heapq.heappush(heap, (load + sizes[i], members + 1, k))
    return shard_of


def inputs_digest(names: Sequence[str], sizes: Sequence[int]) -> str:
    """A digest of the whole input list in order: shards of one run share it."""
    text = json.dumps([[n, s] for n, s in zip(names, sizes)], separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()
