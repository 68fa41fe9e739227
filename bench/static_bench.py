"""Static benchmark: ``lsdae check --no-probes`` against ``fmpy validate`` on large generated FMUs.

For each size, a chain DAE FMU from :mod:`bench.generate` is timed side by side, in one run:

(a) the lsdae console script (``--lsdae-cmd`` + ``--lsdae-args`` + FILE), as a subprocess;
(b) ``fmpy validate FILE``, as a subprocess, with a per-run timeout (recorded as ``>T``);
(c) for reference, in process: a bare lxml parse of modelDescription.xml, and lxml validation
    of the parsed tree against fmpy's FMI 3 XSD (schema loading is not timed).

Wall times come from :func:`time.perf_counter` around :func:`subprocess.run`; the table gives
the median over ``--repeat`` runs. A tool whose first run takes longer than
``--single-run-above`` seconds (fmpy on 100k variables takes minutes) is run once for that
size, and the table says so. Writes ``static.md`` and ``static.json`` into ``--out``.

Exit status: 0 when the benchmark ran (however slow the tools, whatever they reported),
2 on harness errors (bad arguments, a tool command that cannot be found, a generated FMU that
fails the XSD, a failing generator).

    python -m bench.static_bench [--sizes 10000,50000,100000] [--repeat 3] [--out reports/bench]
"""
from __future__ import annotations

import argparse
import datetime as dt
import hashlib
import json
import logging
import os
import platform
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import asdict, dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from lxml import etree

from bench import generate as gen

logger = logging.getLogger(__name__)

REPO_ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SIZES = (10_000, 50_000, 100_000)
DEFAULT_LSDAE_ARGS = "check --no-probes --format json -o /dev/null"
_STDERR_KEEP = 2000  # characters of a failing run's output kept in the JSON


class HarnessError(Exception):
    """The benchmark itself cannot run or its input is wrong (exit status 2)."""


@dataclass
class ToolTiming:
    """Timings of one external command on one FMU."""

    command: list[str]
    runs_s: list[float] = field(default_factory=list)
    returncodes: list[int] = field(default_factory=list)
    timed_out: bool = False
    single_run: bool = False  # stopped after one run because it was slow
    skipped: bool = False
    output_excerpt: str = ""  # stdout+stderr of the first run with a non-zero exit

    @property
    def median_s(self) -> float | None:
        return statistics.median(self.runs_s) if self.runs_s and not self.timed_out else None


@dataclass
class SizeResult:
    requested: int
    n_variables: int
    n_blocks: int
    fmu_path: str
    fmu_bytes: int
    model_description_bytes: int
    manifest_bytes: int
    generate_s: float | None
    lsdae: ToolTiming
    fmpy: ToolTiming
    lxml_parse_s: list[float] = field(default_factory=list)
    lxml_validate_s: list[float] = field(default_factory=list)
    xsd_valid: bool = True


# --- command resolution -------------------------------------------------------------------

def _resolve_command(spec: str | None, default_name: str) -> list[str]:
    """Split ``spec`` (or find ``default_name`` beside this Python, then on PATH)."""
    if spec:
        argv = shlex.split(spec)
        if not argv:
            raise HarnessError(f"empty command for {default_name}")
        if shutil.which(argv[0]) is None:
            raise HarnessError(f"command not found: {argv[0]!r}")
        return argv
    beside = Path(sys.executable).parent / default_name
    if beside.is_file() and os.access(beside, os.X_OK):
        return [str(beside)]
    found = shutil.which(default_name)
    if found is None:
        raise HarnessError(
            f"{default_name!r} not found beside {sys.executable} nor on PATH;"
            f" pass --{default_name}-cmd or --skip-{default_name}"
        )
    return [found]


# --- FMUs ---------------------------------------------------------------------------------

def _generator_fingerprint(naming: str) -> str:
    """Short hash of the generator source, so a changed generator invalidates the cache."""
    src = Path(gen.__file__).read_bytes()
    return hashlib.sha256(src + naming.encode()).hexdigest()[:10]


def _obtain_fmu(size: int, cache_dir: Path, naming: str) -> tuple[Path, float | None]:
    """Return a cached FMU for ``size`` (generating it if needed) and the generation time."""
    path = cache_dir / f"chain-{size}-{naming}-{_generator_fingerprint(naming)}.fmu"
    if path.is_file():
        return path, None
    t0 = time.perf_counter()
    try:
        gen.generate(size, path, naming=naming)
    except Exception as exc:  # the generator failing is a harness error, whatever it raised
        raise HarnessError(f"generating {size} variables failed: {exc!r}") from exc
    return path, time.perf_counter() - t0


def _fmpy_xsd() -> Path:
    try:
        import fmpy
    except ImportError as exc:
        raise HarnessError("fmpy is not importable; it provides the FMI 3 XSD") from exc
    xsd = Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3ModelDescription.xsd"
    if not xsd.is_file():
        raise HarnessError(f"FMI 3 XSD not found at {xsd}")
    return xsd


# --- timing -------------------------------------------------------------------------------

def _run_once(argv: list[str], timeout: float, timing: ToolTiming) -> float | None:
    """Run ``argv`` once; append its time and exit code; None on timeout."""
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(argv, capture_output=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        timing.timed_out = True
        return None
    except OSError as exc:
        raise HarnessError(f"cannot run {argv[0]!r}: {exc}") from exc
    elapsed = time.perf_counter() - t0
    timing.runs_s.append(elapsed)
    timing.returncodes.append(proc.returncode)
    if proc.returncode != 0 and not timing.output_excerpt:
        text = (proc.stdout + proc.stderr).decode("utf-8", "replace")
        timing.output_excerpt = text[:_STDERR_KEEP]
    return elapsed


def _time_lxml(md: bytes, schema: etree.XMLSchema, repeat: int, result: SizeResult) -> None:
    for _ in range(repeat):
        t0 = time.perf_counter()
        doc = etree.fromstring(md)
        t1 = time.perf_counter()
        valid = schema.validate(doc)
        t2 = time.perf_counter()
        result.lxml_parse_s.append(t1 - t0)
        result.lxml_validate_s.append(t2 - t1)
        result.xsd_valid = result.xsd_valid and valid
        del doc


def bench_size(
    size: int,
    *,
    fmu: Path,
    generate_s: float | None,
    schema: etree.XMLSchema,
    lsdae_argv: list[str] | None,
    fmpy_argv: list[str] | None,
    repeat: int,
    timeout: float,
    single_run_above: float,
) -> SizeResult:
    """Time every tool on one FMU. Tools alternate run by run, so drift hits both alike."""
    with zipfile.ZipFile(fmu) as zf:
        md = zf.read("modelDescription.xml")
        manifest_bytes = zf.getinfo(gen.MANIFEST_PATH).file_size
    m = gen.blocks_for(size)
    lsdae = ToolTiming(command=(lsdae_argv or []) + [str(fmu)], skipped=lsdae_argv is None)
    fmpy = ToolTiming(command=(fmpy_argv or []) + [str(fmu)], skipped=fmpy_argv is None)
    result = SizeResult(
        requested=size, n_variables=gen.total_variables(m), n_blocks=m, fmu_path=str(fmu),
        fmu_bytes=fmu.stat().st_size, model_description_bytes=len(md),
        manifest_bytes=manifest_bytes, generate_s=generate_s, lsdae=lsdae, fmpy=fmpy,
    )
    _time_lxml(md, schema, repeat, result)
    if not result.xsd_valid:
        raise HarnessError(f"generated FMU {fmu} fails the FMI 3 XSD: {schema.error_log}")
    for r in range(repeat):
        for name, timing in (("lsdae", lsdae), ("fmpy", fmpy)):
            if timing.skipped or timing.timed_out or timing.single_run:
                continue
            elapsed = _run_once(timing.command, timeout, timing)
            shown = f">{timeout:g} s (timeout)" if elapsed is None else f"{elapsed:.2f} s"
            logger.info("%d vars, %s run %d/%d: %s", result.n_variables, name, r + 1, repeat, shown)
            if elapsed is not None and r == 0 and repeat > 1 and elapsed > single_run_above:
                timing.single_run = True
    return result


# --- report -------------------------------------------------------------------------------

def _shown(path_or_arg: str) -> str:
    """An argument as shown in reports: paths inside the repository become relative."""
    if os.sep not in path_or_arg:
        return path_or_arg
    try:
        return str(Path(os.path.abspath(path_or_arg)).relative_to(REPO_ROOT))
    except ValueError:
        return path_or_arg


def machine_info() -> dict[str, Any]:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()

    def version(dist: str) -> str:
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return "not installed"

    return {
        "cpu": cpu,
        "logical_cores": os.cpu_count(),
        "usable_cores": usable,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "lxml": ".".join(map(str, etree.LXML_VERSION)),
        "libxml2": ".".join(map(str, etree.LIBXML_VERSION)),
        "fmpy": version("fmpy"),
        "lsdae": version("lsdae"),
    }


def _fmt_tool(t: ToolTiming, timeout: float) -> str:
    if t.skipped:
        return "skipped"
    if t.timed_out:
        return f">{timeout:g}"
    if not t.runs_s:
        return "n/a"
    median = t.median_s or 0.0
    text = f"{median:.3f}" if median < 10 else f"{median:.1f}"
    if t.single_run:
        text += " (1 run)"
    bad = sorted({rc for rc in t.returncodes if rc != 0})
    if bad:
        text += f" (exit {','.join(map(str, bad))})"
    return text


def _ratio(res: SizeResult, timeout: float) -> tuple[float | None, str]:
    lsdae, fmpy = res.lsdae.median_s, res.fmpy.median_s
    if lsdae is None or lsdae <= 0:
        return None, "n/a"
    if res.fmpy.timed_out:
        return None, f">{timeout / lsdae:.1f}"
    if fmpy is None:
        return None, "n/a"
    return fmpy / lsdae, f"{fmpy / lsdae:.1f}"


def render_markdown(report: dict[str, Any], results: list[SizeResult]) -> str:
    cfg, mach = report["config"], report["machine"]
    timeout = cfg["timeout_s"]
    lines = [
        "# Static benchmark: `lsdae check --no-probes` vs `fmpy validate`",
        "",
        f"Date: {report['date']}. Sizes: {', '.join(map(str, cfg['sizes']))}."
        f" Repeat: {cfg['repeat']} (median shown; a tool whose first run took longer than"
        f" {cfg['single_run_above_s']:g} s ran once, marked \"(1 run)\")."
        f" Timeout per run: {timeout:g} s (shown as `>T`).",
        "",
        "| variables | FMU MB | XML MB | lsdae median s | fmpy median s | ratio fmpy/lsdae"
        " | lxml parse s | lxml validate s |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for res in results:
        xml_mb = (res.model_description_bytes + res.manifest_bytes) / 1e6
        lines.append(
            f"| {res.n_variables} | {res.fmu_bytes / 1e6:.2f} | {xml_mb:.1f}"
            f" | {_fmt_tool(res.lsdae, timeout)} | {_fmt_tool(res.fmpy, timeout)}"
            f" | {_ratio(res, timeout)[1]}"
            f" | {statistics.median(res.lxml_parse_s):.3f}"
            f" | {statistics.median(res.lxml_validate_s):.3f} |"
        )
    lines += [
        "",
        "FMUs: chain-structured semi-explicit DAEs from `python -m bench.generate`"
        f" (naming `{cfg['naming']}`; 4 variables per block plus 6). XML MB is modelDescription"
        " plus manifest, uncompressed. lsdae and fmpy are wall times of a subprocess"
        " (interpreter start-up included); the lxml columns are in-process, on modelDescription.xml"
        " only, with the XSD loaded beforehand. An `(exit N)` mark means the tool returned a"
        " non-zero status (see `static.json`).",
        "",
        f"- lsdae command: `{' '.join(cfg['lsdae_cmd']) or 'skipped'}` FILE",
        f"- fmpy command: `{' '.join(cfg['fmpy_cmd']) or 'skipped'}` FILE",
        "",
        "## Machine",
        "",
        f"- CPU: {mach['cpu']} ({mach['logical_cores']} logical cores,"
        f" {mach['usable_cores']} usable)",
        f"- OS: {mach['platform']}",
        f"- Python {mach['python']}, lxml {mach['lxml']} (libxml2 {mach['libxml2']}),"
        f" fmpy {mach['fmpy']}, lsdae {mach['lsdae']}",
        "",
    ]
    return "\n".join(lines)


def _parse_sizes(text: str) -> list[int]:
    sizes = []
    for part in text.split(","):
        part = part.strip().lower().replace("_", "")
        if not part:
            continue
        factor = 1000 if part.endswith("k") else 1
        try:
            sizes.append(int(part.rstrip("k")) * factor)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(f"not a size: {part!r}") from exc
    if not sizes or min(sizes) < gen.total_variables(1):
        raise argparse.ArgumentTypeError(f"sizes must be >= {gen.total_variables(1)}")
    return sizes


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m bench.static_bench",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--sizes", type=_parse_sizes, default=list(DEFAULT_SIZES),
                   help="comma-separated variable counts, '50k' works"
                        " (default: 10000,50000,100000)")
    p.add_argument("--repeat", type=int, default=3, help="runs per tool and size (default: 3)")
    p.add_argument("--out", type=Path, default=Path("reports/bench"),
                   help="directory for static.md and static.json (default: reports/bench)")
    p.add_argument("--lsdae-cmd", default=None,
                   help="lsdae program, shell-split (default: lsdae beside this Python, else PATH)")
    p.add_argument("--lsdae-args", default=DEFAULT_LSDAE_ARGS,
                   help=f"arguments before FILE (default: {DEFAULT_LSDAE_ARGS!r})")
    p.add_argument("--fmpy-cmd", default=None,
                   help="fmpy program, shell-split (default: fmpy beside this Python, else PATH)")
    p.add_argument("--timeout", type=float, default=900.0,
                   help="per-run timeout in seconds for each subprocess (default: 900)")
    p.add_argument("--single-run-above", type=float, default=60.0,
                   help="run a tool once for a size if its first run takes longer"
                        " (default: 60 s)")
    p.add_argument("--skip-lsdae", action="store_true", help="do not run lsdae")
    p.add_argument("--skip-fmpy", action="store_true", help="do not run fmpy")
    p.add_argument("--cache-dir", type=Path, default=REPO_ROOT / ".cache" / "bench",
                   help="where generated FMUs are kept between runs (default: .cache/bench)")
    p.add_argument("--no-cache", action="store_true", help="generate into a temporary directory")
    p.add_argument("--naming", choices=gen.NAMINGS, default="structured",
                   help="variableNamingConvention of the generated FMUs (default: structured)")
    p.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    return p


def run(args: argparse.Namespace, cache_dir: Path) -> tuple[dict[str, Any], list[SizeResult]]:
    if args.repeat < 1:
        raise HarnessError("--repeat must be at least 1")
    lsdae_argv = None if args.skip_lsdae else (
        _resolve_command(args.lsdae_cmd, "lsdae") + shlex.split(args.lsdae_args))
    fmpy_argv = None if args.skip_fmpy else _resolve_command(args.fmpy_cmd, "fmpy") + ["validate"]
    schema = etree.XMLSchema(file=str(_fmpy_xsd()))
    results = []
    for size in args.sizes:
        fmu, generate_s = _obtain_fmu(size, cache_dir, args.naming)
        logger.info("%d variables: %s", size, fmu)
        results.append(bench_size(
            size, fmu=fmu, generate_s=generate_s, schema=schema, lsdae_argv=lsdae_argv,
            fmpy_argv=fmpy_argv, repeat=args.repeat, timeout=args.timeout,
            single_run_above=args.single_run_above,
        ))
    report: dict[str, Any] = {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": machine_info(),
        "config": {
            "sizes": args.sizes, "repeat": args.repeat, "timeout_s": args.timeout,
            "single_run_above_s": args.single_run_above, "naming": args.naming,
            "lsdae_cmd": [_shown(a) for a in lsdae_argv or []],
            "fmpy_cmd": [_shown(a) for a in fmpy_argv or []],
        },
    }
    return report, results


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    # Progress lines always show (fmpy takes minutes); -v adds the generator's debug lines.
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(message)s", stream=sys.stderr)
    try:
        if args.no_cache:
            with tempfile.TemporaryDirectory(prefix="lsdae-bench-") as tmp:
                report, results = run(args, Path(tmp))
        else:
            report, results = run(args, args.cache_dir)
    except HarnessError as exc:
        print(f"static_bench: error: {exc}", file=sys.stderr)
        return 2
    timeout = args.timeout
    report["results"] = []
    for res in results:
        entry = asdict(res)
        entry["fmu_path"] = _shown(res.fmu_path)
        for tool in ("lsdae", "fmpy"):
            entry[tool]["command"] = [_shown(a) for a in entry[tool]["command"]]
        for tool in ("lsdae", "fmpy"):
            entry[tool]["median_s"] = getattr(res, tool).median_s
        entry["ratio_fmpy_over_lsdae"] = _ratio(res, timeout)[0]
        entry["lxml_parse_median_s"] = statistics.median(res.lxml_parse_s)
        entry["lxml_validate_median_s"] = statistics.median(res.lxml_validate_s)
        report["results"].append(entry)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "static.json").write_text(json.dumps(report, indent=2) + "\n")
    markdown = render_markdown(report, results)
    (args.out / "static.md").write_text(markdown)
    print(markdown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
