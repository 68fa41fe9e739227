"""The Chain scene at any size: its XML for N algebraic variables, and the FMU built for N.

``scenes/Chain/{modelDescription,fmi-ls-manifest}.xml`` are ``model_description(4)`` and
``manifest(4)`` (a test checks it); :func:`build_chain` compiles model.c with ``-DCHAIN_N=N``
and ``FMU_MAX_VARS`` (the capacity of the model's value-reference tables) raised to the next
power of two, then swaps the XML for N's in the archive. See model.c for the equations. The
model declares its Jacobian's pattern, so the framework's work arrays are O(N) heap arrays and
a derivative call costs O(N); the binary also implements fmi3GetVariableDependencies
(``providesPerElementDependencies="true"``).

    python -m scenes.Chain.chain 4 --write    # rewrite the committed XML
"""
from __future__ import annotations

import hashlib
import os
import sys
import zipfile
from pathlib import Path
from typing import Sequence

from scenes.build import MANIFEST_ENTRY, REPO_ROOT, build_scene

HERE = Path(__file__).resolve().parent
CACHE = REPO_ROOT / ".cache" / "chain"
DEFAULT_N = 4
MAX_N = 16384


def vr_w(i: int) -> int:
    return 10 + 2 * i


def vr_r(i: int) -> int:
    return 11 + 2 * i


def _deps(pairs: Sequence[tuple[int, str]]) -> str:
    pairs = sorted(pairs)
    return (f'dependencies="{" ".join(str(v) for v, _ in pairs)}" '
            f'dependenciesKind="{" ".join(k for _, k in pairs)}"')


_HEADER = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  fmiVersion="3.0"
  modelName="Chain"
  description="A chain of {n} algebraic variables, tridiagonal dg/dw (lsdae test scene)"
  instantiationToken="{{5a0c6d2e-3f41-4b7a-9d2e-51ab0c5e1004}}"
  generationTool="lsdae test scenes"
  variableNamingConvention="structured">

  <ModelExchange
    modelIdentifier="Chain"
    canGetAndSetFMUState="true"
    providesDirectionalDerivatives="true"
    providesAdjointDerivatives="true"
    providesPerElementDependencies="true"/>

  <DefaultExperiment startTime="0" stopTime="1"/>

  <ModelVariables>
"""

_FIXED_VARIABLES = (
    ("Float64", "time", 0, 'causality="independent" variability="continuous"'),
    ("Boolean", "dae", 1, 'causality="structuralParameter" variability="fixed" start="false" '
                          'description="enables the fmi-ls-dae DAE mode"'),
    ("Float64", "x", 2, 'causality="local" variability="continuous" initial="exact" start="1" '
                        'nominal="1"'),
    ("Float64", "der(x)", 3, 'causality="local" variability="continuous" '
                             'initial="calculated" derivative="2"'),
    ("Float64", "u", 4, 'causality="input" variability="continuous" start="0"'),
    ("Float64", "y", 5, 'causality="output" variability="continuous" initial="calculated"'),
)

_ON_X_AND_U = ((2, "dependent"), (4, "dependent"))
_CORE_STRUCTURE = (
    ("Output", 5), ("ContinuousStateDerivative", 3), ("InitialUnknown", 3),
    ("InitialUnknown", 5),
)


def _variable(type_: str, name: str, vr: int, attributes: str) -> str:
    return f'    <{type_} name="{name}" valueReference="{vr}" {attributes}/>'


def model_description(n: int) -> str:
    lines = [_HEADER.format(n=n).rstrip("\n")]
    lines += [_variable(*v) for v in _FIXED_VARIABLES]
    lines += [_variable("Float64", f"w[{i}]", vr_w(i), 'causality="local" variability="continuous" '
                        'initial="approx" start="0" nominal="1" description="algebraic variable"')
              for i in range(n)]
    lines += [_variable("Float64", f"r[{i}]", vr_r(i),
                        'causality="local" variability="continuous" description="residual"')
              for i in range(n)]
    lines += ["  </ModelVariables>", "", "  <ModelStructure>"]
    lines += [f'    <{kind} valueReference="{vr}" {_deps(_ON_X_AND_U)}/>'
              for kind, vr in _CORE_STRUCTURE]
    lines += ["  </ModelStructure>", "", "</fmiModelDescription>"]
    return "\n".join(lines) + "\n"


# The defects that drop x and u from the residuals and rebuild the last residual from the one
# before it (model.c): their manifest says so (``decoupled``).
DECOUPLING_DEFECTS = ("DEFECT_SINGULAR_GW", "DEFECT_ILL_CONDITIONED")


def residual_dependencies(i: int, n: int, *, decoupled: bool = False) -> list[tuple[int, str]]:
    if decoupled and i == n - 1:   # LAST_SCALE * link(w, n - 2) + LAST_EXTRA * w[n - 1]
        return [(vr_w(n - 3), "constant"), (vr_w(n - 2), "dependent"),
                (vr_w(n - 1), "constant")]
    deps = [(vr_w(i), "dependent")]
    if i > 0 or not decoupled:
        deps.append((vr_w(i - 1), "constant") if i > 0 else (2, "constant"))
    if i < n - 1 or not decoupled:
        deps.append((vr_w(i + 1), "constant") if i < n - 1 else (4, "constant"))
    return deps


def manifest(n: int, *, decoupled: bool = False) -> str:
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"',
        '  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"',
        '  fmi-ls:fmi-ls-version="1.0.0-alpha.1"',
        '  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">',
        '  <EnableDAEParameter valueReference="1"/>',
        "  <AlgebraicVariables>",
        *(f'    <AlgebraicVariable valueReference="{vr_w(i)}"/>' for i in range(n)),
        "  </AlgebraicVariables>",
        "  <ModelStructure>",
        f'    <Output valueReference="5" {_deps([(vr_w(n - 1), "constant")])}/>',
        (f'    <ContinuousStateDerivative valueReference="3" '
         f'{_deps([(2, "constant"), (vr_w(0), "constant")])}/>'),
        *(f'    <InitialUnknown valueReference="{vr}" {_deps(_ON_X_AND_U)}/>'
          for vr in (3, 5, *map(vr_w, range(n)))),
        *(f'    <Residual valueReference="{vr_r(i)}" '
          f'{_deps(residual_dependencies(i, n, decoupled=decoupled))}/>' for i in range(n)),
        "  </ModelStructure>",
        "</fmiDAEManifest>",
    ]
    return "\n".join(lines) + "\n"


def max_vars(n: int) -> int:
    """The framework's FMU_MAX_VARS for N: the next power of two, at least 8."""
    size = 8
    while size < n:
        size *= 2
    return size


def build_chain(n: int = DEFAULT_N, *, defines: Sequence[str] = ()) -> Path:
    """The Chain FMU with N algebraic variables (cached by content); with a defect of
    :data:`DECOUPLING_DEFECTS` its manifest lists the residuals' dependencies as changed."""
    if not 3 <= n <= MAX_N:
        raise ValueError(f"Chain needs 3 <= N <= {MAX_N}")
    base = build_scene("Chain", defines=[f"CHAIN_N={n}", f"FMU_MAX_VARS={max_vars(n)}",
                                         *defines])
    decoupled = any(d in DECOUPLING_DEFECTS for d in defines)
    if n == DEFAULT_N and not decoupled:
        return base
    md, mf = model_description(n).encode(), manifest(n, decoupled=decoupled).encode()
    key = hashlib.sha256(base.read_bytes() + md + mf).hexdigest()[:16]
    target = CACHE / f"Chain-{n}-{key}.fmu"
    if target.exists():
        return target
    CACHE.mkdir(parents=True, exist_ok=True)
    tmp = target.with_suffix(f".{os.getpid()}.tmp")
    with zipfile.ZipFile(base) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == "modelDescription.xml":
                data = md
            elif info.filename == MANIFEST_ENTRY:
                data = mf
            zout.writestr(info, data)
    os.replace(tmp, target)
    return target


def main(argv: Sequence[str]) -> int:
    n = int(argv[0]) if argv else DEFAULT_N
    if "--write" in argv:
        (HERE / "modelDescription.xml").write_text(model_description(n))
        (HERE / "fmi-ls-manifest.xml").write_text(manifest(n))
    else:
        print(build_chain(n))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
