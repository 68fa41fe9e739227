"""The script behind action.yml: install lsdae, check the FMUs, hand the results to GitHub.

Inputs come from environment variables that action.yml sets from the action's inputs:

    LSDAE_FMUS         glob patterns, separated by whitespace or newlines (** recurses)
    LSDAE_SELECT       rules to select (comma-separated), optional
    LSDAE_IGNORE       rules to ignore (comma-separated), optional
    LSDAE_FAIL_ON      error | warning | never
    LSDAE_PROBES       true | false
    LSDAE_JUNIT        path of a JUnit XML report to write, optional
    LSDAE_SARIF        path of a SARIF report to write, optional
    LSDAE_BASELINE     a baseline file (lsdae check --baseline), optional
    LSDAE_REPORT_DIR   where lsdae.json, lsdae.md and lsdae.html go (default lsdae-report)
    LSDAE_FIX          true | false: also run ``lsdae fix`` (safe fixes) on every FMU; the fixed
                       FMUs and lsdae-fix.diff go to <report-dir>/fixed (action.yml uploads it)
    LSDAE_SHARD        I/N: check only this share of the FMUs (one job of a matrix); the job
                       leaves annotations and the job summary to the merge
    LSDAE_MERGE        glob pattern(s) of shard reports: join them with ``lsdae merge`` instead
                       of checking (the matrix's last job)
    LSDAE_CACHE        true | false: pass --cache-dir LSDAE_CACHE_DIR to ``lsdae check``
    LSDAE_CACHE_DIR    the folder actions/cache restores and saves (set by ``--cache-key``)
    LSDAE_ACTION_PATH  the action's checkout, installed with pip
    LSDAE_ACTION_SKIP_INSTALL=1   use the lsdae importable by this Python instead (tests)

It installs the checker into its own virtual environment under $RUNNER_TEMP (never into the
runner's Python), runs ``lsdae check`` once with every output, streams the ``github`` format to
stdout (the runner turns those lines into annotations), appends the Markdown summary to
$GITHUB_STEP_SUMMARY, writes the counts to $GITHUB_OUTPUT, and exits with lsdae's exit code,
which follows ``fail-on``. Standard library only: it runs before lsdae is installed.

``action_run.py --cache-key`` runs first when the cache is on: it writes the cache folder, the
key (lsdae's version, the runner's OS, the shard, a digest of the FMUs' content) and the
restore-keys (the same without the digest: the newest earlier cache) to $GITHUB_OUTPUT for
actions/cache. lsdae keys every FMU's result itself, so a restored cache never serves a stale
result; the key only decides which folder is restored and saved.
"""
from __future__ import annotations

import glob
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

FAIL_ON = ("error", "warning", "never")
EXIT_USAGE = 2


def _env(name: str, default: str = "") -> str:
    return os.environ.get(name, default).strip()


def expand(patterns: str) -> list[str]:
    """FMU paths matching the whitespace-separated glob patterns, each once, sorted per pattern."""
    found: dict[str, None] = {}
    for pattern in patterns.split():
        matches = sorted(glob.glob(pattern, recursive=True))
        if not matches and Path(pattern).exists():
            matches = [pattern]
        for m in matches:
            found.setdefault(m, None)
    return list(found)


def _lsdae_command() -> list[str]:
    if _env("LSDAE_ACTION_SKIP_INSTALL") in ("1", "true"):
        return [sys.executable, "-m", "conformance"]
    action = _env("LSDAE_ACTION_PATH") or str(Path(__file__).resolve().parent.parent)
    venv = Path(_env("RUNNER_TEMP") or tempfile.gettempdir()) / "lsdae-venv"
    bindir = venv / ("Scripts" if os.name == "nt" else "bin")
    python = bindir / ("python.exe" if os.name == "nt" else "python")
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    print("::group::Install lsdae", flush=True)
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                    action], check=True)
    print("::endgroup::", flush=True)
    return [str(python), "-m", "conformance"]


def _arguments(fmus: list[str], report_dir: Path, fail_on: str) -> list[str]:
    if _env("LSDAE_MERGE"):   # the matrix's last job: the shards' reports are the input
        args = ["merge", *fmus, "--fail-on", fail_on, "--color", "never"]
        if _env("LSDAE_BASELINE"):
            args += ["--baseline", _env("LSDAE_BASELINE")]
        return args + _formats(report_dir)
    args = ["check", *fmus, "--fail-on", fail_on, "--progress", "never", "--color", "never",
            *_formats(report_dir)]
    for env, flag in (("LSDAE_SELECT", "--select"), ("LSDAE_IGNORE", "--ignore"),
                      ("LSDAE_BASELINE", "--baseline"), ("LSDAE_SHARD", "--shard")):
        if _env(env):
            args += [flag, _env(env)]
    if _env("LSDAE_PROBES", "true").lower() == "false":
        args.append("--no-probes")
    if _env("LSDAE_CACHE").lower() == "true" and _env("LSDAE_CACHE_DIR"):
        args += ["--cache-dir", _env("LSDAE_CACHE_DIR")]
    return args


def _formats(report_dir: Path) -> list[str]:
    """The outputs: annotations on stdout (not for a shard: the merge annotates), the JSON,
    Markdown and HTML reports, and JUnit and SARIF when asked for."""
    args = [] if _env("LSDAE_SHARD") else ["--format", "github"]
    args += ["--format", f"json:{report_dir / 'lsdae.json'}",
            "--format", f"markdown:{report_dir / 'lsdae.md'}",
            "--format", f"html:{report_dir / 'lsdae.html'}"]
    for env, fmt in (("LSDAE_JUNIT", "junit"), ("LSDAE_SARIF", "sarif")):
        if _env(env):
            args += ["--format", f"{fmt}:{_env(env)}"]
    return args


def _version() -> str:
    """lsdae's version, read from the action's checkout (lsdae is not installed yet)."""
    action = Path(_env("LSDAE_ACTION_PATH") or Path(__file__).resolve().parent.parent)
    try:
        text = (action / "conformance" / "__init__.py").read_text(encoding="utf-8")
    except OSError:
        return "unknown"
    found = re.search(r'__version__\s*=\s*"([^"]+)"', text)
    return found.group(1) if found else "unknown"


def fmus_digest(fmus: list[str]) -> str:
    """A digest of the FMUs' names and bytes (files of folders included), in sorted order."""
    digest = hashlib.sha256()
    for fmu in sorted(fmus):
        files = [Path(fmu)] if Path(fmu).is_file() else sorted(
            p for p in Path(fmu).rglob("*") if p.is_file() and not p.is_symlink())
        for file in files:
            digest.update(f"{file.as_posix()}\0".encode("utf-8", "surrogateescape"))
            try:
                digest.update(file.read_bytes())
            except OSError:
                digest.update(b"unreadable")
    return digest.hexdigest()[:20]


def cache_key() -> int:
    """``--cache-key``: the folder, key and restore-keys for actions/cache on $GITHUB_OUTPUT."""
    folder = Path(_env("RUNNER_TEMP") or tempfile.gettempdir()) / "lsdae-cache"
    shard = re.sub(r"[^0-9]+", "of", _env("LSDAE_SHARD")) or "all"
    prefix = f"lsdae-{_version()}-{_env('RUNNER_OS') or sys.platform}-{shard}-"
    key = prefix + fmus_digest(expand(_env("LSDAE_FMUS", "**/*.fmu")))
    _append("GITHUB_OUTPUT", f"dir={folder}\nkey={key}\n"
                             f"restore-keys<<LSDAE_EOF\n{prefix}\nLSDAE_EOF\n")
    print(f"lsdae: cache key {key}", flush=True)
    return 0


def fix_all(lsdae: list[str], fmus: list[str], report_dir: Path) -> Path:
    """``lsdae fix`` on every FMU: the fixed copies (only those that changed) and one diff."""
    fixed = report_dir / "fixed"
    fixed.mkdir(parents=True, exist_ok=True)
    diffs: list[str] = []
    print("::group::lsdae fix", flush=True)
    for fmu in fmus:
        done = subprocess.run([*lsdae, "fix", fmu, "--diff", "--no-probes", "--color", "never"],
                              capture_output=True, text=True, check=False)
        sys.stdout.write(done.stderr)
        if done.returncode == EXIT_USAGE or not done.stdout:
            continue
        diffs.append(done.stdout)
        name = fmu.strip("/").replace("/", "__") or "fmu"
        subprocess.run([*lsdae, "fix", fmu, "-o", str(fixed / name), "--no-probes",
                        "--color", "never", "--fail-on", "never"], capture_output=True,
                       check=False)
    print("::endgroup::", flush=True)
    (fixed / "lsdae-fix.diff").write_text("".join(diffs), encoding="utf-8")
    return fixed


def counts(report: dict) -> dict[str, int]:
    """Findings by severity, leaving out those a baseline accepted."""
    out = {"errors": 0, "warnings": 0, "infos": 0, "baselined": 0,
           "fmus": len(report.get("fmus", ()))}
    key = {"error": "errors", "warning": "warnings", "info": "infos"}
    for fmu in report.get("fmus", ()):
        for f in fmu.get("findings", ()):
            if (f.get("evidence") or {}).get("baselined"):
                out["baselined"] += 1
            else:
                out[key[f["severity"]]] += 1
    return out


def _append(env: str, text: str) -> None:
    target = _env(env)
    if not target:
        return
    with open(target, "a", encoding="utf-8") as handle:
        handle.write(text)


def _outputs(values: dict[str, object]) -> None:
    _append("GITHUB_OUTPUT", "".join(f"{k}={v}\n" for k, v in values.items()))


def main() -> int:
    if sys.argv[1:] == ["--cache-key"]:
        return cache_key()
    fail_on = _env("LSDAE_FAIL_ON", "error").lower() or "error"
    if fail_on not in FAIL_ON:
        print(f"::error title=lsdae::fail-on must be one of {', '.join(FAIL_ON)}, "
              f"not {fail_on!r}")
        return EXIT_USAGE
    if _env("LSDAE_PROBES", "true").lower() not in ("true", "false"):
        print("::error title=lsdae::probes must be true or false")
        return EXIT_USAGE
    merging = bool(_env("LSDAE_MERGE"))
    what = "LSDAE_MERGE" if merging else "LSDAE_FMUS"
    fmus = expand(_env(what, "**/*.fmu"))
    report_dir = Path(_env("LSDAE_REPORT_DIR") or "lsdae-report")
    report_dir.mkdir(parents=True, exist_ok=True)
    if not fmus:
        name = "merge" if merging else "fmus"
        print(f"::error title=lsdae::no {'shard report' if merging else 'FMU'} matches "
              f"{_env(what, '**/*.fmu')!r}")
        _outputs({"errors": 0, "warnings": 0, "infos": 0, "baselined": 0, "fmus": 0,
                  "report-dir": report_dir})
        _append("GITHUB_STEP_SUMMARY", f"**lsdae**: nothing matched the `{name}` pattern.\n")
        return EXIT_USAGE
    lsdae = _lsdae_command()
    command = lsdae + _arguments(fmus, report_dir, fail_on)
    print(f"lsdae: {'merging' if merging else 'checking'} {len(fmus)} "
          f"{'shard report' if merging else 'FMU'}{'s' if len(fmus) != 1 else ''}", flush=True)
    code = subprocess.run(command).returncode
    json_path, md_path = report_dir / "lsdae.json", report_dir / "lsdae.md"
    try:
        report = json.loads(json_path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        print(f"::error title=lsdae::no report was written ({exc}); exit code {code}")
        return code or EXIT_USAGE
    values: dict[str, object] = dict(counts(report))
    values.update({"report-dir": report_dir, "json": json_path, "markdown": md_path,
                   "html": report_dir / "lsdae.html"})
    _outputs(values)
    if md_path.is_file() and not _env("LSDAE_SHARD"):   # a shard's summary is the merge's
        _append("GITHUB_STEP_SUMMARY", md_path.read_text(encoding="utf-8") + "\n")
    if _env("LSDAE_FIX").lower() == "true" and not merging:
        fix_all(lsdae, fmus, report_dir)
    return code


if __name__ == "__main__":
    sys.exit(main())
