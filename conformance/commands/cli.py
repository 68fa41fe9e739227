"""Command line: wiring only; each command returns the exit code.

The grammar is :mod:`conformance.commands.arguments`. The commands live beside this module:
:mod:`conformance.commands.check` (``check``, ``pre-commit``), :mod:`conformance.commands.explain`
(``rules``, ``explain``), :mod:`conformance.commands.simulate`, :mod:`conformance.commands.fix` and
:mod:`conformance.commands.merge`.
Only the command in hand is imported, after the arguments are read: ``lsdae --version`` loads
no engine, ``lsdae rules`` no XML library, ``lsdae check --no-probes`` no numerical library
(tests/unit/test_startup_imports.py holds each command to that).
"""
from __future__ import annotations

import argparse
import logging
import sys
from typing import Callable, Sequence

from .arguments import build_parser
from .exit_codes import EXIT_INTERRUPTED, EXIT_USAGE, UsageError

Command = Callable[[argparse.Namespace], int]


def _check(args: argparse.Namespace) -> int:
    from .check import cmd_check  # lazy: each command loads only what it needs
    return cmd_check(args)


def _precommit(args: argparse.Namespace) -> int:
    from .check import cmd_precommit  # lazy: each command loads only what it needs
    return cmd_precommit(args)


def _rules(args: argparse.Namespace) -> int:
    from .explain import cmd_rules  # lazy: each command loads only what it needs
    return cmd_rules(args)


def _explain(args: argparse.Namespace) -> int:
    from .explain import cmd_explain  # lazy: each command loads only what it needs
    return cmd_explain(args)


def _simulate(args: argparse.Namespace) -> int:
    from .simulate import run  # lazy: each command loads only what it needs
    return run(args)


def _fix(args: argparse.Namespace) -> int:
    from .fix import run  # lazy: each command loads only what it needs
    return run(args)


def _merge(args: argparse.Namespace) -> int:
    from .merge import run  # lazy: each command loads only what it needs
    return run(args)


COMMANDS: dict[str, Command] = {"check": _check, "pre-commit": _precommit, "rules": _rules,
                                "explain": _explain, "simulate": _simulate, "fix": _fix,
                                "merge": _merge}


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if getattr(args, "verbose", False) else logging.ERROR,
                        format="lsdae: %(levelname)s: %(message)s")
    try:
        return COMMANDS[args.command](args)
    except UsageError as exc:
        print(f"lsdae: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:  # outside a run of checks (those write what they finished)
        print("lsdae: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # never a bare traceback
        from ..report.catalogue import CatalogueError  # lazy: --version and --help need no catalogue
        if isinstance(exc, CatalogueError):
            print(f"lsdae: the rule catalogue is broken: {exc}", file=sys.stderr)
            return EXIT_USAGE
        logging.getLogger(__name__).debug("internal error", exc_info=True)
        print(f"lsdae: internal error: {type(exc).__name__}: {exc} (run with -v for details)",
              file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
