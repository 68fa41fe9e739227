"""One run of the campaign: sample, build, observe, check and explain each mutant.

For every sampled mutant: build it with the mutated source (``build_scene(host,
overrides=...)``; a compile error, or an implicit declaration of a function -- a constraint
violation of C99 that only links because a shared library may leave symbols undefined -- makes
it *stillborn*); observe it with the oracle and compare with the original host's observations
(*equivalent* when nothing differs); check it with lsdae at the main setting and compare with
the original's report (*killed*, *survived*, or check-timeout / check-failed /
internal-error). Equivalent mutants are checked too: a new finding on one is either a false
alarm of lsdae or a blind spot of the oracle, and is listed. Survivors get the promise checks,
minus what the original already breaks, as evidence for their verdict.

Results of the oracle, the checks and the promise checks are cached in
``.cache/mutation/results/`` by the FMU's content and the digest of the code that produced
them (lsdae's package and catalogue for checks); ``fresh=True`` ignores the cache (timings are
then all of this run).
"""
from __future__ import annotations

import hashlib
import json
import logging
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

from scenes.build import SCENES_DIR, SceneBuildError, build_scene

from . import oracle, promises
from .checking import (MAIN, SETTINGS, CheckResult, Setting, new_findings, new_information,
                       outcome, run_check)
from .generate import Mutant
from .targets import _CACHE, IMPLICIT, IMPLICIT_REASON, Target, syntax_errors

log = logging.getLogger(__name__)
REPO_ROOT = Path(__file__).resolve().parents[2]
RESULTS = _CACHE / "results"


def _digest(paths: Iterable[Path]) -> str:
    h = hashlib.sha256()
    for path in sorted(paths):
        h.update(str(path.relative_to(REPO_ROOT)).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:16]


def checker_digest() -> str:
    """lsdae's code and catalogue: a check result is valid while they are unchanged."""
    files = [*(REPO_ROOT / "conformance").rglob("*.py"), *(REPO_ROOT / "rules").glob("*.toml"),
             *(REPO_ROOT / "schemas").rglob("*.xsd")]
    return _digest(files)


def _module_digest(*names: str) -> str:
    here = Path(__file__).resolve().parent
    return _digest(here / f"{n}.py" for n in names)


@dataclass
class Cache:
    fresh: bool = False
    root: Path = RESULTS

    def get(self, key: str, compute: Callable[[], Any]) -> Any:
        path = self.root / f"{key}.json"
        if not self.fresh and path.is_file():
            return json.loads(path.read_text())
        value = compute()
        self.root.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(value))
        return value


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:20]


@dataclass
class Runner:
    """What a campaign needs to run mutants: settings, cache, digests, the originals."""
    cache: Cache
    settings: tuple[str, ...] = (MAIN,)
    check_timeout: float = 300.0
    originals: dict[str, dict[str, Any]] = field(default_factory=dict)
    _checker: str = field(default_factory=checker_digest)
    _oracle: str = field(default_factory=lambda: _module_digest("oracle", "fmu_view"))
    _promises: str = field(default_factory=lambda: _module_digest(
        "promises", "promise_calls", "promise_jacobian", "fmu_view"))

    def observe(self, fmu: Path) -> dict[str, Any]:
        return self.cache.get(f"oracle-{_sha(fmu)}-{self._oracle}", lambda: oracle.observe(fmu))

    def check(self, fmu: Path, setting: Setting) -> CheckResult:
        key = hashlib.sha256(json.dumps([setting.args, setting.seeds]).encode()).hexdigest()
        data = self.cache.get(f"check-{_sha(fmu)}-{key[:12]}-{self._checker}",
                              lambda: run_check(fmu, setting, timeout=self.check_timeout)
                              .to_json())
        return CheckResult.from_json(data)

    def promises(self, fmu: Path) -> dict[str, str]:
        return self.cache.get(f"promises-{_sha(fmu)}-{self._promises}",
                              lambda: promises.check(fmu))

    def original(self, host: str) -> dict[str, Any]:
        if host not in self.originals:
            fmu = build_scene(host)
            self.originals[host] = {
                "fmu": fmu, "oracle": self.observe(fmu), "promises": self.promises(fmu),
                "checks": {s: self.check(fmu, SETTINGS[s]) for s in self.settings}}
        return self.originals[host]


def build_mutant(m: Mutant) -> tuple[Path | None, str]:
    """(the FMU, "") or (None, why it is stillborn)."""
    text = m.apply((SCENES_DIR / m.source).read_text())
    error = syntax_errors(Target(m.target, m.source, m.host), text)
    if error:
        return None, error
    try:
        fmu = build_scene(m.host, overrides={m.source: text})
    except SceneBuildError as exc:
        errors = [ln for ln in str(exc).splitlines() if "error" in ln]
        return None, (errors[0].split("error:", 1)[-1].strip() if errors else "compile error")
    if IMPLICIT in (fmu.parent / "build.log").read_text():
        return None, IMPLICIT_REASON
    return fmu, ""


def run_mutant(runner: Runner, m: Mutant) -> dict[str, Any]:
    """The record of one mutant at the runner's main setting."""
    rec: dict[str, Any] = m.to_json()
    fmu, why = build_mutant(m)
    if fmu is None:
        rec.update(outcome="stillborn", build_detail=why)
        return rec
    orig = runner.original(m.host)
    obs = runner.observe(fmu)
    if obs["status"] != "ok":
        diffs = [f"the oracle's run {obs['status']}"]
    else:
        diffs = oracle.differences(orig["oracle"]["obs"], obs["obs"])
    rec["oracle_detail"] = diffs
    rec["fmu"] = str(fmu)
    result = runner.check(fmu, SETTINGS[MAIN])
    rec["checks"] = {MAIN: result.to_json()}
    new = new_findings(orig["checks"][MAIN], result)
    rec["killed_by"] = sorted([c, s, n] for (c, s), n in new.items())
    verdict = outcome(orig["checks"][MAIN], result)
    if not diffs:
        rec["outcome"] = "equivalent"
        rec["equivalent_but_reported"] = verdict == "killed"
        return rec
    rec["outcome"] = verdict
    if verdict == "informed":
        rec["informed_by"] = sorted([c, s, n] for (c, s), n in
                                    new_information(orig["checks"][MAIN], result).items())
    if verdict == "survived":
        mine, theirs = runner.promises(fmu), orig["promises"]
        rec["promises"] = {k: v for k, v in mine.items() if k not in theirs}
    return rec


def run_all(runner: Runner, mutants: list[Mutant], *, jobs: int) -> list[dict[str, Any]]:
    """Every mutant's record, in the order given; the originals are prepared first."""
    for host in sorted({m.host for m in mutants}):
        runner.original(host)
    done = 0

    def one(m: Mutant) -> dict[str, Any]:
        nonlocal done
        rec = run_mutant(runner, m)
        done += 1
        log.info("[%d/%d] %s %s", done, len(mutants), rec["outcome"], m.id)
        return rec

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        return list(pool.map(one, mutants))
