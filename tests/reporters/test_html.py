"""The HTML reporter: self-contained, deterministic, plots from probe info, opened in Chromium."""
from __future__ import annotations

import base64
import os
import re
import shutil
import subprocess
from html import escape
from html.parser import HTMLParser
from pathlib import Path

import pytest

from conformance.model.drafts.names import DRAFT_LABELS
from conformance.report.catalogue import default_catalogue
from conformance.report.findings import (Finding, FmuReport, Location, Report, RunInfo, Severity,
                                        evidence)
from conformance.reporters import REPORTER_BY_NAME
from conformance.reporters.html import _verdict, render

CATALOGUE = default_catalogue()


def _finding(code: str, severity: Severity, message: str, **kw) -> Finding:
    return Finding(code, CATALOGUE[code].name, severity, message, **kw)


def sample_report(*, baselined: bool = True) -> Report:
    """Two FMUs: one with findings and probe data, one clean without probes."""
    rows = ["der(x1)", "der(x2)", "r1", "r2"]
    cols = ["x1", "x2", "w1", "w2", "u"]
    declared = [[0, 1], [1, 0], [1, 2], [2, 0], [2, 2], [3, 1], [3, 3], [3, 4]]
    observed = [[0, 1], [1, 0], [1, 2], [2, 0], [2, 2], [2, 3], [3, 1], [3, 3]]
    errors = [
        {"rule": "DAE701", "entry": "r1 at start", "error": 3e-13, "tolerance": 1e-8},
        {"rule": "DAE702", "entry": "d(r1)/d(w2)", "error": 0.5, "tolerance": 1e-6},
        {"rule": "DAE702", "entry": "d(der(x2))/d(w1)", "error": 2e-9, "tolerance": 1e-6},
        {"rule": "DAE703", "entry": "der(x1) ODE vs DAE", "error": 0.0, "tolerance": 1e-8},
        {"rule": "DAE703", "entry": "der(x2) ODE vs DAE", "error": float("nan"),
         "tolerance": 1e-8},
    ]
    mark = evidence(baselined=True) if baselined else ()
    findings = (
        _finding("DAE203", Severity.ERROR, "enable parameter 'dae' is a <Float64>, not a "
                 "<Boolean> <script>alert(1)</script>",
                 location=Location("modelDescription.xml", 12, None,
                                   "/fmiModelDescription/ModelVariables/Float64[@name='dae']",
                                   '<Float64 name="dae" valueReference="1" '
                                   'causality="structuralParameter"/>'),
                 evidence=evidence(value_reference=1, type="Float64"), subject="dae"),
        _finding("DAE104", Severity.WARNING, "the manifest's 'fmi-ls-description' differs",
                 location=Location("extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml", 2,
                                   snippet="<fmiDAEManifest"), evidence=mark),
        _finding("DAE091", Severity.INFO, "no manifest: a Co-Simulation FMU that does not use "
                 "the DAE layer"),
    )
    first = FmuReport("build/demo/Broken.fmu", "alpha1", findings, rules_run=("DAE203",),
                      info=evidence(model_name="Broken", fmi_version="3.0", variables=9,
                                    jacobian={"rows": rows, "cols": cols, "declared": declared,
                                              "observed": observed},
                                    probe_errors=errors, seed=0))
    second = FmuReport("build/demo/Clean.fmu", "alpha1", (),
                       rules_skipped=(("DAE701", "probes turned off (--no-probes)"),),
                       info=evidence(model_name="Clean"))
    return Report("0.1.0", (first, second), options=evidence(draft="auto", probes=True,
                                                             seed=0))


class _Collect(HTMLParser):
    VOID = {"meta", "img", "br", "hr", "link", "input"}

    def __init__(self) -> None:
        super().__init__()
        self.stack: list[str] = []
        self.tags: list[tuple[str, dict]] = []
        self.errors: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
        else:
            self.stack.pop()


def _parse(page: str) -> _Collect:
    parser = _Collect()
    parser.feed(page)
    parser.close()
    assert parser.errors == [] and parser.stack == [], (parser.errors, parser.stack)
    return parser


def test_registered():
    assert REPORTER_BY_NAME["html"] is render


def test_page_is_self_contained_and_well_nested():
    page = render(sample_report(), CATALOGUE)
    parsed = _parse(page)
    assert not any(tag == "script" for tag, _ in parsed.tags)
    assert "Content-Security-Policy" in page
    for tag, attrs in parsed.tags:
        for name in ("src", "href"):
            value = attrs.get(name)
            if value is not None:
                assert value.startswith(("data:", "#")), (tag, value[:80])
    assert "<script>alert(1)</script>" not in page  # messages are escaped


def test_plots_are_decodable_images():
    parsed = _parse(render(sample_report(), CATALOGUE))
    images = [attrs["src"] for tag, attrs in parsed.tags if tag == "img"]
    assert len(images) == 2  # the sparsity and the error plot of the first FMU
    for uri in images:
        mime, _, payload = uri.partition(";base64,")
        data = base64.b64decode(payload)
        assert mime == "data:image/svg+xml" and data.lstrip().startswith(b"<?xml")
        # namespace names are not fetched; a reference to another resource would be
        assert not re.search(rb'(href|src)="(?!#)', data), "the plot refers outside itself"


def test_deterministic_apart_from_run_info():
    report = sample_report()
    assert render(report, CATALOGUE) == render(report, CATALOGUE)
    a = render(report, CATALOGUE, run=RunInfo("2026-01-01T00:00:00+00:00", "a",
                                              (("build/demo/Broken.fmu", 1.0),)))
    b = render(report, CATALOGUE, run=RunInfo("2026-02-02T00:00:00+00:00", "b",
                                              (("build/demo/Broken.fmu", 2.0),)))
    assert len(a.splitlines()) == len(b.splitlines())
    differ = [(x, y) for x, y in zip(a.splitlines(), b.splitlines(), strict=True) if x != y]
    assert all("2026-0" in x or "1.00" in x for x, _ in differ), differ


def test_verdict_counts_and_baseline_marks():
    page = render(sample_report(), CATALOGUE)
    assert "Not conformant: 1 error, 0 warnings (1 more accepted by the baseline)" in page
    assert page.count('class="badge baselined"') == 1
    clean = Report("0.1.0", (sample_report().fmus[1],))
    assert "Conformant: no errors or warnings" in render(clean, CATALOGUE)


def test_no_probe_data_is_said_not_drawn():
    page = render(Report("0.1.0", (sample_report().fmus[1],)), CATALOGUE)
    assert "<img" not in page
    assert "No probe data: probes turned off (--no-probes)." in page


def test_large_jacobian_is_a_png():
    n = 80
    jac = {"rows": [f"r{i}" for i in range(n)], "cols": [f"c{i}" for i in range(n)],
           "declared": [[i, j] for i in range(n) for j in range(n) if (i + j) % 2 == 0],
           "observed": [[i, j] for i in range(n) for j in range(n) if (i + j) % 2 == 0]}
    fmu = FmuReport("big.fmu", "alpha1", (), info=evidence(jacobian=jac))
    page = render(Report("0.1.0", (fmu,)), CATALOGUE)
    assert "data:image/png;base64," in page
    assert render(Report("0.1.0", (fmu,)), CATALOGUE) == page


def test_malformed_probe_data_does_not_break_the_page():
    fmu = FmuReport("odd.fmu", "alpha1", (), info=evidence(
        jacobian={"rows": ["a"], "cols": ["b"], "declared": [[5, 5]], "observed": []},
        probe_errors=[{"rule": "DAE701", "entry": "x", "error": "oops", "tolerance": 1}]))
    page = render(Report("0.1.0", (fmu,)), CATALOGUE)
    assert page.count("could not be plotted") == 2
    _parse(page)


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") \
        or shutil.which("google-chrome")


@pytest.fixture
def chromium() -> str:
    """The browser; on CI (``CI`` set) its absence fails the test instead of skipping it, since
    ``.ci/run`` installs Debian's chromium and nothing else guards the page in a browser."""
    found = _chromium()
    if found is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is not installed, and CI must open the HTML report in a "
                        "browser (.ci/run installs Debian's chromium)")
        pytest.skip("chromium is not installed")
    return found


def test_opens_in_headless_chromium_without_console_messages(tmp_path, chromium):
    page = tmp_path / "report.html"
    page.write_text(render(sample_report(), CATALOGUE, run=RunInfo(
        "2026-01-01T00:00:00+00:00", "ci", (("build/demo/Broken.fmu", 0.42),))), "utf-8")
    shot = Path(os.environ.get("LSDAE_HTML_SCREENSHOT", tmp_path / "report.png"))
    log = _headless(chromium, page, shot, tmp_path)
    console = [line for line in log.splitlines() if ":CONSOLE" in line]
    assert console == [], console
    assert shot.is_file() and shot.stat().st_size > 10_000
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_chromium_check_would_see_a_network_fetch(tmp_path, chromium):
    """The console check is not vacuous: the page's CSP turns a remote image into a message."""
    page = tmp_path / "bad.html"
    good = render(Report("0.1.0", (sample_report().fmus[1],)), CATALOGUE)
    page.write_text(good.replace("</main>", '<img src="https://example.invalid/x.png"></main>'),
                    "utf-8")
    log = _headless(chromium, page, tmp_path / "bad.png", tmp_path)
    assert re.search(r":CONSOLE.*Content Security Policy", log), log[-2000:]


def _headless(browser: str, page: Path, shot: Path, tmp_path: Path) -> str:
    # No background networking, component updates, sync or QUIC: on a machine whose network is
    # closed they only add refused connections to the log.
    cmd = [browser, "--headless=new", "--no-sandbox", "--disable-gpu",
           "--no-first-run", "--no-default-browser-check", "--disable-extensions",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--disable-quic",
           f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
           "--hide-scrollbars", "--window-size=1280,2400", f"--screenshot={shot}",
           page.as_uri()]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    return done.stdout + done.stderr


def test_simulation_trajectory_is_drawn_with_both_modes():
    sim = {"mode": "dae", "status": "stopped", "t_end": 0.8, "rtol": 1e-6, "steps": 40,
           "times": [0.0, 0.4, 0.8], "series": {"y1": [2.0, 1.7, 1.0], "y2": [0.0, -1.0, -9.0]},
           "ode": {"times": [0.0, 0.4, 0.8], "series": {"y1": [2.0, 1.7, 1.1]}}}
    fmu = FmuReport(path="vdp.fmu", draft="alpha1", findings=(),
                    info=evidence(simulation=sim))
    page = render(Report(tool_version="0", fmus=(fmu,)))
    assert "<h3>Simulation</h3>" in page
    images = re.findall(r'<img src="data:image/svg\+xml;base64,([^"]+)"', page)
    assert images and all(base64.b64decode(i).startswith(b"<?xml") for i in images)
    assert "stopped at t = 0.8" in page


def test_no_simulation_no_section():
    page = render(Report(tool_version="0", fmus=(FmuReport(path="a.fmu", draft=None,
                                                             findings=()),)))
    assert "<h3>Simulation</h3>" not in page


def test_an_fmu_whose_binary_was_not_checked_says_why():
    checked = FmuReport(path="a.fmu", draft="alpha1", findings=(), rules_run=("DAE701",))
    unchecked = FmuReport(path="b.fmu", draft="alpha1", findings=(),
                          info=evidence(probes="not run: no binary for x86_64-linux"))
    page = render(Report(tool_version="1", fmus=(checked, unchecked)), CATALOGUE)
    assert page.count("Binary not checked:") == 1
    section = page[page.index('id="fmu-2"'):]
    assert "Binary not checked:</strong> no binary for x86_64-linux" in section


def test_each_finding_shows_the_basis_its_severity_rests_on():
    """Issue 29: the rule's basis, or the basis of the finding's part when it has one."""
    from html import escape

    rule = CATALOGUE["unsafe-archive-path"]
    part = rule.parts[0]
    findings = (_finding(rule.code, rule.severity, "an absolute name", subject="/etc/x"),
                _finding(rule.code, part.severity, "a link", subject="l", part=part.part))
    page = render(Report("0.1", (FmuReport("a.fmu", "alpha1", findings),)), CATALOGUE,
                  run=RunInfo())
    assert escape(f"{rule.basis.describe()} ({rule.severity})") in page
    assert escape(f"{part.describe()} ({part.severity})") in page


# --- field by field: the verdict, the tables' headings, each finding's severity -------------

def _counts(error=0, warning=0, info=0, baselined=0) -> dict[str, int]:
    return {"error": error, "warning": warning, "info": info, "baselined": baselined}


def test_verdict_texts_and_classes():
    assert _verdict(_counts()) == ("Conformant: no errors or warnings", "pass")
    assert _verdict(_counts(info=3, baselined=2)) == (
        "Conformant: no errors or warnings (2 more accepted by the baseline)", "pass")
    assert _verdict(_counts(warning=1)) == ("Conformant, with 1 warning", "warn")
    assert _verdict(_counts(warning=2, baselined=1)) == (
        "Conformant, with 2 warnings (1 more accepted by the baseline)", "warn")
    assert _verdict(_counts(error=2, warning=1)) == ("Not conformant: 2 errors, 1 warning",
                                                     "fail")


def test_fmu_sections_name_their_facts_headings_findings_and_rules():
    page = render(sample_report(), CATALOGUE)
    assert ("<tr><th>FMU</th><th>draft</th><th>errors</th><th>warnings</th><th>infos</th>"
            "<th>baselined</th><th>verdict</th></tr>") in page
    first = page[page.index('id="fmu-1"'):page.index('id="fmu-2"')]
    second = page[page.index('id="fmu-2"'):]
    label = escape(DRAFT_LABELS["alpha1"])
    assert (f'<p class="meta">draft: {label} · model name: Broken · fmi version: 3.0 · '
            "variables: 9</p>") in first
    assert [line for line in first.splitlines() if "<h3>" in line] == [
        "<h3>Findings (3)</h3>", "<h3>DAE Jacobian: declared versus observed sparsity</h3>",
        "<h3>Probe errors against tolerance</h3>"]
    assert re.findall(r'<article class="([^"]*)">', first) == [
        "finding error", "finding warning baselined", "finding info"]
    assert ('<div class="head"><span class="badge error">error</span> <code>DAE203</code> '
            "enable-parameter-not-boolean</div>") in first
    assert ("<details><summary>Rules run (1) and skipped (0)</summary>"
            "<p><code>DAE203</code></p></details>\n</section>") in first
    assert ("<details><summary>Rules run (0) and skipped (1)</summary><p><code>none</code></p>"
            "<table><tr><th>rule</th><th>reason</th></tr><tr><td><code>DAE701</code></td>"
            "<td>probes turned off (--no-probes)</td></tr></table></details>") in second
