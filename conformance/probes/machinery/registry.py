"""Probes by rule code: explicit, no discovery magic (like ``conformance.checks.REGISTRY``).

``MODULES`` names each family package of ``conformance.probes``, its modules that hold probes,
and the codes each module's own ``PROBES`` dict holds (the suite checks that they agree, that
the packages are the families, and that no code is in two modules). A probe's module, with numpy
and everything it needs, is imported when the probe is first looked up: the parent process plans
the probe run from the codes alone and never loads a family; the worker loads the modules it
runs. A new family adds one package and one entry here. The runner emits the ``binary-*`` rules
itself; they have no function.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Iterator, Mapping

if TYPE_CHECKING:
    from ..instruments.api import Probe

#: family package -> its modules that hold probes -> their codes, in the order of the codes.
MODULES: dict[str, dict[str, tuple[str, ...]]] = {
    "evaluation": {"handshake": ("DAE710", "DAE711", "DAE712"),
                   "basic": ("DAE720", "DAE721", "DAE722"),
                   "failures": ("DAE723", "DAE724", "DAE725")},
    "readback": {"start_values": ("DAE713",),
                 "getters": ("DAE714", "DAE715", "DAE716", "DAE717"),
                 "importer_paths": ("DAE730", "DAE731"),
                 "rare_calls": ("DAE738", "DAE739")},
    "events": {"indicators": ("DAE732", "DAE733"),
               "updates": ("DAE734", "DAE735", "DAE736", "DAE737")},
    "derivatives": {"partials": ("DAE740", "DAE741", "DAE742", "DAE743", "DAE744"),
                    "dgdw": ("DAE745", "DAE746", "DAE747")},
    "initialization": {"unknowns": ("DAE750", "DAE751", "DAE752")},
    "endurance": {"sustained": ("DAE760", "DAE762"),
                  "memory": ("DAE761",)},
    "simulation": {"verdicts": ("DAE801", "DAE802", "DAE803", "DAE804", "DAE805", "DAE807"),
                   "invariants": ("DAE806",)},
}

#: family -> its codes
FAMILIES: dict[str, tuple[str, ...]] = {
    family: tuple(sorted(code for codes in modules.values() for code in codes))
    for family, modules in MODULES.items()}

#: code -> family package name
FAMILY_OF: dict[str, str] = {code: family for family, codes in FAMILIES.items()
                             for code in codes}

#: code -> the module that holds its probe, as ``family.module`` under ``conformance.probes``
MODULE_OF: dict[str, str] = {code: f"{family}.{module}" for family, modules in MODULES.items()
                             for module, codes in modules.items() for code in codes}

#: Where the families live: the package above the machinery.
FAMILY_PACKAGE = __package__.rsplit(".", 1)[0]

#: The endurance probes: run last, at the ``--endurance`` level, counted call by call.
ENDURANCE: frozenset[str] = frozenset(FAMILIES["endurance"])

#: Run first (start-value-not-applied): what a fresh instance holds is read before any other
#: instance was freed.
FIRST: frozenset[str] = frozenset({"DAE713"})

#: Run after every other probe but the endurance ones: illegal calls, each on a fresh instance,
#: so that an FMU that crashes on one has already been probed for everything else.
LAST: frozenset[str] = frozenset({"DAE738", "DAE739"})   # stop-time-refused, illegal-call-accepted

#: The first cause (instances-not-independent): the findings of the rules its ``explains``
#: option lists are its consequences when they vanish with every instance alone
#: (``conformance.probes.machinery.stage``, ``runner.fold_consequences``).
FIRST_CAUSE = "DAE762"


class _Probes(Mapping[str, "Probe"]):
    """The probe functions by code, each module imported on first use."""

    def __getitem__(self, code: str) -> "Probe":
        module = importlib.import_module(f"{FAMILY_PACKAGE}.{MODULE_OF[code]}")
        return module.PROBES[code]

    def __iter__(self) -> Iterator[str]:
        return iter(FAMILY_OF)

    def __len__(self) -> int:
        return len(FAMILY_OF)

    def __contains__(self, code: object) -> bool:
        return code in FAMILY_OF


PROBES: Mapping[str, "Probe"] = _Probes()
