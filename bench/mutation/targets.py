"""What the campaign mutates: the targets, their line ranges, and which lines are live code.

A target is one C file (path relative to ``scenes/``), the scene built with its mutants (the
*host*), and optionally the framework functions it is restricted to. The scene models are
whole files (``<Scene>/model.c``; ``FourBar/fourbar.h`` holds the four-bar equations both
FourBar scenes share, built with FourBar). ``common/dae_model.h`` is not a target: it holds
declarations and the ``D_*`` addressing macros, no model code.

The framework (``common/fmi3_framework.c``) is split into groups of functions, each built with a
host that exercises them (events: EventDAE, the only scene with event indicators; the rest:
SimpleDAE, which has inputs, outputs and a tunable switch, so Reconfiguration Mode and input
derivatives are reachable). Left out, with the reason: logging and the discard plumbing (no
behaviour of the model), memory set-up and the value-reference index (``grab``, ``allocate``,
``build_index``, ``lookup``: every call goes through them, a mutant there breaks everything
at once), the sparse pattern and per-element dependencies (``load_pattern``,
``build_structure``, ``dependencies``: only Chain declares a pattern), the FMU state and the
unsupported interface types (not modes, events, derivatives, variables or reset).

Live lines: a line counts only if replacing it with garbage makes the file fail to compile
(``cc -fsyntax-only`` with the build's flags). That drops comments, blank lines, the
``#ifdef DEFECT_...`` variants that are not compiled, and unused macros, whatever their
shape. Conditional-compilation and ``#include`` directives are never mutated (they choose
code, they are not code); ``#define`` lines are (FourBar's constants are defines).
"""
from __future__ import annotations

import hashlib
import json
import re
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from scenes.build import SCENES_DIR, compiler, fmi_headers_dir, scene_names

FRAMEWORK = "common/fmi3_framework.c"
FRAMEWORK_GROUPS: dict[str, tuple[str, tuple[str, ...]]] = {
    # group: (host scene, functions)
    "modes": ("SimpleDAE", (
        "fmu_computes_w", "fmi3EnterInitializationMode", "fmi3ExitInitializationMode",
        "fmi3EnterEventMode", "fmi3Terminate", "fmi3EnterConfigurationMode",
        "fmi3ExitConfigurationMode", "fmi3GetBoolean", "fmi3SetBoolean",
        "fmi3EnterContinuousTimeMode", "fmi3CompletedIntegratorStep", "fmi3SetTime",
        "fmi3SetContinuousStates")),
    "reset": ("SimpleDAE", ("reset_data", "changed", "fmi3Reset")),
    "evaluation": ("SimpleDAE", (
        "eval_at", "eval_solved", "band_factor", "band_solve", "factor_gw", "norm2",
        "solve_algebraic", "update", "fmi3GetContinuousStateDerivatives",
        "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates",
        "fmi3GetNumberOfContinuousStates")),
    "derivatives": ("SimpleDAE", (
        "partials_at", "band_solve_transposed", "unknown_row", "known_col", "jac_times",
        "jac_transposed_times", "directional", "adjoint", "partial_derivatives",
        "fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative")),
    "variables": ("SimpleDAE", ("slot", "fmi3GetFloat64", "may_set", "fmi3SetFloat64")),
    "events": ("EventDAE", (
        "indicators_at", "fmi3UpdateDiscreteStates", "fmi3GetEventIndicators",
        "fmi3GetNumberOfEventIndicators")),
}
_DIRECTIVE = re.compile(r"^\s*#\s*(if|ifdef|ifndef|elif|else|endif|include|error|pragma)\b")
_CACHE = Path(__file__).resolve().parents[2] / ".cache" / "mutation"
LIVE_VERSION = 1   # bump when the liveness test changes (the cache is keyed on it)
IMPLICIT = "implicit declaration of function"
IMPLICIT_REASON = "implicit declaration of a function (a C99 constraint violation; it links " \
    "only because a shared library may leave symbols undefined, and fails to load)"


@dataclass(frozen=True)
class Target:
    name: str                   # "SimpleDAE/model.c", "framework:events"
    source: str                 # the file, relative to scenes/
    host: str                   # the scene built with the mutant
    functions: tuple[str, ...] = ()   # framework functions (empty: the whole file)

    def text(self) -> str:
        return (SCENES_DIR / self.source).read_text()


def all_targets() -> list[Target]:
    """Every scene's model.c, FourBar/fourbar.h, then the framework's groups."""
    out = [Target(f"{name}/model.c", f"{name}/model.c", name) for name in scene_names()]
    out.insert([t.host for t in out].index("FourBar") + 1,
               Target("FourBar/fourbar.h", "FourBar/fourbar.h", "FourBar"))
    out += [Target(f"framework:{group}", FRAMEWORK, host, functions)
            for group, (host, functions) in FRAMEWORK_GROUPS.items()]
    return out


def function_lines(text: str, name: str) -> range:
    """The lines (1-based) of the definition of C function ``name``: from the line that
    starts it at column 0 to the brace that closes its body (braces in strings and comments
    are not expected in the framework)."""
    lines = text.splitlines()
    pattern = re.compile(rf"^[A-Za-z].*\b{re.escape(name)}\(")
    for i, line in enumerate(lines):
        if pattern.match(line) and not line.rstrip().endswith(";"):
            depth, opened = 0, False
            for j in range(i, len(lines)):
                depth += lines[j].count("{") - lines[j].count("}")
                opened = opened or "{" in lines[j]
                if opened and depth == 0:
                    return range(i + 1, j + 2)
    raise ValueError(f"no definition of {name}() found")


def code_lines(text: str) -> set[int]:
    """The lines (1-based) with something besides comments and blanks (the sources have no
    comment markers inside string literals)."""
    without = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group().count("\n"), text, flags=re.S)
    without = re.sub(r"//[^\n]*", "", without)
    return {n for n, line in enumerate(without.splitlines(), start=1) if line.strip()}


def describe(targets: list[Target]) -> list[dict[str, object]]:
    """What each target covers, for the report: file, host, and for the framework groups
    each function with its first and last line."""
    out: list[dict[str, object]] = []
    for t in targets:
        text = t.text()
        out.append({"target": t.name, "source": t.source, "host": t.host,
                    "functions": [[f, function_lines(text, f)[0], function_lines(text, f)[-1]]
                                  for f in t.functions]})
    return out


def candidate_lines(target: Target) -> list[int]:
    """The target's lines with code, before the liveness test (directives never)."""
    text = target.text()
    lines = text.splitlines()
    if target.functions:
        numbers = sorted({n for f in target.functions for n in function_lines(text, f)})
    else:
        numbers = list(range(1, len(lines) + 1))
    code = code_lines(text)
    return [n for n in numbers if n in code and not _DIRECTIVE.match(lines[n - 1])]


def _syntax_errors(target: Target, text: str, work: Path) -> str:
    """The compiler's first error when the host's build has ``text`` as the target (syntax and
    types only, ``cc -fsyntax-only``), or "" when it compiles."""
    src = work / target.source
    src.write_text(text)
    scene = work / target.host
    files = [work / FRAMEWORK] if target.source == FRAMEWORK else sorted(scene.glob("*.c"))
    cmd = [compiler(), "-std=c99", "-fsyntax-only", f"-I{work / 'common'}", f"-I{scene}",
           f"-I{fmi_headers_dir()}", '-DFMU_INSTANTIATION_TOKEN="mutation"', *map(str, files)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if IMPLICIT in proc.stderr:
        return IMPLICIT_REASON
    if proc.returncode == 0:
        return ""
    errors = [ln.split("error:", 1)[1].strip() for ln in proc.stderr.splitlines() if "error:" in ln]
    return errors[0] if errors else "compile error"


def _stage(target: Target, dest: Path) -> None:
    for folder in ("common", target.host):
        (dest / folder).mkdir(parents=True, exist_ok=True)
        for path in (SCENES_DIR / folder).iterdir():
            if path.suffix in (".c", ".h"):
                (dest / folder / path.name).write_bytes(path.read_bytes())


def syntax_errors(target: Target, text: str) -> str:
    """:func:`_syntax_errors` in a staged copy of the sources: a fast test for a stillborn
    mutant before the full build (tens of milliseconds against seconds)."""
    with tempfile.TemporaryDirectory(prefix="lsdae-syntax-") as tmp:
        _stage(target, Path(tmp))
        return _syntax_errors(target, text, Path(tmp))


def live_lines(target: Target, *, jobs: int = 2) -> list[int]:
    """The candidate lines whose replacement by garbage breaks the build (cached by content)."""
    text = target.text()
    candidates = candidate_lines(target)
    key = hashlib.sha256(json.dumps([target.source, target.host, candidates, text, compiler(),
                                     LIVE_VERSION]).encode()).hexdigest()[:20]
    cache = _CACHE / f"live-{key}.json"
    if cache.is_file():
        return json.loads(cache.read_text())
    lines = text.splitlines(keepends=True)

    def dead(number: int) -> bool:
        garbage = "@ lsdae mutation garbage @" + \
            (" \\" if lines[number - 1].rstrip().endswith("\\") else "") + "\n"
        mutated = "".join(lines[:number - 1]) + garbage + "".join(lines[number:])
        return syntax_errors(target, mutated) in ("", IMPLICIT_REASON)

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        verdicts = list(pool.map(dead, candidates))
    live = [n for n, is_dead in zip(candidates, verdicts) if not is_dead]
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_text(json.dumps(live))
    return live
