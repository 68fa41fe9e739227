"""Probes by rule code: explicit, no discovery magic (like ``conformance.checks.REGISTRY``).

Each family module exposes its own ``PROBES`` dict; :func:`register` merges it here and refuses
a code registered twice. A new family adds two lines at the end of this file. The runner emits
the ``binary-*`` rules itself; they have no probe function.
"""
from __future__ import annotations

from typing import Mapping

from .api import Probe

PROBES: dict[str, Probe] = {}


def register(family: Mapping[str, Probe]) -> None:
    for code, probe in family.items():
        if code in PROBES:  # pragma: no cover - a defect caught by the tests
            raise RuntimeError(f"probe {code} registered twice")
        PROBES[code] = probe


from .handshake import PROBES as _handshake  # noqa: E402

register(_handshake)
from .basic import PROBES as _basic  # noqa: E402

register(_basic)
from .derivatives import PROBES as _derivatives  # noqa: E402

register(_derivatives)
from .simulation import PROBES as _simulation  # noqa: E402

register(_simulation)
