"""Probes by rule code: explicit, no discovery magic (like ``conformance.checks.REGISTRY``).

``FAMILIES`` names each family module and the codes its own ``PROBES`` dict holds (the suite
checks that the two agree, and that no code is in two families). A family's module, with numpy
and everything it needs, is imported when one of its probes is first looked up: the parent
process plans the probe run from the codes alone and never loads a family; the worker loads the
ones it runs. A new family adds one line here. The runner emits the ``binary-*`` rules itself;
they have no function.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Iterator, Mapping

if TYPE_CHECKING:
    from .api import Probe

FAMILIES: dict[str, tuple[str, ...]] = {
    "handshake": ("DAE710", "DAE711", "DAE712"),
    "start_values": ("DAE713",),
    "basic": ("DAE720", "DAE721", "DAE722"),
    "evaluation": ("DAE723", "DAE724", "DAE725"),
    "derivatives": ("DAE740", "DAE741", "DAE742", "DAE743", "DAE744"),
    "dgdw": ("DAE745", "DAE746", "DAE747"),
    "simulation": ("DAE801", "DAE802", "DAE803", "DAE804", "DAE805", "DAE807"),
    "invariants": ("DAE806",),
    "importer_paths": ("DAE730", "DAE731"),
    "readback": ("DAE714", "DAE715", "DAE716", "DAE717"),
    "event_indicators": ("DAE732", "DAE733"),
    "events": ("DAE734", "DAE735", "DAE736", "DAE737"),
    "rare_calls": ("DAE738", "DAE739"),
    "initial_unknowns": ("DAE750", "DAE751", "DAE752"),
    "endurance": ("DAE760", "DAE761", "DAE762"),
}

#: code -> family module name
FAMILY_OF: dict[str, str] = {code: family for family, codes in FAMILIES.items()
                             for code in codes}

#: The endurance probes: run last, at the ``--endurance`` level, counted call by call.
ENDURANCE: frozenset[str] = frozenset(FAMILIES["endurance"])

#: Run first: what a fresh instance holds is read before any other instance was freed.
FIRST: frozenset[str] = frozenset(FAMILIES["start_values"])

#: Run after every other probe but the endurance ones: illegal calls, each on a fresh instance,
#: so that an FMU that crashes on one has already been probed for everything else.
LAST: frozenset[str] = frozenset(FAMILIES["rare_calls"])

#: The first cause (instances-not-independent): the findings of the rules its ``explains``
#: option lists are its consequences when they vanish with every instance alone
#: (``conformance.probes.stage``, ``runner.fold_consequences``).
FIRST_CAUSE = "DAE762"


class _Probes(Mapping[str, "Probe"]):
    """The probe functions by code, each family module imported on first use."""

    def __getitem__(self, code: str) -> "Probe":
        family = importlib.import_module(f"{__package__}.{FAMILY_OF[code]}")
        return family.PROBES[code]

    def __iter__(self) -> Iterator[str]:
        return iter(FAMILY_OF)

    def __len__(self) -> int:
        return len(FAMILY_OF)

    def __contains__(self, code: object) -> bool:
        return code in FAMILY_OF


PROBES: Mapping[str, "Probe"] = _Probes()
