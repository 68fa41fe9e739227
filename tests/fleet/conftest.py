"""Helpers of the fleet tests: run lsdae in this process, write every format, compare them."""
from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

from conformance.commands.cli import main
from conformance.reporters import REPORTER_BY_NAME
from scenes.build import build_scene
from tests.fixturekit import all_cases, materialise

#: Scenes with binaries (checked with --no-probes but for the probe case) of different sizes.
SCENES = ("HelloWorldDAE", "SimpleDAE", "VanDerPolDAE", "Robertson", "FourBar")


def lsdae(*args: str) -> tuple[int, str, str]:
    """``lsdae ARGS`` in this process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def every_format(folder: Path) -> list[str]:
    """``--format NAME:FILE`` for every reporter, the files in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    return [a for name in REPORTER_BY_NAME for a in ("--format", f"{name}:{folder / name}")]


# Timings and the facts of the run (when, where) are the only things a merge may change.
_TIMINGS = [
    (re.compile(r'\b(time|timestamp|hostname)="[^"]*"'), r'\1="?"'),            # JUnit
    (re.compile(r'<td class="num">[0-9.]+</td>'), '<td class="num">?</td>'),   # HTML durations
    (re.compile(r"<tr><th>(started|host)</th><td>[^<]*</td></tr>"), r"<tr><th>\1</th>?</tr>"),
    (re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\+00:00|Z)?"), "TIMESTAMP"),
]


def outputs(folder: Path) -> dict[str, str]:
    """Every format's text from ``folder``, timings normalised."""
    texts = {}
    for name in REPORTER_BY_NAME:
        text = (folder / name).read_text(encoding="utf-8")
        for pattern, repl in _TIMINGS:
            text = pattern.sub(repl, text)
        texts[name] = text
    return texts


@pytest.fixture(scope="session")
def scene_fmus() -> list[str]:
    return [str(build_scene(name)) for name in SCENES]


@pytest.fixture(scope="session")
def fixture_fmus(tmp_path_factory) -> list[str]:
    """Every rule fixture, failing and passing, as an FMU folder or .fmu file."""
    root = tmp_path_factory.mktemp("fixtures")
    return [str(materialise(case, root / case.id.replace("/", "_"))) for case in all_cases()]
