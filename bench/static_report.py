"""The results of the static benchmark (:mod:`bench.static_bench`), their ratios and tables.

Two ratios are the ones to chase, both measured in the same run as the figures they divide:
lsdae's wall time over the parse floor (lxml parsing both XML files in process), and lsdae's
peak memory over that of a process that only parses both files. fmpy is shown beside them.
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Any


@dataclass
class ToolTiming:
    """Timings of one external command on one FMU."""

    command: list[str]
    runs_s: list[float] = field(default_factory=list)
    returncodes: list[int] = field(default_factory=list)
    max_rss_kib: list[int] = field(default_factory=list)  # peak resident memory of each run
    timed_out: bool = False
    single_run: bool = False  # stopped after one run because it was slow
    skipped: bool = False
    output_excerpt: str = ""  # stdout+stderr of the first run with a non-zero exit

    @property
    def median_s(self) -> float | None:
        return statistics.median(self.runs_s) if self.runs_s and not self.timed_out else None

    @property
    def median_rss_mib(self) -> float | None:
        return statistics.median(self.max_rss_kib) / 1024 if self.max_rss_kib else None


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
    parse_only: ToolTiming        # the parse-only process (c)
    parse_floor_s: list[float] = field(default_factory=list)   # (c): both parses, in it
    visit_floor_s: list[float] = field(default_factory=list)   # (c): one visit of each element
    lxml_parse_s: list[float] = field(default_factory=list)    # modelDescription.xml alone
    lxml_validate_s: list[float] = field(default_factory=list)
    xsd_valid: bool = True



def fmt_tool(t: ToolTiming, timeout: float, *, skipped: str = "skipped") -> str:
    if t.skipped:
        return skipped
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


def fmpy_ratio(res: SizeResult, timeout: float) -> tuple[float | None, str]:
    """fmpy's median time over lsdae's (how many times faster lsdae is)."""
    lsdae, fmpy = res.lsdae.median_s, res.fmpy.median_s
    if lsdae is None or lsdae <= 0:
        return None, "n/a"
    if res.fmpy.timed_out:
        return None, f">{timeout / lsdae:.1f}"
    if fmpy is None:
        return None, "n/a"
    return fmpy / lsdae, f"{fmpy / lsdae:.1f}"


def floor_ratio(res: SizeResult) -> float | None:
    """lsdae's median wall time over the median in-process parse of both XML files."""
    lsdae = res.lsdae.median_s
    if lsdae is None or not res.parse_floor_s:
        return None
    floor = statistics.median(res.parse_floor_s)
    return lsdae / floor if floor > 0 else None


def visit_ratio(res: SizeResult) -> float | None:
    """The parse floor plus the visit floor over the parse floor: the least ``lsdae / floor``
    of any checker that builds something per element from Python."""
    if not res.parse_floor_s or not res.visit_floor_s:
        return None
    floor = statistics.median(res.parse_floor_s)
    return (floor + statistics.median(res.visit_floor_s)) / floor if floor > 0 else None


def memory_ratio(res: SizeResult) -> float | None:
    """lsdae's median peak RSS over the parse-only process's."""
    lsdae, floor = res.lsdae.median_rss_mib, res.parse_only.median_rss_mib
    return lsdae / floor if lsdae is not None and floor else None


def _x(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.1f}×" if value >= 10 else f"{value:.2f}×"


def _mib(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.0f}"


def render_markdown(report: dict[str, Any], results: list[SizeResult]) -> str:
    cfg, mach = report["config"], report["machine"]
    timeout = cfg["timeout_s"]
    fmpy_up_to = cfg.get("fmpy_up_to")
    not_run = f"not run (> {fmpy_up_to})" if fmpy_up_to and cfg["fmpy_cmd"] else "skipped"
    lines = [
        "# Static benchmark: `lsdae check --no-probes` against the XML parse floor and"
        " `fmpy validate`",
        "",
        f"Date: {report['date']}. Sizes: {', '.join(map(str, cfg['sizes']))}."
        f" Repeat: {cfg['repeat']} (median shown; a tool whose first run took longer than"
        f" {cfg['single_run_above_s']:g} s ran once, marked \"(1 run)\")."
        f" Timeout per run: {timeout:g} s (shown as `>T`).",
        "",
        "## Against the floor",
        "",
        "| variables | XML MB | lsdae s | parse floor s | lsdae / floor | visit floor s"
        " | (parse + visit) / parse | lsdae peak MiB | parse-only peak MiB"
        " | lsdae / parse-only peak | parse-only process s |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for res in results:
        xml_mb = (res.model_description_bytes + res.manifest_bytes) / 1e6
        lines.append(
            f"| {res.n_variables} | {xml_mb:.1f} | {fmt_tool(res.lsdae, timeout)}"
            f" | {statistics.median(res.parse_floor_s):.3f} | {_x(floor_ratio(res))}"
            f" | {statistics.median(res.visit_floor_s):.3f} | {_x(visit_ratio(res))}"
            f" | {_mib(res.lsdae.median_rss_mib)} | {_mib(res.parse_only.median_rss_mib)}"
            f" | {_x(memory_ratio(res))} | {fmt_tool(res.parse_only, timeout)} |"
        )
    lines += [
        "",
        "## Beside fmpy",
        "",
        "| variables | FMU MB | lsdae s | fmpy s | fmpy / lsdae | lxml parse of modelDescription s"
        " | lxml XSD validation of modelDescription s |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for res in results:
        lines.append(
            f"| {res.n_variables} | {res.fmu_bytes / 1e6:.2f} | {fmt_tool(res.lsdae, timeout)}"
            f" | {fmt_tool(res.fmpy, timeout, skipped=not_run)} | {fmpy_ratio(res, timeout)[1]}"
            f" | {statistics.median(res.lxml_parse_s):.3f}"
            f" | {statistics.median(res.lxml_validate_s):.3f} |"
        )
    lines += [
        "",
        "FMUs: chain-structured semi-explicit DAEs from `python -m bench.generate`"
        f" (naming `{cfg['naming']}`; 4 variables per block plus 6). XML MB is modelDescription"
        " plus manifest, uncompressed.",
        "",
        "- lsdae, fmpy and the parse-only process are wall times of a subprocess (interpreter"
        " start-up included) and their peak resident memory (max RSS, from `os.wait4`).",
        "- The parse-only process reads both members from the FMU and parses them with"
        " `lxml.etree.fromstring` (default parser), keeping both trees: its peak memory is the"
        " memory floor of a checker that holds both documents. The parse floor is the time of"
        " its two parses, measured inside it (bytes already read, in a fresh process as lsdae"
        " runs); `lsdae / floor` divides lsdae's median wall time by the median floor.",
        "- The visit floor is the time the same process then takes to visit every element of"
        " both trees once from Python, reading its attribute values and its source line"
        " (`el.values()`, `el.sourceline`), and building nothing: the least any checker written"
        " in Python spends per element to read it. `(parse + visit) / parse` is thus the"
        " lowest `lsdae / floor` such a checker could show, before it checks anything.",
        "- The last two columns are for reference, in the benchmark's own process: a parse of"
        " modelDescription.xml alone and its validation against fmpy's FMI 3 XSD (schema"
        " loaded beforehand).",
        f"- fmpy runs only for sizes up to {fmpy_up_to} (`--fmpy-up-to`)." if fmpy_up_to else
        "- fmpy runs at every size.",
        "- An `(exit N)` mark means the tool returned a non-zero status (see `static.json`).",
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
