"""The progress line (conformance/run/progress.py): when it is shown, what it says, and that it is
erased (fast, in this process; the -j runs are in test_parallel_progress.py)."""
from __future__ import annotations

import io
import os

import pytest

from conformance.run import progress as progress_module
from conformance.run.progress import NoProgress, Progress, make_progress, wanted


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


class _Closed(io.StringIO):
    def isatty(self) -> bool:
        raise ValueError("I/O operation on closed file")


def test_progress_only_on_a_terminal_outside_ci(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    assert wanted("auto", total=3, probes=False, stream=_Tty())
    assert wanted("auto", total=1, probes=True, stream=_Tty())
    assert not wanted("auto", total=1, probes=False, stream=_Tty())  # one quick FMU
    assert not wanted("auto", total=3, probes=True, stream=io.StringIO())  # a pipe
    assert not wanted("auto", total=3, probes=True, stream=_Closed())
    assert not wanted("never", total=3, probes=True, stream=_Tty())
    assert wanted("always", total=1, probes=False, stream=io.StringIO())
    monkeypatch.setenv("CI", "true")
    assert not wanted("auto", total=3, probes=True, stream=_Tty())
    assert wanted("always", total=3, probes=True, stream=_Tty())
    quiet = make_progress("auto", total=3, probes=True, stream=_Tty())
    assert type(quiet) is NoProgress and quiet.total == 3
    shown = make_progress("always", total=2, probes=False, stream=_Tty())
    assert type(shown) is Progress and shown.total == 2


def test_the_line_counts_names_and_is_erased(monkeypatch):
    clock = iter([100.0, 101.25, 103.5, 110.0])
    monkeypatch.setattr(progress_module.time, "monotonic", lambda: next(clock))
    monkeypatch.setattr(progress_module, "_columns", lambda: 80)
    stream = _Tty()
    line = Progress(2, stream=stream)
    line.start("a.fmu")
    line.finish("a.fmu")
    line.finish("b.fmu")
    assert stream.getvalue() == ("\r[0/2]   1.2s checking a.fmu"
                                 "\r[1/2]   3.5s checked a.fmu "
                                 "\r[2/2]  10.0s done" + " " * 9)
    width = len("[2/2]  10.0s done")
    line.close()
    assert stream.getvalue().endswith("\r" + " " * width + "\r")
    line.close()                                           # erased once only
    assert stream.getvalue().endswith("done" + " " * 9 + "\r" + " " * width + "\r")


def test_a_long_line_is_cut_to_the_terminal(monkeypatch):
    monkeypatch.setattr(progress_module, "_columns", lambda: 20)
    stream = _Tty()
    Progress(1, stream=stream, label="reading").start("a" * 40)
    text = stream.getvalue()
    assert text.startswith("\r[0/1] ") and text.endswith("…") and len(text) == 1 + 19


def test_no_progress_prints_nothing(capsys):
    quiet = NoProgress(4)
    quiet.start("a")
    quiet.finish("a")
    quiet.close()
    assert quiet.total == 4 and quiet.done == 1
    assert capsys.readouterr() == ("", "")
    assert NoProgress().total == 0


def test_the_width_of_a_terminal_or_eighty(monkeypatch):
    monkeypatch.setattr(progress_module.os, "get_terminal_size",
                        lambda fd: os.terminal_size((132, 40)))
    assert progress_module._columns() == 132

    def no_terminal(fd):
        raise OSError("not a terminal")
    monkeypatch.setattr(progress_module.os, "get_terminal_size", no_terminal)
    assert progress_module._columns() == 80


@pytest.mark.parametrize("mode", ["auto", "always"])
def test_progress_goes_to_stderr_by_default(mode, monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    shown = make_progress("always", total=2, probes=False)
    assert shown.stream is progress_module.sys.stderr
