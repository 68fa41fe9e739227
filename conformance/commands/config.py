"""``[tool.lsdae]`` in pyproject.toml: the same options as the command line, which wins.

```toml
[tool.lsdae]
select = ["DAE2", "DAE601"]
ignore = ["ls-description-mismatch"]
severity = { DAE302 = "warning" }
draft = "auto"
probes = true
endurance = "quick"      # off | quick | long: the budget of the endurance probes
fail-on = "error"        # error | warning | never: the least severity that fails the run
exit-zero = false        # exit 0 even with failing findings (usage errors still exit 2)
baseline = "lsdae-baseline.json"   # relative to this pyproject.toml
jobs = 4                 # FMUs checked in parallel processes
```
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

KEYS = {"select", "ignore", "severity", "draft", "probes", "fail-on", "exit-zero", "baseline",
        "jobs", "rule-options", "endurance"}
FAIL_ON = ("error", "warning", "never")
ENDURANCE_LEVELS = ("off", "quick", "long")


class ConfigError(Exception):
    """The configuration file is unreadable or has unknown keys."""


@dataclass(frozen=True)
class FileConfig:
    path: Path | None = None
    values: dict[str, Any] = field(default_factory=dict)


def find_pyproject(start: Path) -> Path | None:
    """The nearest pyproject.toml at or above ``start`` that has a [tool.lsdae] table."""
    for folder in (start, *start.parents):
        candidate = folder / "pyproject.toml"
        if candidate.is_file():
            try:
                data = tomllib.loads(candidate.read_text(encoding="utf-8"))
            except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
                continue
            if "lsdae" in data.get("tool", {}):
                return candidate
    return None


def load_config(path: Path | None = None, *, start: Path | None = None) -> FileConfig:
    """Read ``[tool.lsdae]`` from ``path`` or from the nearest pyproject.toml."""
    if path is None:
        path = find_pyproject(start or Path.cwd())
        if path is None:
            return FileConfig()
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"cannot read configuration {path}: {exc}") from None
    table = data.get("tool", {}).get("lsdae", {})
    unknown = set(table) - KEYS
    if unknown:
        raise ConfigError(f"{path}: unknown key(s) in [tool.lsdae]: {', '.join(sorted(unknown))}")
    for key in ("select", "ignore"):
        if key in table and not (isinstance(table[key], list)
                                 and all(isinstance(v, str) for v in table[key])):
            raise ConfigError(f"{path}: [tool.lsdae] {key} must be a list of strings")
    if "severity" in table and not isinstance(table["severity"], dict):
        raise ConfigError(f"{path}: [tool.lsdae] severity must be a table CODE = \"level\"")
    if "rule-options" in table and not (
            isinstance(table["rule-options"], dict)
            and all(isinstance(v, dict) for v in table["rule-options"].values())):
        raise ConfigError(f"{path}: [tool.lsdae.rule-options] takes one table per rule, e.g. "
                          "[tool.lsdae.rule-options.DAE740] rtol = 1e-4")
    values = dict(table)
    _check_run_keys(values, Path(path))
    return FileConfig(Path(path), values)


def _check_run_keys(values: dict[str, Any], path: Path) -> None:
    """Validate the keys that decide the exit code and the run; resolve the baseline path."""
    if "fail-on" in values and values["fail-on"] not in FAIL_ON:
        raise ConfigError(f"{path}: [tool.lsdae] fail-on must be one of {', '.join(FAIL_ON)}")
    if "endurance" in values and values["endurance"] not in ENDURANCE_LEVELS:
        raise ConfigError(f"{path}: [tool.lsdae] endurance must be one of "
                          f"{', '.join(ENDURANCE_LEVELS)}")
    if "exit-zero" in values and not isinstance(values["exit-zero"], bool):
        raise ConfigError(f"{path}: [tool.lsdae] exit-zero must be true or false")
    jobs = values.get("jobs", 1)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ConfigError(f"{path}: [tool.lsdae] jobs must be a positive integer")
    if "baseline" in values:
        if not isinstance(values["baseline"], str) or not values["baseline"]:
            raise ConfigError(f"{path}: [tool.lsdae] baseline must be a file name")
        values["baseline"] = str(path.parent / values["baseline"])
