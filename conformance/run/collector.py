"""Violations in, findings out: the rule, its severity, grouping and the source line.

One defect is one finding: after grouping, violations that name a shared cause are folded
(:mod:`.causes`), unless the options ask for every violation (``fold=False``: ``lsdae fix``,
whose fixers read each one).

:class:`Collector` keeps the violations of the rules that the
:class:`~conformance.run.options.RuleSelection` enables, groups repeated ones into one finding
with a count, and adds the source line each finding points at (:class:`LineCache`).
"""
from __future__ import annotations

import re
from dataclasses import replace
from typing import Iterable, Protocol

from ..report.catalogue import RuleSpec
from .causes import cause_keys, fold_indexed
from .options import RuleSelection
from ..report.findings import Finding, Location, Violation, evidence

GROUP_SHOWN = 5
START_TAG_LOOKBACK = 200  # lines searched upwards for the '<' that starts a tag


class Texts(Protocol):
    """The bytes of the files findings point into
    (:class:`conformance.run.source_texts.SourceTexts`, or a plain dict)."""

    def get(self, name: str, /) -> bytes | None: ...


class Collector:
    """Accumulates violations per rule and turns them into grouped, located findings."""

    def __init__(self, selection: RuleSelection, texts: Texts, threshold: int, *,
                 fold: bool = True):
        self.selection = selection
        self.texts = texts
        self.threshold = threshold
        self.fold = fold
        self.items: list[tuple[RuleSpec, Violation]] = []

    def add(self, rule: RuleSpec, violations: Iterable[Violation]) -> None:
        for v in violations:
            target = rule
            if v.rule and v.rule not in (rule.name, rule.code):
                target = self.selection.catalogue.get(v.rule) or rule
            if target.code in self.selection.enabled:
                self.items.append((target, v))

    def add_stage(self, violations: Iterable[Violation]) -> None:
        """Violations from loaders and stages, which name their rule themselves."""
        for v in violations:
            rule = self.selection.catalogue.get(v.rule or "")
            if rule is None:
                rule = self.selection.catalogue["internal-error"]
                v = replace(v, message=f"unknown rule {v.rule!r}: {v.message}")
            if rule.code in self.selection.enabled:
                self.items.append((rule, v))

    def emit(self, rule_name: str, violation: Violation) -> None:
        self.add_stage([replace(violation, rule=rule_name)])

    def findings(self) -> tuple[Finding, ...]:
        groups: dict[tuple[str, str | None, str, str], list[tuple[RuleSpec, Violation]]] = {}
        for rule, v in self.items:
            key = (rule.code, v.part, v.message, v.location.file or "")
            groups.setdefault(key, []).append((rule, v))
        units: list[tuple[RuleSpec, Violation]] = []
        counts: list[int] = []
        labels: list[str | None] = []
        for members in groups.values():
            if len(members) > self.threshold:
                rule, v, label = _grouped(members)
                units.append((rule, v))
                counts.append(len(members))
                labels.append(label)
            else:
                units.extend(members)
                counts.extend([1] * len(members))
                labels.extend([None] * len(members))
        out: list[Finding] = []
        kept = (fold_indexed(units, self.selection.severity_of, labels) if self.fold
                else list(enumerate(units)))
        for k, (rule, v) in kept:
            out.append(Finding(rule.code, rule.name, self.selection.severity_of(rule, v.part),
                               limit_said(rule, v.part, v.text), v.location, v.evidence,
                               v.subject, counts[k], part=v.part))
        lines = LineCache(self.texts)
        out = [replace(f, location=lines.with_snippet(f.location)) for f in out]
        return tuple(sorted(set(out), key=Finding.sort_key))


def _grouped(members: list[tuple[RuleSpec, Violation]]
             ) -> tuple[RuleSpec, Violation, str]:
    """Violations of one rule with one message as one: the count and the first few subjects in
    the message, the first's evidence; the cause keys of all (they fold as one); and how to
    name the group among the places of another finding."""
    members = sorted(members, key=lambda m: m[1].location.sort_key())
    rule, first = members[0]
    subjects = [v.subject for _, v in members if v.subject]
    shown = ", ".join(f"'{s}'" for s in subjects[:GROUP_SHOWN])
    more = ", …" if len(subjects) > GROUP_SHOWN else ""
    if "{subject}" in first.message:
        message = plural_subject(first.message, f"{len(members)} items ({shown}{more})")
    else:
        message = f"{first.message} ({len(members)} times)"
    ev = first.evidence + evidence(
        count=len(members), subjects=subjects[:20],
        lines=[v.location.line for _, v in members[:20]])
    keys = tuple(dict.fromkeys(k for _, v in members for k in cause_keys(v)))
    place = str(dict(first.evidence).get("place", ""))
    label = f"{len(members)} items ({shown}{more})" + (f", {place}" if place else "")
    return rule, replace(first, message=message, evidence=ev, subject=None,
                         cause=keys or None), label


def limit_said(rule: RuleSpec, part: str | None, message: str) -> str:
    """A finding whose basis is one of lsdae's own limits says so, and how to raise the limit
    (the basis's word), so that it never reads as a verdict on the FMU."""
    basis = rule.part(part)
    if basis is None or basis.kind != "limit":
        return message
    return f"{message} (lsdae's own limit, not a verdict on the FMU: {basis.word})"


# The verbs that follow "{subject}" in messages, in the third person singular, and their plural.
_PLURAL_VERBS = {"is": "are", "has": "have", "does": "do", "was": "were", "names": "name",
                 "uses": "use", "reads": "read", "takes": "take", "returns": "return",
                 "overlaps": "overlap", "lies": "lie", "gives": "give", "expands": "expand",
                 "differs": "differ", "depends": "depend", "lists": "list", "changes": "change"}
_VERB_AFTER_SUBJECT = re.compile(r"\{subject\}(\s+)([a-z]+)\b")


def plural_subject(message: str, phrase: str) -> str:
    """``message`` with ``{subject}`` replaced by a plural ``phrase`` ("3 items (...)") and the
    verb that follows it made to agree ("is declared" -> "are declared")."""
    def agree(match: re.Match[str]) -> str:
        verb = match.group(2)
        return "{subject}" + match.group(1) + _PLURAL_VERBS.get(verb, verb)

    return _VERB_AFTER_SUBJECT.sub(agree, message).replace("{subject}", phrase)


class LineCache:
    def __init__(self, texts: Texts):
        self.texts = texts
        self.lines: dict[str, list[bytes]] = {}

    def with_snippet(self, loc: Location) -> Location:
        """Add the source line; move a line that ends a multi-line start tag to its start.

        libxml2 records the line where a start tag *ends*. A raw '<' cannot occur in attribute
        text, so the nearest line at or above it that holds a '<' is where the tag begins.
        Done here, for the few lines findings point at, not for every element when parsing.
        """
        if not loc.file or not loc.line:
            return loc
        if loc.file not in self.lines:
            data = self.texts.get(loc.file)
            self.lines[loc.file] = data.split(b"\n") if data is not None else []
        lines = self.lines[loc.file]
        if loc.line > len(lines):
            return loc
        line = loc.line
        for above in range(line, max(line - START_TAG_LOOKBACK, 0), -1):
            if b"<" in lines[above - 1]:
                line = above
                break
        text = lines[line - 1].decode("utf-8", "replace").rstrip()
        return replace(loc, line=line, snippet=text[:240])

