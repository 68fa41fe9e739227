"""One fixture system: every fixture is in the index, used by a test, and found from tests.fixtures."""
from __future__ import annotations

import ast

import pytest

from tests.fixtures import index

#: Folders whose tests exercise the fixture machinery itself (the scene builder and framework).
MACHINERY = ("tests/scenes/", "tests/fixtures/")
PRIVATE = ("scenes", "tests.fixtures.")


def test_the_index_file_is_current():
    assert index.INDEX_FILE.read_text(encoding="utf-8") == index.render(*index.uses()), \
        "tests/fixtures/INDEX.md is stale: run `python -m tests.fixtures.index`"


def test_every_fixture_is_used_by_a_test():
    unused = index.unused()
    assert not unused, "fixtures no test uses: " + ", ".join(f"{f.kind} {f.id}" for f in unused)


def test_every_kind_has_fixtures():
    kinds = {f.kind for f in index.fixtures()}
    assert kinds == set(index.KINDS)


@pytest.mark.parametrize("path", index.test_modules(), ids=lambda p: p.name)
def test_tests_take_fixtures_from_the_index_only(path):
    where = path.relative_to(index.REPO).as_posix()
    if where.startswith(MACHINERY):
        return
    private = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        modules = ([node.module or ""] if isinstance(node, ast.ImportFrom)
                   else [a.name for a in node.names] if isinstance(node, ast.Import) else [])
        private += [f"line {node.lineno}: {m}" for m in modules
                    if m == "scenes" or m.startswith(PRIVATE)]
    assert not private, f"{where} imports fixtures around tests.fixtures:\n" + "\n".join(private)
