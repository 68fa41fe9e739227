"""``lsdae check`` on an FMU in a subprocess, at a setting, and the kill criterion.

The check is the user's: ``python -m conformance check FMU --format json:FILE --seed S`` with
probes on, the setting's endurance level and rule options, an empty ``[tool.lsdae]`` (so no
pyproject.toml around changes it), in a subprocess with a timeout. A setting with several
seeds runs one check per seed and takes the union of the findings (more sampled points), its
time the sum.

Kill criterion (issue 20, point 7): a mutant is killed when its report has an error or warning
(rule code, subject) that the original's report at the same setting has not -- a new defect
under a rule the original already trips counts. The *subject* is the finding's ``subject``
field (the variable or element the finding is about: what a baseline keys on), else its
XPath-like ``path``; never the message, whose numbers move with any change of the model.
``internal-error`` (DAE099, a failure of lsdae itself) is not a detection: such a mutant is
listed apart, for the lead to look at.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO_ROOT = Path(__file__).resolve().parents[2]
KILLING = ("error", "warning")
INFORMING = ("info",)    # said, at the weight its text gives: no verdict of non-conformance
INTERNAL = "DAE099"
Key = tuple[str, str]   # (rule code, subject)


@dataclass(frozen=True)
class Setting:
    name: str
    label: str
    args: tuple[str, ...]
    seeds: tuple[int, ...] = (0,)


_LOW = ("DAE750.points=1", "DAE750.max_instances=100", "DAE801.output_points=26",
        "DAE760.calls_quick=5000", "DAE762.cycles_quick=4")
_HIGH = ("DAE750.points=6", "DAE750.max_instances=1600", "DAE750.max_seconds=30",
         "DAE801.output_points=401", "DAE760.calls_quick=200000", "DAE762.cycles_quick=80")


def _options(pairs: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(a for pair in pairs for a in ("--rule-option", pair))


SETTINGS: dict[str, Setting] = {s.name: s for s in (
    Setting("off", "--endurance off", ("--endurance", "off")),
    Setting("quick", "--endurance quick (the default)", ("--endurance", "quick")),
    Setting("long", "--endurance long", ("--endurance", "long")),
    Setting("budget-low", "quick, smaller sampling budgets: " + ", ".join(_LOW),
            ("--endurance", "quick", *_options(_LOW))),
    Setting("budget-high", "quick, larger sampling budgets: " + ", ".join(_HIGH),
            ("--endurance", "quick", *_options(_HIGH))),
    Setting("seeds-3", "quick, seeds 0, 1 and 2 (three sets of sampled points, findings "
            "united)", ("--endurance", "quick"), (0, 1, 2)),
)}
MAIN = "quick"


@dataclass
class CheckResult:
    status: str                     # "ok", "timeout", "failed" (no report)
    seconds: float
    findings: dict[Key, str] = field(default_factory=dict)   # killing-level key -> rule name
    internal: list[str] = field(default_factory=list)        # DAE099 messages
    informed: dict[Key, str] = field(default_factory=dict)   # information-level key -> name
    detail: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"status": self.status, "seconds": round(self.seconds, 3),
                "findings": sorted([code, subject, name]
                                   for (code, subject), name in self.findings.items()),
                "internal": self.internal, "detail": self.detail,
                "informed": sorted([code, subject, name]
                                   for (code, subject), name in self.informed.items())}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> CheckResult:
        return cls(data["status"], data["seconds"],
                   {(c, s): n for c, s, n in data["findings"]}, data["internal"],
                   {(c, s): n for c, s, n in data.get("informed", [])},
                   data.get("detail", ""))


def subject_of(finding: dict[str, Any]) -> str:
    return finding.get("subject") or finding.get("path") or ""


def read_findings(report: dict[str, Any]
                  ) -> tuple[dict[Key, str], list[str], dict[Key, str]]:
    """The killing-level (code, subject) keys of a JSON report, its internal errors, and its
    information-level keys."""
    keys: dict[Key, str] = {}
    internal: list[str] = []
    informed: dict[Key, str] = {}
    for fmu in report.get("fmus", []):
        for f in fmu.get("findings", []):
            if f["code"] == INTERNAL:
                internal.append(f.get("message", "")[:300])
            elif f["severity"] in KILLING:
                keys[(f["code"], subject_of(f))] = f["name"]
            elif f["severity"] in INFORMING:
                informed[(f["code"], subject_of(f))] = f["name"]
    return keys, internal, informed


def run_check(fmu: Path, setting: Setting, *, timeout: float = 300.0) -> CheckResult:
    """``lsdae check`` at ``setting`` (each of its seeds), in subprocesses."""
    result = CheckResult("ok", 0.0)
    with tempfile.TemporaryDirectory(prefix="lsdae-mutation-check-") as tmp:
        config = Path(tmp) / "pyproject.toml"
        config.write_text("[tool.lsdae]\n")
        for seed in setting.seeds:
            out = Path(tmp) / f"report-{seed}.json"
            cmd = [sys.executable, "-m", "conformance", "check", str(fmu), "--format",
                   f"json:{out}", "--seed", str(seed), "--progress", "never", "--color",
                   "never", "--config", str(config), *setting.args]
            start = time.perf_counter()
            try:
                proc = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True,
                                      timeout=timeout, check=False)
            except subprocess.TimeoutExpired:
                return CheckResult("timeout", time.perf_counter() - start + result.seconds,
                                   detail=f"no report after {timeout:g} s (seed {seed})")
            result.seconds += time.perf_counter() - start
            if not out.is_file():
                return CheckResult("failed", result.seconds, detail=f"exit {proc.returncode}: "
                                   f"{proc.stderr.strip()[-300:]}")
            keys, internal, informed = read_findings(json.loads(out.read_text()))
            result.findings.update(keys)
            result.internal += internal
            result.informed.update(informed)
    return result


def new_findings(original: CheckResult, mutant: CheckResult) -> dict[Key, str]:
    """The mutant's killing-level keys the original has not."""
    return {k: v for k, v in mutant.findings.items() if k not in original.findings}


def new_information(original: CheckResult, mutant: CheckResult) -> dict[Key, str]:
    """The mutant's information-level keys the original has not."""
    return {k: v for k, v in mutant.informed.items() if k not in original.informed}


def outcome(original: CheckResult, mutant: CheckResult) -> str:
    """killed, informed (no new error or warning, but a new finding of information: lsdae says
    it at the weight its text gives, which calls nothing non-conformant), survived,
    check-timeout, check-failed, or internal-error (lsdae failed and nothing else is new)."""
    if mutant.status == "timeout":
        return "check-timeout"
    if mutant.status != "ok":
        return "check-failed"
    if new_findings(original, mutant):
        return "killed"
    if new_information(original, mutant):
        return "informed"
    if mutant.internal and not original.internal:
        return "internal-error"
    return "survived"
