"""Files of the repository that live outside the package, found from wherever the tests run."""
from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent


def repo_file(relative: str) -> Path:
    """The file at ``relative`` from the repository's root (``docs/rules.md``,
    ``.pre-commit-hooks.yaml``): the nearest folder above the tests that holds it. The tests also
    run from mutmut's copy of the tree (build/mutation-self/<package>/mutants/,
    docs/mutation-self.md), which has neither docs/ nor the hook manifest of its own."""
    for parent in HERE.parents:
        if (parent / relative).is_file():
            return parent / relative
    raise FileNotFoundError(f"{relative} above {HERE}")
