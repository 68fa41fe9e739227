"""The command line: argument parsing, configuration, each subcommand and its exit code.

``cli`` (wiring: reads the arguments, then imports only the command in hand), ``arguments`` (the
grammar of every command), ``config`` ([tool.lsdae] in pyproject.toml), ``exit_codes``; one
module per command: ``check`` (``check``, ``pre-commit``; ``precommit`` maps files to FMUs),
``explain`` (``rules``, ``explain``; ``ruledocs`` renders a rule), ``simulate``, ``fix``, ``merge``.

The top floor: it may import every room below (``run`` first); nothing imports it but
``conformance.__main__``.
"""
