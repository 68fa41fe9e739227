"""Static benchmark: ``lsdae check --no-probes`` against the XML parse floor and ``fmpy validate``.

For each size, a chain DAE FMU from :mod:`bench.generate` is timed side by side, in one run:

(a) the lsdae console script (``--lsdae-cmd`` + ``--lsdae-args`` + FILE), as a subprocess;
(b) ``fmpy validate FILE``, as a subprocess, with a per-run timeout (recorded as ``>T``), for
    sizes up to ``--fmpy-up-to`` variables (it takes minutes per 100k variables);
(c) a parse-only process: a subprocess that reads both members from the FMU and parses them
    with ``lxml.etree.fromstring`` (default parser), keeping both trees, as a checker that
    holds both documents would. The parse itself, timed inside that fresh process (bytes
    already read, memory not yet touched, as lsdae finds it), is the parse floor; the
    process's peak memory is the memory floor;
(d) for reference, in this process: a parse of modelDescription.xml alone and its lxml
    validation against fmpy's FMI 3 XSD (schema loading is not timed).

The numbers to chase are lsdae's time over the parse floor, and lsdae's peak memory (max RSS of
the process, from :func:`os.wait4`) over the parse-only process's (both from (c)).

Wall times come from :func:`time.perf_counter` around each subprocess; the table gives the
median over ``--repeat`` runs. A tool whose first run takes longer than ``--single-run-above``
seconds (fmpy on 100k variables takes minutes) is run once for that size, and the table says
so. Writes ``static.md`` and ``static.json`` into ``--out``.

Exit status: 0 when the benchmark ran (however slow the tools, whatever they reported),
2 on harness errors (bad arguments, a tool command that cannot be found, a generated FMU that
fails the XSD, a failing generator).

    python -m bench.static_bench [--sizes 10000,50000,100000,500000] [--repeat 3]
                                 [--fmpy-up-to 100000] [--out reports/bench]
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
import threading
import time
import zipfile
from dataclasses import asdict
from importlib import metadata
from pathlib import Path
from typing import Any

from lxml import etree

from bench import generate as gen
from bench.static_report import (SizeResult, ToolTiming, floor_ratio, fmpy_ratio, memory_ratio,
                                 visit_ratio,
                                 render_markdown)

logger = logging.getLogger(__name__)

REPO_ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SIZES = (10_000, 50_000, 100_000, 500_000)
DEFAULT_FMPY_UP_TO = 100_000   # fmpy validate takes minutes per 100k variables
DEFAULT_LSDAE_ARGS = "check --no-probes --format json -o /dev/null"
_STDERR_KEEP = 2000  # characters of a failing run's output kept in the JSON


class HarnessError(Exception):
    """The benchmark itself cannot run or its input is wrong (exit status 2)."""


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

# The parse-only process (c): what any checker must do at least, in a process of its own.
# It prints the seconds spent in the two parses (the parse floor), then the seconds of one
# visit of every element from Python, reading its attribute values and its line (the least a
# checker written in Python does per element to build anything from it: the visit floor).
PARSE_ONLY_SCRIPT = (
    "import sys, time, zipfile\n"
    "from lxml import etree\n"
    "with zipfile.ZipFile(sys.argv[1]) as zf:\n"
    "    md, manifest = zf.read('modelDescription.xml'), zf.read(sys.argv[2])\n"
    "t0 = time.perf_counter()\n"
    "model_tree = etree.fromstring(md)\n"
    "del md\n"
    "manifest_tree = etree.fromstring(manifest)\n"
    "t1 = time.perf_counter()\n"
    "for root in (model_tree, manifest_tree):\n"
    "    for el in root.iter():\n"
    "        el.values(), el.sourceline\n"
    "print(f'{t1 - t0:.6f} {time.perf_counter() - t1:.6f}')\n"
)


def _wait(proc: subprocess.Popen, timeout: float) -> tuple[float, int, int] | None:
    """Wait for ``proc`` with :func:`os.wait4`: (end time, exit status, max RSS in KiB), or
    None after killing it on timeout. wait4 gives this child's own peak memory, where
    getrusage(RUSAGE_CHILDREN) would give the largest of all children so far."""
    done: list[tuple[float, int, int]] = []

    def reap() -> None:
        _, status, usage = os.wait4(proc.pid, 0)
        done.append((time.perf_counter(), os.waitstatus_to_exitcode(status), usage.ru_maxrss))

    waiter = threading.Thread(target=reap, daemon=True)
    waiter.start()
    waiter.join(timeout)
    if not done:
        proc.kill()
        waiter.join()
        proc.returncode = done[0][1]
        return None
    proc.returncode = done[0][1]  # reaped here, not by Popen
    return done[0]


def _run_once(argv: list[str], timeout: float, timing: ToolTiming,
              output: list[str] | None = None) -> float | None:
    """Run ``argv`` once; append its time, exit code and peak memory, and its output to
    ``output`` when given; None on timeout."""
    with tempfile.TemporaryFile() as out:
        t0 = time.perf_counter()
        try:
            proc = subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT)
        except OSError as exc:
            raise HarnessError(f"cannot run {argv[0]!r}: {exc}") from exc
        finished = _wait(proc, timeout)
        if finished is None:
            timing.timed_out = True
            return None
        end, returncode, max_rss_kib = finished
        elapsed = end - t0
        timing.runs_s.append(elapsed)
        timing.returncodes.append(returncode)
        timing.max_rss_kib.append(max_rss_kib)
        if output is not None:
            out.seek(0)
            output.append(out.read().decode("utf-8", "replace"))
        if returncode != 0 and not timing.output_excerpt:
            out.seek(0)
            timing.output_excerpt = out.read(_STDERR_KEEP * 4).decode("utf-8", "replace")[
                :_STDERR_KEEP]
    return elapsed


def _time_lxml(md: bytes, schema: etree.XMLSchema, repeat: int, result: SizeResult) -> None:
    """(d): modelDescription.xml parsed and validated in this process, for reference."""
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


def _parse_floor(output: str) -> tuple[float, float]:
    """The seconds the parse-only process printed: its two parses, its visit of the elements."""
    try:
        parse, visit = output.strip().splitlines()[-1].split()
        return float(parse), float(visit)
    except (ValueError, IndexError) as exc:
        raise HarnessError(f"the parse-only process printed {output[:200]!r}") from exc


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
    fmpy_up_to: int | None = None,
) -> SizeResult:
    """Time every tool on one FMU. Tools alternate run by run, so drift hits all alike."""
    with zipfile.ZipFile(fmu) as zf:
        md = zf.read("modelDescription.xml")
        manifest = zf.read(gen.MANIFEST_PATH)
    m = gen.blocks_for(size)
    n_variables = gen.total_variables(m)
    fmpy_skipped = fmpy_argv is None or (fmpy_up_to is not None and size > fmpy_up_to)
    lsdae = ToolTiming(command=(lsdae_argv or []) + [str(fmu)], skipped=lsdae_argv is None)
    fmpy = ToolTiming(command=(fmpy_argv or []) + [str(fmu)], skipped=fmpy_skipped)
    parse_only = ToolTiming(command=[sys.executable, "-c", PARSE_ONLY_SCRIPT, str(fmu),
                                     gen.MANIFEST_PATH])
    result = SizeResult(
        requested=size, n_variables=n_variables, n_blocks=m, fmu_path=str(fmu),
        fmu_bytes=fmu.stat().st_size, model_description_bytes=len(md),
        manifest_bytes=len(manifest), generate_s=generate_s, lsdae=lsdae, fmpy=fmpy,
        parse_only=parse_only,
    )
    _time_lxml(md, schema, repeat, result)
    del md, manifest  # the subprocesses below should not share the machine with these bytes
    if not result.xsd_valid:
        raise HarnessError(f"generated FMU {fmu} fails the FMI 3 XSD: {schema.error_log}")
    for r in range(repeat):
        for name, timing in (("lsdae", lsdae), ("parse-only", parse_only), ("fmpy", fmpy)):
            if timing.skipped or timing.timed_out or timing.single_run:
                continue
            output: list[str] | None = [] if timing is parse_only else None
            elapsed = _run_once(timing.command, timeout, timing, output)
            if output and elapsed is not None:
                parse, visit = _parse_floor(output[0])
                result.parse_floor_s.append(parse)
                result.visit_floor_s.append(visit)
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
                        " (default: 10000,50000,100000,500000)")
    p.add_argument("--fmpy-up-to", type=int, default=DEFAULT_FMPY_UP_TO,
                   help="run fmpy only for sizes (as requested) up to this; 0: every size"
                        f" (default: {DEFAULT_FMPY_UP_TO})")
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
            single_run_above=args.single_run_above, fmpy_up_to=args.fmpy_up_to or None,
        ))
    report: dict[str, Any] = {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": machine_info(),
        "config": {
            "sizes": args.sizes, "repeat": args.repeat, "timeout_s": args.timeout,
            "single_run_above_s": args.single_run_above, "naming": args.naming,
            "fmpy_up_to": args.fmpy_up_to or None,
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
        for tool in ("lsdae", "fmpy", "parse_only"):
            entry[tool]["command"] = [_shown(a) for a in entry[tool]["command"]]
            entry[tool]["median_s"] = getattr(res, tool).median_s
            entry[tool]["median_max_rss_mib"] = getattr(res, tool).median_rss_mib
        entry["ratio_fmpy_over_lsdae"] = fmpy_ratio(res, timeout)[0]
        entry["parse_floor_median_s"] = statistics.median(res.parse_floor_s)
        entry["ratio_lsdae_over_parse_floor"] = floor_ratio(res)
        entry["visit_floor_median_s"] = statistics.median(res.visit_floor_s)
        entry["ratio_parse_and_visit_over_parse_floor"] = visit_ratio(res)
        entry["ratio_lsdae_over_parse_only_peak_rss"] = memory_ratio(res)
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
