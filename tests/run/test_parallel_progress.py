"""-j N: same output as -j 1, input order, crashes become findings; the progress display."""
from __future__ import annotations

import io
import re

import pytest

from conformance.report.catalogue import default_catalogue
from conformance.commands.cli import main
from conformance.run.engine import EngineOptions
from conformance.run.parallel import check_all
from conformance.run.progress import Progress
from tests.run import workers
from tests.fixtures import BOOLEAN_DAE, INT_DAE

STATIC = EngineOptions(probes=False)


_TIMESTAMP = re.compile(rb"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d+)?(?:Z|[+-]\d\d:\d\d)")


@pytest.fixture
def several(fmu, tmp_path):
    """Five FMUs, some clean, some faulty, plus a path that does not exist."""
    paths = [fmu("a"), fmu("b", edits=((BOOLEAN_DAE, INT_DAE),)), fmu("c", manifest=False),
             fmu("d"), fmu("e", edits=(('name="x" valueReference="2"',
                                        'name="x" valueReference="1"'),))]
    return [str(p) for p in paths] + [str(tmp_path / "missing.fmu")]


@pytest.mark.parametrize("fmt", ["json", "console", "sarif", "markdown"])
def test_parallel_output_equals_serial(several, tmp_path, fmt):
    outputs = []
    for jobs in ("1", "3"):
        out = tmp_path / f"j{jobs}.{fmt}"
        code = main(["check", *several, "--no-probes", "-j", jobs, "--color", "never",
                     "--format", f"{fmt}:{out}"])
        # the run's start time (to the second) is the only thing two runs may differ in: a
        # serial run on a loaded machine takes more than a second
        outputs.append((code, _TIMESTAMP.sub(b"<started>", out.read_bytes())))
    assert outputs[0] == outputs[1]
    assert outputs[0][0] == 1


def test_results_keep_input_order(several):
    report = check_all(list(reversed(several)), options=STATIC, catalogue=default_catalogue(),
                       jobs=4)
    assert [f.path for f in report.fmus] == list(reversed(several))


def test_a_dying_worker_costs_only_its_own_fmu(fmu):
    paths = [str(fmu("ok1")), str(fmu("crash-me")), str(fmu("ok2")), str(fmu("ok3"))]
    durations: dict[str, float] = {}
    report = check_all(paths, options=STATIC, catalogue=default_catalogue(), jobs=2,
                       worker=workers.crash_on_marked, durations=durations)
    assert [f.path for f in report.fmus] == paths
    by_path = {f.path: f for f in report.fmus}
    assert [f.code for f in by_path[paths[1]].findings] == ["DAE099"]
    for p in (paths[0], paths[2], paths[3]):
        assert by_path[p].findings == () and by_path[p].draft == "alpha1"
    assert set(durations) == set(paths)


def test_an_exception_in_a_worker_is_a_finding(fmu):
    paths = [str(fmu("ok")), str(fmu("raise-me"))]
    report = check_all(paths, options=STATIC, catalogue=default_catalogue(), jobs=2,
                       worker=workers.raise_on_marked)
    assert report.fmus[0].findings == ()
    [finding] = report.fmus[1].findings
    assert finding.code == "DAE099" and "RuntimeError" in finding.message
    serial = check_all(paths, options=STATIC, catalogue=default_catalogue(), jobs=1,
                       worker=workers.raise_on_marked)
    assert serial == report


def test_workers_may_start_processes_of_their_own(fmu):
    """The probe runner starts a process per FMU; pool workers must be allowed to."""
    paths = [str(fmu("p1")), str(fmu("p2"))]
    report = check_all(paths, options=STATIC, catalogue=default_catalogue(), jobs=2,
                       worker=workers.spawn_child)
    assert all(f.findings == () for f in report.fmus)


def test_bad_selection_fails_before_any_worker_starts(several):
    with pytest.raises(ValueError):
        check_all(several, options=EngineOptions(select=("NOPE9",)),
                  catalogue=default_catalogue(), jobs=2)


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_line_counts_and_is_erased(several):
    stream = _Tty()
    check_all(several, options=STATIC, catalogue=default_catalogue(),
              progress=Progress(len(several), stream=stream))
    text = stream.getvalue()
    assert f"[0/{len(several)}]" in text and f"[{len(several) - 1}/{len(several)}]" in text
    assert text.endswith("\r")  # the line is blanked before the report is printed


def test_progress_goes_to_stderr_never_stdout(several, capsys, monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    main(["check", *several[:2], "--no-probes", "--progress", "always", "--format", "json"])
    out, err = capsys.readouterr()
    assert "[1/2]" in err and "[" not in out.splitlines()[0]
    main(["check", *several[:2], "--no-probes", "--format", "json"])  # stderr is not a tty
    assert capsys.readouterr().err == ""
