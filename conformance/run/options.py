"""What the user chose, and the rule set that follows from it.

:class:`EngineOptions` holds the choices; :class:`RuleSelection` resolves them against the
catalogue: which rules are on, and at which severity.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..report.catalogue import Catalogue, RuleSpec
from ..report.findings import Severity


@dataclass(frozen=True)
class EngineOptions:
    """What the user chose: rule selection, severity overrides, draft, probes."""

    select: tuple[str, ...] = ()
    ignore: tuple[str, ...] = ()
    severity: tuple[tuple[str, str], ...] = ()
    draft: str = "auto"
    probes: bool = True
    probes_only: bool = False
    seed: int = 0
    group_threshold: int = 3
    fold: bool = True                 # one finding per cause (``conformance.run.causes``)
    endurance: str = "quick"          # the endurance probes: "off", "quick" or "long"
    probe_workers: int = 0            # probe workers at once, 1 or 2; 0: by the FMU's size


class RuleSelection:
    """The effective rule set: which codes are on, and at which severity."""

    def __init__(self, catalogue: Catalogue, options: EngineOptions):
        self.catalogue = catalogue
        selected = {r.code for r in catalogue}
        if options.select:
            selected = {r.code for p in options.select for r in self._resolve(p)}
        for pattern in options.ignore:
            selected -= {r.code for r in self._resolve(pattern)}
        self.enabled = frozenset(selected)
        self.severity: dict[str, Severity] = {r.code: r.severity for r in catalogue}
        self.overridden: set[str] = set()
        for pattern, level in options.severity:
            for rule in self._resolve(pattern):
                self.severity[rule.code] = Severity.parse(level)
                self.overridden.add(rule.code)

    def severity_of(self, rule: RuleSpec, part: str | None) -> Severity:
        """A violation's severity: the user's for the rule when they set one, else the basis of
        its sub-check (``part``), else the rule's."""
        if part is None or rule.code in self.overridden:
            return self.severity[rule.code]
        return rule.severity_of(part)

    def _resolve(self, pattern: str) -> list[RuleSpec]:
        rules = self.catalogue.matching(pattern.strip())
        if not rules:
            raise ValueError(f"no rule matches {pattern!r} (see `lsdae rules`)")
        return rules
