"""Markdown job summary: table counts match the JSON report, text is escaped, size bounded."""
from __future__ import annotations

import json
import re
from dataclasses import replace

from conformance.report.findings import FmuReport, Report, Severity
from conformance.reporters import REPORTER_BY_NAME, json_report, markdown
from tests.reporters.samples import (
    SAMPLE_CATALOGUE,
    SAMPLE_RUN,
    compare_expected,
    new_counts,
    sample_report,
)


def _rows(text: str) -> list[list[str]]:
    """The summary table's body rows, split at unescaped pipes (GitHub's reading)."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|---|")) + 1
    rows = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        cells = re.split(r"(?<!\\)\|", line.strip())[1:-1]
        rows.append([c.strip() for c in cells])
    return rows


def test_registered():
    assert REPORTER_BY_NAME["markdown"] is markdown.render


def test_sample_matches_saved_output():
    compare_expected("sample.md", markdown.render(sample_report(), SAMPLE_CATALOGUE,
                                                  run=SAMPLE_RUN))


def test_engine_report_matches_saved_output(engine):
    compare_expected("engine.md", markdown.render(engine))


def test_table_matches_the_json_report(engine):
    for report, columns in ((sample_report(), 7), (engine, 6)):  # 'baselined' when needed
        data = json.loads(json_report.render(report))
        rows = _rows(markdown.render(report))
        assert len(rows) == len(data["fmus"])
        for row, fmu in zip(rows, data["fmus"], strict=True):
            assert len(row) == columns
            new = new_counts(fmu)
            assert row[0].strip("`").replace("\\|", "|") == fmu["path"]
            assert row[1] == ("fail" if new["error"] else "pass")
            assert row[2:5] == [str(new["error"]), str(new["warning"]), str(new["info"])]
            if columns == 7:
                assert int(row[5]) == len(fmu["findings"]) - sum(new.values())
            assert (fmu["draft"] or "no manifest") in row[-1]


def test_findings_grouped_by_severity_with_code_name_and_location():
    text = markdown.render(sample_report(), SAMPLE_CATALOGUE)
    assert "- **DAE790** `binary-crashed`" in text  # not in the catalogue: no dead link
    broken = text.split("### `models/Broken.fmu`: fail", 1)[1].split("\n### ", 1)[0]
    assert broken.index("#### Errors (4)") < broken.index("#### Warnings (1)")
    assert "`enable-parameter-missing` (accepted by the baseline):" in broken
    assert "[DAE203](" in broken and "`enable-parameter-not-boolean`" in broken
    assert "`modelDescription.xml:12`" in broken
    assert "probes turned off (\\-\\-no\\-probes)" not in broken  # no over-escaping
    assert "probes turned off (--no-probes): `DAE701`" in broken
    clean = text.split("### `models/Clean.fmu`: pass", 1)[1]
    assert "No findings." in clean


def test_text_from_the_fmu_is_escaped():
    text = markdown.render(sample_report())
    line = next(line for line in text.splitlines() if "odd name" in line)
    assert "<d>" not in line and "&lt;d&gt;" in line
    assert "\\@octocat" in line and "\\#1" in line and "\\*x\\*" in line
    assert "\\[l\\](u)" in line and "a\\|b\\`c" in line
    assert "::error::injected" in line and "\r" not in line  # one line, whatever it held


def test_code_spans_hold_backticks_and_pipes():
    assert markdown.code("a`b") == "``a`b``"
    assert markdown.code("`x") == "`` `x ``"
    assert markdown.code("p|q", cell=True) == "`p\\|q`"
    report = Report("9.9.9", (FmuReport(path="odd|name`.fmu", draft=None, findings=()),))
    assert _rows(markdown.render(report))[0][0] == "``odd\\|name`.fmu``"


def test_stays_under_the_budget_and_says_what_was_left_out():
    base = sample_report().fmus[0].findings[1]
    findings = tuple(replace(base, subject=f"v{i}", message=f"{base.message} #{i}")
                     for i in range(400))
    report = Report("9.9.9", (FmuReport(path="m/Big.fmu", draft="alpha1", findings=findings),
                              FmuReport(path="m/Small.fmu", draft="alpha1", findings=())))
    text = markdown.render(report, budget=20_000)
    assert len(text.encode()) < 20_000 + 500
    shown = sum(1 for line in text.splitlines() if line.startswith("- **[DAE203]"))
    assert 0 < shown < 400
    assert f"**{400 - shown} findings left out**" in text
    assert "### `m/Small.fmu`: pass" in text  # every FMU keeps its heading
    assert len(_rows(text)) == 2


def test_verdict_and_totals():
    text = markdown.render(sample_report())
    assert ("4 FMUs checked: 2 passed, 2 failed; 5 errors, 1 warning, 1 info; "
            "1 more accepted by the baseline.") in text
    severities = [f.severity for f in sample_report().all_findings()]
    assert severities.count(Severity.ERROR) == 6  # one of them accepted by the baseline


def test_backtick_quotes_in_messages_become_code_spans():
    assert markdown.message("rename `<A>` to `<B|C>` now") == "rename `<A>` to `<B|C>` now"
    assert markdown.message("one ` tick <x>") == "one \\` tick &lt;x&gt;"
    assert markdown.message("a\n`b`\r\nc") == "a `b` c"


def test_text_escapes_html_entities_and_blank_quotes_stay_text():
    assert markdown.text("R&D <x>") == "R&amp;D &lt;x&gt;"
    assert markdown.message("a ` ` b") == "a \\` \\` b"


def test_the_budget_is_a_byte_limit_on_the_whole_summary():
    report = Report("9.9.9", (sample_report().fmus[0],))
    full = markdown.render(report, budget=10**9)
    footer = len("<sub>lsdae 9.9.9</sub>\n".encode())
    exact = len(full.encode()) - footer
    assert markdown.render(report, budget=exact) == full
    cut = markdown.render(report, budget=exact - 1)
    # one byte short: the FMU's block no longer fits whole; its findings are kept one by one
    assert "Skipped rules" in full and "Skipped rules" not in cut
