"""The command line's grammar (conformance/commands/arguments.py): every command's options, their
defaults, choices, metavars and help texts, compared with the saved grammar in
``expected/grammar.json``; and the argument types that refuse bad values.

The grammar is read from argparse's actions, not from ``--help`` output, whose layout changes
between Python versions. Set ``LSDAE_UPDATE_EXPECTED=1`` to rewrite the saved grammar after an
intended change, then read the diff.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any

import pytest

from conformance.commands.arguments import build_parser
from tests.clikit import lsdae

EXPECTED = Path(__file__).with_name("expected") / "grammar.json"


def _type(kind: Any) -> Any:
    """A type as a name; a closure (``_positive(float)``) with the types it closes over."""
    if kind is None:
        return None
    name = getattr(kind, "__name__", repr(kind))
    cells = [c.cell_contents for c in getattr(kind, "__closure__", None) or ()]
    closed = [c.__name__ for c in cells if isinstance(c, type)]
    return [name, *closed] if closed else name


def _plain(value: Any) -> Any:
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return f"Path({value})"
    return value


def _parser(parser: argparse.ArgumentParser) -> dict[str, Any]:
    groups = {id(a): i for i, g in enumerate(parser._mutually_exclusive_groups)
              for a in g._group_actions}
    actions, commands = [], {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            commands = {name: _parser(sub) for name, sub in action.choices.items()}
            helps = {c.dest: c.help for c in action._choices_actions}
            actions.append({"subcommands": list(action.choices), "dest": action.dest,
                            "required": action.required, "help": helps})
            continue
        actions.append({
            "options": action.option_strings, "dest": action.dest,
            "action": type(action).__name__, "nargs": action.nargs,
            "const": _plain(action.const), "default": _plain(action.default),
            "type": _type(action.type), "choices": _plain(action.choices),
            "required": action.required, "metavar": action.metavar, "help": action.help,
            "exclusive_group": groups.get(id(action)),
        })
    return {"prog": parser.prog, "description": parser.description, "epilog": parser.epilog,
            "formatter": parser.formatter_class.__name__,
            "defaults": {k: _plain(v) for k, v in sorted(parser._defaults.items())},
            "actions": actions, "commands": commands}


def test_the_grammar_is_the_saved_one():
    """Every option name, default, choice, metavar and help text of every command."""
    grammar = json.dumps(_parser(build_parser()), indent=1, ensure_ascii=False) + "\n"
    if os.environ.get("LSDAE_UPDATE_EXPECTED"):
        EXPECTED.parent.mkdir(parents=True, exist_ok=True)
        EXPECTED.write_text(grammar, encoding="utf-8")
        return
    assert EXPECTED.exists(), f"{EXPECTED} is missing: run with LSDAE_UPDATE_EXPECTED=1"
    saved = EXPECTED.read_text(encoding="utf-8")
    assert json.loads(grammar) == json.loads(saved), (
        "the command line's grammar differs from the saved one; if the change is intended, "
        "rerun with LSDAE_UPDATE_EXPECTED=1 and review the diff")


@pytest.mark.parametrize("command", ["check", "pre-commit", "rules", "explain", "simulate",
                                     "fix", "merge"])
def test_help_of_each_command_exits_zero_and_shows_its_options(command, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "2000")   # no wrapping (it breaks lines at hyphens)
    parser = build_parser()
    with pytest.raises(SystemExit) as done:
        parser.parse_args([command, "--help"])
    assert done.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for action in sub.choices[command]._actions:
        for option in action.option_strings:
            assert option in text
        if action.help and action.help != argparse.SUPPRESS:
            assert " ".join(action.help.split()) in text


def test_top_level_help_gives_the_exit_codes(capsys):
    with pytest.raises(SystemExit) as done:
        build_parser().parse_args(["--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: lsdae ")
    # RawDescriptionHelpFormatter: the epilog's lines as written
    assert ("exit codes:\n  0    no finding at the --fail-on severity (default: error) or above\n"
            in out)
    assert out.endswith("\n\n`lsdae COMMAND --help` describes each command.\n")


@pytest.mark.parametrize("argv, dest, value", [
    (["check", "x.fmu", "-j", "0"], "jobs", 0),
    (["check", "x.fmu", "-j", "3"], "jobs", 3),
    (["simulate", "x.fmu", "--stop-time", "2.5"], "stop_time", 2.5),
    (["simulate", "x.fmu", "--rtol", "1e-9"], "rtol", 1e-9),
    (["simulate", "x.fmu", "--output-points", "1"], "output_points", 1),
    (["simulate", "x.fmu", "--max-steps", "7"], "max_steps", 7),
    (["simulate", "x.fmu", "--time-limit", "0.25"], "time_limit", 0.25),
    (["simulate", "x.fmu", "--output-times", "0,0.5,2"], "output_times", (0.0, 0.5, 2.0)),
])
def test_typed_arguments_are_read(argv, dest, value):
    got = getattr(build_parser().parse_args(argv), dest)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize("argv, message", [
    (["check", "x.fmu", "-j", "-1"], "-j takes 0 (one per CPU) or more"),
    (["check", "x.fmu", "-j", "many"], "not a number of processes: 'many'"),
    (["simulate", "x.fmu", "--stop-time", "0"], "must be positive: '0'"),
    (["simulate", "x.fmu", "--stop-time=-1e-300"], "must be positive: '-1e-300'"),
    (["simulate", "x.fmu", "--rtol", "tight"], "not a number: 'tight'"),
    (["simulate", "x.fmu", "--output-points", "0"], "must be positive: '0'"),
    (["simulate", "x.fmu", "--output-points", "2.5"], "not a number: '2.5'"),
    (["simulate", "x.fmu", "--max-steps", "-3"], "must be positive: '-3'"),
])
def test_bad_typed_arguments_are_usage_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as done:
        build_parser().parse_args(argv)
    assert done.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err.splitlines()[-1].endswith(f": {message}")


def test_usage_error_of_main_is_one_line_on_stderr():
    code, out, err = lsdae("explain", "no-such-rule")
    assert (code, out, err) == (2, "", "lsdae: no rule 'no-such-rule' (see `lsdae rules`)\n")
