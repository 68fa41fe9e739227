"""``lsdae rules`` and ``lsdae explain``: the catalogue as a list, or one rule in full."""
from __future__ import annotations

import argparse
import sys

from ..report.catalogue import Catalogue, RuleSpec, default_catalogue
from ..model.drafts.names import DRAFT_LABELS
from .exit_codes import EXIT_OK, UsageError
from .ruledocs import render_markdown, rule_home

FIX_MARKS = {"safe": "fix", "unsafe": "fix?", None: ""}   # the column of `lsdae rules`

def _rule_line(rule: RuleSpec) -> str:
    return (f"{rule.code}  {rule.name:<40} {rule.severity!s:<8} "
            f"{FIX_MARKS[rule.fix_kind]:<4} {rule.summary}")


def cmd_rules(args: argparse.Namespace) -> int:
    catalogue = default_catalogue()
    if args.format == "markdown":
        sys.stdout.write(render_markdown(catalogue))
    else:
        for rule in catalogue:
            print(_rule_line(rule))
    return EXIT_OK


def explain_text(rule: RuleSpec) -> str:
    drafts = ", ".join("all drafts" if d == "*" else DRAFT_LABELS.get(d, d) for d in rule.drafts)
    parts = [
        f"{rule.code} {rule.name}  ({rule.severity}, {rule.stage} stage)",
        "", rule.summary, "",
        f"Applies to: {drafts}",
        f"Spec:       {rule.spec}",
        f"Basis:      {rule.basis.describe()}, hence {rule.severity}" if rule.basis else
        f"Basis:      none recorded, {rule.severity}",
    ]
    parts += [f"  part {b.part} ({b.what}): {b.describe()}, hence {b.severity}"
              for b in rule.parts]
    parts.append(f"Fix:        {rule.fix or 'none: `lsdae fix` leaves this finding'}")
    if rule.aliases:
        parts.append(f"Aliases:    {', '.join(rule.aliases)}")
    home = rule_home(rule)
    if home:
        parts.append(f"Code:       {home}")
    parts += ["", "Why it matters:", _indent(rule.rationale), "", "Fails:", _indent(rule.bad),
              "", "Passes:", _indent(rule.good)]
    if rule.options:
        name, value = rule.options[0]
        parts += ["", "Options (defaults):"] + [f"    {k} = {_toml(v)}" for k, v in rule.options]
        parts += ["", "Set an option on the command line, or in pyproject.toml:",
                  f"    lsdae check --rule-option {rule.code}.{name}={_toml(value)} ...",
                  f"    [tool.lsdae.rule-options.{rule.code}]",
                  f"    {name} = {_toml(value)}"]
    return "\n".join(parts) + "\n"


def _toml(value: object) -> str:
    """A value as it is written in TOML (and on the command line)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _indent(text: str) -> str:
    return "\n".join(f"    {line}" if line else "" for line in text.splitlines())


def cmd_explain(args: argparse.Namespace, catalogue: Catalogue | None = None) -> int:
    catalogue = catalogue or default_catalogue()
    rule = catalogue.get(args.rule)
    if rule is None:
        raise UsageError(f"no rule {args.rule!r} (see `lsdae rules`)")
    sys.stdout.write(explain_text(rule))
    return EXIT_OK
