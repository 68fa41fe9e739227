"""``[tool.lsdae]`` (conformance/commands/config.py): which pyproject.toml is read, and what it
may hold."""
from __future__ import annotations

import pytest

from conformance.commands.config import ConfigError, FileConfig, find_pyproject, load_config


def test_the_nearest_pyproject_with_a_tool_lsdae_table_is_read(tmp_path):
    inner = tmp_path / "a" / "b"
    inner.mkdir(parents=True)
    top = tmp_path / "pyproject.toml"
    top.write_text('[tool.lsdae]\nfail-on = "warning"\nbaseline = "ci/b.json"\n',
                   encoding="utf-8")
    # nearer ones without the table: no [tool] at all, another tool's, unreadable TOML
    (inner / "pyproject.toml").write_text('[project]\nname = "x"\n', encoding="utf-8")
    (tmp_path / "a" / "pyproject.toml").write_text('[tool.other]\nx = 1\n', encoding="utf-8")
    assert find_pyproject(inner) == top
    (tmp_path / "a" / "pyproject.toml").write_text("[tool.lsdae\n", encoding="utf-8")
    assert find_pyproject(inner) == top
    assert load_config(start=inner) == FileConfig(
        top, {"fail-on": "warning", "baseline": str(tmp_path / "ci" / "b.json")})


def test_non_ascii_config_is_read_as_utf8(tmp_path):
    (tmp_path / "pyproject.toml").write_bytes(
        '[tool.lsdae]\nbaseline = "Grundlinie-\u00e4\u00f6\u00fc.json"\n'.encode("utf-8"))
    assert find_pyproject(tmp_path) == tmp_path / "pyproject.toml"
    assert load_config(start=tmp_path).values == {
        "baseline": str(tmp_path / "Grundlinie-\u00e4\u00f6\u00fc.json")}


def test_a_named_config_that_cannot_be_read_is_an_error(tmp_path):
    with pytest.raises(ConfigError) as error:
        load_config(tmp_path / "missing.toml")
    assert str(error.value).startswith(f"cannot read configuration {tmp_path / 'missing.toml'}: ")


@pytest.mark.parametrize("table, message", [
    ('baseline = ""', "baseline must be a file name"),
    ('endurance = "forever"', "endurance must be one of off, quick, long"),
    ('fail-on = "sometimes"', "fail-on must be one of error, warning, never"),
    ('jobs = -1', "jobs must be a positive integer"),
])
def test_bad_run_keys(tmp_path, table, message):
    path = tmp_path / "pyproject.toml"
    path.write_text(f"[tool.lsdae]\n{table}\n", encoding="utf-8")
    with pytest.raises(ConfigError) as error:
        load_config(path)
    assert str(error.value) == f"{path}: [tool.lsdae] {message}"
