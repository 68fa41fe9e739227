"""``[tool.lsdae]`` in pyproject.toml: the same options as the command line, which wins.

```toml
[tool.lsdae]
select = ["DAE2", "DAE601"]
ignore = ["ls-description-mismatch"]
severity = { DAE302 = "warning" }
draft = "auto"
probes = true
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

KEYS = {"select", "ignore", "severity", "draft", "probes"}


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
    return FileConfig(Path(path), dict(table))
