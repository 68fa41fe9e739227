"""Imports in conformance/ flow one way (docs/architecture.md): no circle, nothing climbs back up.

The top level of the package is a dozen rooms (subpackages), stacked in ``FLOORS`` (top first),
the table of docs/architecture.md. Every module is on the floor of its room. An import may stay
in its room or go to a lower floor, never higher and never sideways to another room of the same
floor; the module graph as a whole has no circle; and an import inside a function carries a
comment on its line saying why it is lazy (or sits under ``if TYPE_CHECKING:``). Each room's
``__init__.py`` says what it holds and what it may import.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "conformance"

FLOORS: list[tuple[str, ...]] = [
    ("__main__",),
    ("commands",),
    ("run",),
    ("probes",),
    ("simulate", "fixes"),
    ("checks", "runtime", "intake", "reporters"),
    ("model",),
    ("report", "numerics", "__init__"),
]
ROOMS = sorted(room for floor in FLOORS for room in floor if not room.startswith("__"))


def _module(path: Path) -> str:
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    return ".".join(p for p in parts if p != "__init__") or "__init__"


def _floor(module: str) -> int:
    head = module.split(".")[0]
    for depth, group in enumerate(FLOORS):
        if module in group or head in group:
            return depth
    raise AssertionError(f"conformance.{module} is on no floor: add it to FLOORS")


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> list[str]:
    """The conformance modules a relative ``from ... import`` names (a package or its members)."""
    if node.level == 0:
        if not (node.module or "").startswith("conformance."):
            return []
        base = node.module.split(".", 1)[1]
    else:
        parts = module.split(".") if module != "__init__" else []
        keep = len(parts) - node.level + (1 if is_package else 0)
        base = ".".join(parts[:max(keep, 0)] + ([node.module] if node.module else []))
    names = [f"{base}.{a.name}" if base else a.name for a in node.names]
    return [n for n in names if _exists(n)] or ([base] if base else [])


def _exists(module: str) -> bool:
    path = PACKAGE.joinpath(*module.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _imports() -> dict[str, list[tuple[str, int, bool, str]]]:
    """module -> [(imported module, line, inside a function, source line)]."""
    out: dict[str, list[tuple[str, int, bool, str]]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _module(path)
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        tree = ast.parse(text)
        found = out.setdefault(module, [])
        for parent in ast.walk(tree):
            lazy = isinstance(parent, (ast.FunctionDef, ast.AsyncFunctionDef))
            typing_only = isinstance(parent, ast.If) and "TYPE_CHECKING" in ast.unparse(parent.test)
            for node in ast.iter_child_nodes(parent):
                if isinstance(node, ast.ImportFrom):
                    for target in _resolve(module, path.name == "__init__.py", node):
                        found.append((target, node.lineno, lazy and not typing_only,
                                      lines[node.lineno - 1]))
                elif isinstance(node, ast.Import) and lazy:
                    found.append(("", node.lineno, True, lines[node.lineno - 1]))
    return out


IMPORTS = _imports()


def test_every_module_is_on_a_floor():
    for module in IMPORTS:
        _floor(module)


@pytest.mark.parametrize("module", sorted(IMPORTS))
def test_imports_never_climb(module):
    climbs = [f"line {line}: conformance.{module} (floor {_floor(module)}) imports "
              f"conformance.{target} (floor {_floor(target)})"
              for target, line, _, _ in IMPORTS[module]
              if target and target.split(".")[0] != module.split(".")[0]
              and _floor(target) < _floor(module)]
    assert not climbs, "\n".join(climbs)


@pytest.mark.parametrize("module", sorted(IMPORTS))
def test_rooms_of_one_floor_do_not_import_each_other(module):
    room = module.split(".")[0]
    sideways = [f"line {line}: conformance.{module} imports conformance.{target}, another room "
                f"of floor {_floor(module)}"
                for target, line, _, _ in IMPORTS[module]
                if target and target.split(".")[0] != room and _floor(target) == _floor(module)]
    assert not sideways, "\n".join(sideways)


def test_the_top_level_names_a_dozen_rooms_and_nothing_else():
    entries = {p.name for p in PACKAGE.iterdir() if p.name != "__pycache__"}
    rooms = {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()}
    assert entries - rooms == {"__init__.py", "__main__.py"}, "a loose module at the top level"
    assert rooms == set(ROOMS) and len(rooms) <= 12


@pytest.mark.parametrize("room", ROOMS)
def test_each_room_says_what_it_holds_and_may_import(room):
    doc = ast.get_docstring(ast.parse((PACKAGE / room / "__init__.py").read_text("utf-8")))
    assert doc and len(doc.splitlines()) >= 3, f"conformance/{room}/__init__.py: no docstring"
    assert "import" in doc, f"conformance/{room}/__init__.py: say what the room may import"


@pytest.mark.parametrize("module", sorted(IMPORTS))
def test_function_local_imports_say_why(module):
    silent = [f"line {line}: {source.strip()}" for _, line, lazy, source in IMPORTS[module]
              if lazy and "#" not in source]
    assert not silent, f"conformance.{module}: a lazy import needs a reason on its line\n" + \
        "\n".join(silent)


def test_no_circle_of_imports():
    graph = {m: {t for t, *_ in edges if t and t != m and t in IMPORTS}
             for m, edges in IMPORTS.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            circle = visit(node)
            assert circle is None, "circle of imports: " + " -> ".join(circle)


# One floor down, the probe stage by family (docs/architecture.md): ``probes/machinery`` on top
# (the runner, the worker's stage, the registry, which loads the families by name alone), the
# families side by side and never importing each other, ``probes/instruments`` below them all.
PROBE_TOP, PROBE_BOTTOM = "machinery", "instruments"


def _probe_rooms() -> set[str]:
    return {p.name for p in (PACKAGE / "probes").iterdir() if (p / "__init__.py").is_file()}


def _probe_families() -> set[str]:
    from conformance.probes.machinery.registry import FAMILIES
    return set(FAMILIES)


def test_the_probe_rooms_are_the_registry_families_the_machinery_and_the_instruments():
    entries = {p.name for p in (PACKAGE / "probes").iterdir() if p.name != "__pycache__"}
    assert entries - _probe_rooms() == {"__init__.py"}, "a loose module in conformance/probes/"
    assert _probe_rooms() == _probe_families() | {PROBE_TOP, PROBE_BOTTOM}
    for room in _probe_rooms():
        doc = ast.get_docstring(ast.parse((PACKAGE / "probes" / room / "__init__.py")
                                          .read_text("utf-8")))
        assert doc and "import" in doc, f"conformance/probes/{room}/__init__.py: no docstring"


def _allowed(room: str) -> set[str]:
    if room == PROBE_TOP:
        return {PROBE_TOP, PROBE_BOTTOM}
    return {room, PROBE_BOTTOM}


@pytest.mark.parametrize("module", sorted(m for m in IMPORTS if m.startswith("probes.")))
def test_probe_families_import_only_themselves_and_the_instruments(module):
    room = module.split(".")[1]
    wrong = [f"line {line}: conformance.{module} imports conformance.{target}"
             for target, line, _, _ in IMPORTS[module]
             if target.startswith("probes.") and target.split(".")[1] not in _allowed(room)]
    assert not wrong, "\n".join(wrong)
