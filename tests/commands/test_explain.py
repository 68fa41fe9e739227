"""``lsdae rules`` and ``lsdae explain`` (conformance/commands/explain.py, ruledocs.py): what a
user reads about a rule, to the character."""
from __future__ import annotations


import pytest

from conformance.commands import explain
from conformance.commands.ruledocs import render_markdown
from conformance.report.catalogue import Basis, Catalogue, RuleSpec, default_catalogue
from conformance.report.findings import Severity
from tests.clikit import lsdae
from tests.repokit import repo_file

DOCS = repo_file("docs/rules.md")

RULE = RuleSpec(
    code="DAE999", name="made-up-rule", severity=Severity.WARNING, stage="static",
    drafts=("alpha1", "mine"), needs=(), spec="fmi-ls-dae 1.0.0-alpha.1, 2.3",
    summary="A made-up rule.", rationale="First line.\n\nThird line.", bad="<bad/>",
    good="<good/>", aliases=("old-name", "older-name"),
    options=(("rtol", 1e-4), ("strict", False), ("label", 'say "hi" \\ there'),
             ("codes", ("DAE1", 2))),
    fix="none: nothing can be derived",
    basis=Basis("should", "fmi-ls-dae 1.0.0-alpha.1", "2.3", "SHOULD"),
    parts=(Basis("must", "FMI 3.0.2", "4.1", "shall", part="size", what="the size"),))

EXPLAINED = """\
DAE999 made-up-rule  (warning, static stage)

A made-up rule.

Applies to: fmi-ls-dae 1.0.0-alpha.1 (September 2026, the 2026 paper), mine
Spec:       fmi-ls-dae 1.0.0-alpha.1, 2.3
Basis:      should (the text recommends it); fmi-ls-dae 1.0.0-alpha.1, 2.3: \u201cSHOULD\u201d, \
hence warning
  part size (the size): must (the text requires it); FMI 3.0.2, 4.1: \u201cshall\u201d, hence error
Fix:        none: nothing can be derived
Aliases:    old-name, older-name

Why it matters:
    First line.

    Third line.

Fails:
    <bad/>

Passes:
    <good/>

Options (defaults):
    rtol = 0.0001
    strict = false
    label = "say \\"hi\\" \\\\ there"
    codes = ["DAE1", 2]

Set an option on the command line, or in pyproject.toml:
    lsdae check --rule-option DAE999.rtol=0.0001 ...
    [tool.lsdae.rule-options.DAE999]
    rtol = 0.0001
"""


def test_explain_text_of_a_rule_in_full():
    assert explain.explain_text(RULE) == EXPLAINED


def test_explain_text_without_basis_fix_aliases_or_options():
    bare = RuleSpec("DAE998", "bare-rule", Severity.INFO, "probe", ("*",), (), "FMI 3.0.2",
                    "Bare.", "Why.", "b", "g")
    assert explain.explain_text(bare) == (
        "DAE998 bare-rule  (info, probe stage)\n\nBare.\n\nApplies to: all drafts\n"
        "Spec:       FMI 3.0.2\nBasis:      none recorded, info\n"
        "Fix:        none: `lsdae fix` leaves this finding\n\nWhy it matters:\n    Why.\n\n"
        "Fails:\n    b\n\nPasses:\n    g\n")


@pytest.mark.parametrize("value, text", [
    (True, "true"), (False, "false"), ("plain", '"plain"'), ('a"b\\c', '"a\\"b\\\\c"'),
    ([1, "x", False], '[1, "x", false]'), ((), "[]"), (0.5, "0.5"), (3, "3"),
])
def test_toml_values(value, text):
    assert explain._toml(value) == text


def test_explain_command_prints_the_text(capsys):
    catalogue = Catalogue([RULE])
    args = type("Args", (), {"rule": "made-up-rule"})()
    assert explain.cmd_explain(args, catalogue) == 0
    assert capsys.readouterr().out == EXPLAINED


def test_rules_lists_one_line_per_rule():
    code, out, err = lsdae("rules")
    catalogue = default_catalogue()
    assert (code, err) == (0, "")
    lines = out.splitlines()
    assert len(lines) == len(list(catalogue))
    rule = catalogue.get("DAE091")
    assert lines[[r.code for r in catalogue].index("DAE091")] == (
        f"DAE091  {rule.name:<40} {rule.severity!s:<8} {'':<4} {rule.summary}")


def test_rules_markdown_is_docs_rules_md():
    """``lsdae rules --format markdown`` writes docs/rules.md (which is generated from it)."""
    code, out, err = lsdae("rules", "--format", "markdown")
    assert (code, err) == (0, "")
    assert out == DOCS.read_text(encoding="utf-8") == render_markdown(default_catalogue())
