"""Value-reference lists as the C arrays and sets an instance needs, at every FMI call.

A model of 10,000 variables passes lists of 10,000 value references to most calls; turning one
into a C array is one pass through numpy (a Python-level loop of ctypes would take ten times
longer). The lists that live as long as the worker (the layout's tuples, the probes' rows and
columns, all tuples) are converted once and kept, by identity, in a small LRU cache; each call
still gets its own copy of the array, so nothing an FMU writes into one reaches the next call.
"""
from __future__ import annotations

import ctypes
from collections import OrderedDict
from typing import Any, Mapping, Sequence

import numpy as np

CACHED_FROM = 64     # tuples at least this long are converted once
CACHE_SIZE = 64      # tuples kept (the worker passes a few dozen distinct ones)

_ARRAYS: OrderedDict[int, tuple[tuple[int, ...], np.ndarray]] = OrderedDict()
_SETS: OrderedDict[int, tuple[tuple[int, ...], frozenset[int]]] = OrderedDict()


def _cached(cache: OrderedDict, values: tuple, make: Any) -> Any:
    key = id(values)
    hit = cache.get(key)
    if hit is not None and hit[0] is values:   # we hold ``values``: its id cannot be reused
        cache.move_to_end(key)
        return hit[1]
    made = make(values)
    cache[key] = (values, made)
    if len(cache) > CACHE_SIZE:
        cache.popitem(last=False)
    return made


def _uint32(values: Sequence[int]) -> np.ndarray:
    array = np.asarray(values, dtype=np.uint32)
    array.flags.writeable = False
    return array


def vr_array(values: Sequence[int]) -> Any:
    """A C array of value references (a fresh copy each call)."""
    try:
        array = (_cached(_ARRAYS, values, _uint32)
                 if isinstance(values, tuple) and len(values) >= CACHED_FROM
                 else np.asarray(values, dtype=np.uint32))
    except OverflowError:  # out of range (hostile XML): ctypes wraps it, as it always did
        return (ctypes.c_uint * len(values))(*values)
    return (ctypes.c_uint * len(array)).from_buffer_copy(array) if len(array) else \
        (ctypes.c_uint * 0)()


def double_array(values: Sequence[float] | np.ndarray) -> Any:
    """A C array of doubles (through numpy, as :func:`vr_array`)."""
    array = np.asarray(values, dtype=np.float64)
    return (ctypes.c_double * len(array)).from_buffer_copy(array) if len(array) else \
        (ctypes.c_double * 0)()


def as_set(vrs: Sequence[int]) -> frozenset[int]:
    """``vrs`` as a set (a tuple of the worker's, once)."""
    if isinstance(vrs, tuple) and len(vrs) >= CACHED_FROM:
        return _cached(_SETS, vrs, frozenset)
    return frozenset(vrs)


def all_in(vrs: Sequence[int], values: Mapping[int, float]) -> bool:
    return values.keys() >= as_set(vrs)


def present(vrs: Sequence[int], values: Mapping[int, float]) -> Sequence[int]:
    """``vrs`` that ``values`` holds, in order: ``vrs`` itself when it holds them all (one set
    operation, the usual case), else a list of those it holds."""
    keys = values.keys()
    return vrs if keys >= as_set(vrs) else [vr for vr in vrs if vr in keys]


def pick(values: Mapping[int, float], vrs: Sequence[int]) -> list[float]:
    """``values[vr]`` for each of ``vrs`` (a C-level loop: thousands per call)."""
    return list(map(values.__getitem__, vrs))
