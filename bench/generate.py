"""Generator of large, valid, chain-structured DAE FMUs (XML only) for benchmarks and tests.

The FMU holds ``modelDescription.xml`` (FMI 3.0, Model Exchange) and a 1.0.0-alpha.1 fmi-ls-dae
manifest at ``extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml``; there is no binary. The
model is a semi-explicit index-1 DAE made of ``m`` blocks, ``k = 1..m``::

    der(x[k]) = w[k] - 2*x[k]               (+ f for k = m)
    0 = r[k]  = w[k] - 0.5*w[k-1] - x[k]    (w[0] is the input u)
    yFirst = w[1],  yLast = x[m]

so ``dg/dw`` is lower bidiagonal with a unit diagonal: the residual/algebraic bipartite graph
has a perfect matching. Variables, in value-reference order:

====== ============================ =============================================
vr     variable                     kind
====== ============================ =============================================
0      ``time``                     independent
1      ``enableDAEMode``            Boolean structuralParameter, fixed, false
2, 3   ``chain.u``, ``chain.f``     continuous inputs
4, 5   ``chain.yFirst``, ``yLast``  continuous outputs (initial calculated)
6+4j   ``chain.x[k]``               state, initial exact     (j = k - 1)
7+4j   ``der(chain.x[k])``          its derivative
8+4j   ``chain.w[k]``               algebraic, initial approx
9+4j   ``chain.r[k]``               residual
====== ============================ =============================================

The modelDescription ModelStructure describes ODE mode, where ``w`` is solved away and
``der(x[k])`` depends on ``x[1..k]`` and ``u``; to keep the file linear in ``m`` the derivatives
carry no ``dependencies`` attribute ("depends on all knowns"). The manifest lists the DAE-mode
structure with exact dependencies on states, inputs and algebraic variables.

Everything is built with plain string joins, so 100k variables take well under a second.
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
import uuid
import zipfile
from pathlib import Path

logger = logging.getLogger(__name__)

__all__ = [
    "MANIFEST_PATH",
    "NAMINGS",
    "blocks_for",
    "generate",
    "model_description_xml",
    "manifest_xml",
    "total_variables",
]

MANIFEST_PATH = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
NAMINGS = ("structured", "flat")

VR_TIME = 0
VR_ENABLE = 1
VR_U = 2
VR_F = 3
VR_Y_FIRST = 4
VR_Y_LAST = 5
FIRST_BLOCK_VR = 6
N_FIXED = FIRST_BLOCK_VR  # variables outside the blocks
BLOCK_SIZE = 4

_LS_NS = "http://fmi-standard.org/fmi-ls-manifest"
# Fixed ZIP timestamp so that the same arguments give byte-identical archives.
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def blocks_for(n_vars: int) -> int:
    """Number of blocks ``m`` (at least 1) with ``total_variables(m)`` nearest to ``n_vars``."""
    return max(1, (n_vars - N_FIXED + BLOCK_SIZE // 2) // BLOCK_SIZE)


def total_variables(m: int) -> int:
    """Number of variables in a model with ``m`` blocks."""
    return N_FIXED + BLOCK_SIZE * m


def _vr(m_index: int, offset: int) -> int:
    """Value reference of a block variable; ``m_index`` is 0-based, offset 0=x 1=der 2=w 3=r."""
    return FIRST_BLOCK_VR + BLOCK_SIZE * m_index + offset


def _names(naming: str) -> dict[str, str]:
    """Name templates (``{k}`` is the 1-based block index) for the naming convention."""
    if naming == "structured":
        return {
            "u": "chain.u", "f": "chain.f", "yFirst": "chain.yFirst", "yLast": "chain.yLast",
            "x": "chain.x[{k}]", "der": "der(chain.x[{k}])", "w": "chain.w[{k}]",
            "r": "chain.r[{k}]",
        }
    if naming == "flat":
        return {
            "u": "u", "f": "f", "yFirst": "yFirst", "yLast": "yLast",
            "x": "x_{k}", "der": "der(x_{k})", "w": "w_{k}", "r": "r_{k}",
        }
    raise ValueError(f"naming must be one of {NAMINGS}, not {naming!r}")


def _algebraic_starts(m: int) -> list[str]:
    """Consistent start values of ``w`` for x = 1, u = 0 (w[k] = x[k] + 0.5*w[k-1])."""
    starts: list[str] = []
    w = 0.0
    for _ in range(m):
        w = 1.0 + 0.5 * w
        starts.append(repr(w))
    return starts


def model_description_xml(m: int, *, naming: str = "structured") -> str:
    """The modelDescription.xml text for ``m`` blocks (ODE-mode ModelStructure)."""
    nm = _names(naming)
    token = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"lsdae-bench-chain/{m}/{naming}")) + "}"
    last_x = _vr(m - 1, 0)
    parts: list[str] = [
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<fmiModelDescription fmiVersion="3.0" modelName="ChainDAE"'
        f' description="Chain-structured semi-explicit index-1 DAE, {m} block(s), for benchmarks"'
        f' instantiationToken="{token}" generationTool="lsdae bench.generate"'
        f' variableNamingConvention="{naming}">\n'
        '  <ModelExchange modelIdentifier="ChainDAE" providesDirectionalDerivatives="true"/>\n'
        '  <DefaultExperiment startTime="0" stopTime="10"/>\n'
        '  <ModelVariables>\n'
        f'    <Float64 name="time" valueReference="{VR_TIME}" causality="independent"'
        ' variability="continuous"/>\n'
        f'    <Boolean name="enableDAEMode" valueReference="{VR_ENABLE}"'
        ' causality="structuralParameter" variability="fixed" start="false"'
        ' description="true: DAE mode (fmi-ls-dae)"/>\n'
        f'    <Float64 name="{nm["u"]}" valueReference="{VR_U}" causality="input"'
        ' variability="continuous" start="0"/>\n'
        f'    <Float64 name="{nm["f"]}" valueReference="{VR_F}" causality="input"'
        ' variability="continuous" start="0"/>\n'
        f'    <Float64 name="{nm["yFirst"]}" valueReference="{VR_Y_FIRST}" causality="output"'
        ' variability="continuous"/>\n'
        f'    <Float64 name="{nm["yLast"]}" valueReference="{VR_Y_LAST}" causality="output"'
        ' variability="continuous"/>\n'
    ]
    x_t, der_t, w_t, r_t = nm["x"], nm["der"], nm["w"], nm["r"]
    for j, w_start in enumerate(_algebraic_starts(m)):
        k = j + 1
        vx = _vr(j, 0)
        parts.append(
            f'    <Float64 name="{x_t.format(k=k)}" valueReference="{vx}" causality="local"'
            ' variability="continuous" initial="exact" start="1"/>\n'
            f'    <Float64 name="{der_t.format(k=k)}" valueReference="{vx + 1}" causality="local"'
            f' variability="continuous" derivative="{vx}"/>\n'
            f'    <Float64 name="{w_t.format(k=k)}" valueReference="{vx + 2}" causality="local"'
            f' variability="continuous" initial="approx" start="{w_start}"/>\n'
            f'    <Float64 name="{r_t.format(k=k)}" valueReference="{vx + 3}" causality="local"'
            ' variability="continuous"/>\n'
        )
    parts.append(
        '  </ModelVariables>\n'
        '  <ModelStructure>\n'
        # ODE mode: yFirst = w[1] = x[1] + 0.5*u
        f'    <Output valueReference="{VR_Y_FIRST}" dependencies="{VR_U} {_vr(0, 0)}"'
        ' dependenciesKind="constant constant"/>\n'
        f'    <Output valueReference="{VR_Y_LAST}" dependencies="{last_x}"'
        ' dependenciesKind="constant"/>\n'
    )
    # der(x[k]) depends on x[1..k], u (and f for k = m): omitted, meaning "all knowns".
    parts.extend(
        f'    <ContinuousStateDerivative valueReference="{_vr(j, 1)}"/>\n' for j in range(m)
    )
    # MS-05: outputs (calculated) and derivatives (calculated); states are exact, w is local.
    parts.append(
        f'    <InitialUnknown valueReference="{VR_Y_FIRST}" dependencies="{VR_U} {_vr(0, 0)}"'
        ' dependenciesKind="constant constant"/>\n'
        f'    <InitialUnknown valueReference="{VR_Y_LAST}" dependencies="{last_x}"'
        ' dependenciesKind="constant"/>\n'
    )
    parts.extend(f'    <InitialUnknown valueReference="{_vr(j, 1)}"/>\n' for j in range(m))
    parts.append('  </ModelStructure>\n</fmiModelDescription>\n')
    return "".join(parts)


def manifest_xml(m: int) -> str:
    """The 1.0.0-alpha.1 manifest text for ``m`` blocks (DAE-mode ModelStructure)."""
    parts: list[str] = [
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<fmiDAEManifest xmlns:fmi-ls="{_LS_NS}"\n'
        '  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"\n'
        '  fmi-ls:fmi-ls-version="1.0.0-alpha.1"\n'
        '  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">\n'
        f'  <EnableDAEParameter valueReference="{VR_ENABLE}"/>\n'
        '  <AlgebraicVariables>\n'
    ]
    parts.extend(f'    <AlgebraicVariable valueReference="{_vr(j, 2)}"/>\n' for j in range(m))
    last_x = _vr(m - 1, 0)
    parts.append(
        '  </AlgebraicVariables>\n'
        '  <ModelStructure>\n'
        f'    <Output valueReference="{VR_Y_FIRST}" dependencies="{_vr(0, 2)}"'
        ' dependenciesKind="constant"/>\n'
        f'    <Output valueReference="{VR_Y_LAST}" dependencies="{last_x}"'
        ' dependenciesKind="constant"/>\n'
    )
    for j in range(m - 1):
        parts.append(
            f'    <ContinuousStateDerivative valueReference="{_vr(j, 1)}"'
            f' dependencies="{_vr(j, 0)} {_vr(j, 2)}" dependenciesKind="constant constant"/>\n'
        )
    parts.append(
        f'    <ContinuousStateDerivative valueReference="{_vr(m - 1, 1)}"'
        f' dependencies="{VR_F} {last_x} {_vr(m - 1, 2)}"'
        ' dependenciesKind="constant constant constant"/>\n'
        f'    <InitialUnknown valueReference="{VR_Y_FIRST}"/>\n'
        f'    <InitialUnknown valueReference="{VR_Y_LAST}" dependencies="{last_x}"'
        ' dependenciesKind="constant"/>\n'
    )
    # DAE-30: InitialUnknown may also list algebraic variables (as in the alpha.1 example).
    for j in range(m):
        parts.append(
            f'    <InitialUnknown valueReference="{_vr(j, 1)}"/>\n'
            f'    <InitialUnknown valueReference="{_vr(j, 2)}"/>\n'
        )
    # r[1] = w[1] - 0.5*u - x[1]; r[k] = w[k] - 0.5*w[k-1] - x[k]; dependencies in vr order.
    parts.append(
        f'    <Residual valueReference="{_vr(0, 3)}" dependencies="{VR_U} {_vr(0, 0)} {_vr(0, 2)}"'
        ' dependenciesKind="constant constant constant"/>\n'
    )
    for j in range(1, m):
        parts.append(
            f'    <Residual valueReference="{_vr(j, 3)}"'
            f' dependencies="{_vr(j - 1, 2)} {_vr(j, 0)} {_vr(j, 2)}"'
            ' dependenciesKind="constant constant constant"/>\n'
        )
    parts.append('  </ModelStructure>\n</fmiDAEManifest>\n')
    return "".join(parts)


def generate(n_vars: int, dest: Path, *, naming: str = "structured") -> Path:
    """Write a chain DAE FMU with about ``n_vars`` variables to ``dest`` and return its path.

    ``dest`` is the ``.fmu`` file to write; if it is an existing directory, the file
    ``chain-<n_vars>.fmu`` is written inside it. Parent directories are created.
    """
    if n_vars < total_variables(1):
        raise ValueError(f"n_vars must be at least {total_variables(1)}, not {n_vars}")
    dest = Path(dest)
    if dest.is_dir():
        dest = dest / f"chain-{n_vars}.fmu"
    dest.parent.mkdir(parents=True, exist_ok=True)
    m = blocks_for(n_vars)
    md = model_description_xml(m, naming=naming).encode("utf-8")
    manifest = manifest_xml(m).encode("utf-8")
    tmp = dest.with_name(dest.name + ".part")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in (("modelDescription.xml", md), (MANIFEST_PATH, manifest)):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    tmp.replace(dest)
    logger.debug("wrote %s: %d blocks, %d variables", dest, m, total_variables(m))
    return dest


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.generate",
        description="Write a chain-structured fmi-ls-dae FMU (XML only) with about N variables.",
    )
    parser.add_argument("n_vars", type=int, help="approximate total number of variables")
    parser.add_argument("out", type=Path, help="the .fmu file to write (or an existing directory)")
    parser.add_argument("--naming", choices=NAMINGS, default="structured",
                        help="variableNamingConvention (default: structured)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    try:
        path = generate(args.n_vars, args.out, naming=args.naming)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    elapsed = time.perf_counter() - t0
    m = blocks_for(args.n_vars)
    size_mb = path.stat().st_size / 1e6
    print(f"{path}: {total_variables(m)} variables ({m} blocks), {size_mb:.2f} MB zipped,"
          f" {elapsed:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
