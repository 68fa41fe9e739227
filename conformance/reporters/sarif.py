"""SARIF 2.1.0 for GitHub code scanning (and any other SARIF viewer).

One run for the whole report. ``tool.driver.rules`` is the catalogue (never the first finding
seen), so a rule's text is the same in every upload; each result names its rule by ``ruleId`` and
``ruleIndex``. A result points at the FMU as the repository holds it: the ``.fmu`` file, or, when
the FMU is an unpacked folder, the XML file inside it with the line. The output depends only on
the report, the catalogue and the paths given: no timestamps, no absolute paths unless the FMU
lies outside the repository.

What GitHub requires and uses is documented on its page "SARIF support for code scanning";
``tests/reporters/test_sarif.py`` checks every field that page marks as required.
"""
from __future__ import annotations

import hashlib
import json
import os
import posixpath
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import quote

from ..report.catalogue import Catalogue
from ..report.findings import Finding, FmuReport, Report, Severity
from .json_report import plain
from .sarif_rules import LEVEL, PROJECT_URL, RULES_DOC_URL, descriptors, rule_url

__all__ = ["RULES_DOC_URL", "annotated_file", "inner_location", "is_baselined", "render",
           "rule_url", "sarif_log"]

SCHEMA_URI = "https://json.schemastore.org/sarif-2.1.0.json"
SARIF_VERSION = "2.1.0"
_SRCROOT = "%SRCROOT%"
#: The evidence key a baseline sets on the findings it accepts (conformance/report/baseline.py).
BASELINED = "baselined"
_FINGERPRINT = "lsdae/v1"


# -- paths shared with the github reporter ---------------------------------------------------

def is_folder(path: str) -> bool:
    """Whether an FMU path names an unpacked folder: asked of the file system when it exists,
    otherwise read from the name (a ``.fmu`` suffix is an archive)."""
    if os.path.isdir(path):
        return True
    if os.path.exists(path):
        return False
    return not path.lower().endswith(".fmu")


def repo_path(path: str, *, root: str | None = None) -> tuple[str, bool]:
    """The FMU path relative to the repository root, POSIX-style, and whether it is inside.

    A relative path is taken as relative to the root (the CLI runs there in CI). ``root``
    defaults to ``$GITHUB_WORKSPACE`` or the working directory and is only consulted for an
    absolute path or one that climbs with ``..``; outside the root the absolute path is returned.
    """
    posix = path.replace("\\", "/") if os.sep == "\\" else path
    pure = PurePosixPath(posix)
    if not pure.is_absolute() and ".." not in pure.parts:
        return posixpath.normpath(posix), True
    base = Path(root or os.environ.get("GITHUB_WORKSPACE") or os.getcwd())
    absolute = Path(os.path.normpath(base / path))
    try:
        return absolute.relative_to(os.path.normpath(base)).as_posix(), True
    except ValueError:
        return absolute.as_posix(), False


def annotated_file(fmu: FmuReport, finding: Finding, *, root: str | None = None
                   ) -> tuple[str, bool, bool]:
    """The file to annotate for a finding: (path, inside the repository, lines refer to it).

    Lines are only meaningful when the FMU is a folder, so that the finding's XML file is itself
    a file of the repository; for a ``.fmu`` archive (or a file the folder lacks) the
    annotation goes on the archive (or the folder).
    """
    path, inside = repo_path(fmu.path, root=root)
    inner = finding.location.file
    if inner and is_folder(fmu.path):
        # A file the finding says is missing cannot be annotated: the folder is, instead.
        if os.path.isdir(fmu.path):
            present = os.path.isfile(os.path.join(fmu.path, inner))
        else:  # a report read back or built in a test: a line means the file was read
            present = finding.location.line is not None
        if present:
            return posixpath.normpath(posixpath.join(path, inner)), inside, True
    return path, inside, False


def is_baselined(finding: Finding) -> bool:
    """Accepted by a baseline: still reported, but it fails nothing."""
    return bool(finding.evidence_dict().get(BASELINED))


def inner_location(finding: Finding) -> str:
    """``file:line`` inside the FMU, or '' when the finding has no file."""
    loc = finding.location
    if not loc.file:
        return ""
    return loc.file + (f":{loc.line}" if loc.line else "")


def _utf16_len(text: str) -> int:
    return len(text.encode("utf-16-le")) // 2


def _region(finding: Finding, lines_apply: bool) -> dict[str, int]:
    """Every region field GitHub marks as required; the whole source line when it is known."""
    loc = finding.location
    if not lines_apply or not loc.line:
        return {"startLine": 1, "startColumn": 1, "endLine": 1, "endColumn": 2}
    if loc.column:
        start = loc.column
    elif loc.snippet:
        start = _utf16_len(loc.snippet) - _utf16_len(loc.snippet.lstrip()) + 1
    else:
        start = 1
    end = _utf16_len(loc.snippet) + 1 if loc.snippet else start + 1
    return {"startLine": loc.line, "startColumn": start, "endLine": loc.line,
            "endColumn": max(end, start + 1)}


def _uri(path: str, inside: bool) -> str:
    if inside:
        return quote(path, safe="/")
    return Path(path).as_uri()


def fingerprint(fmu: FmuReport, finding: Finding, *, root: str | None = None) -> str:
    """A hash that names the fault, not where it sits: rule, FMU, file inside it, and subject
    (or element path); never the line, so an unrelated edit above keeps the alert."""
    loc = finding.location
    what = finding.subject or loc.path or finding.message
    key = "\0".join([finding.code, repo_path(fmu.path, root=root)[0], loc.file or "", what])
    return hashlib.sha256(key.encode("utf-8")).hexdigest()


def _result(fmu: FmuReport, finding: Finding, rule_index: int, seen: dict[str, int],
            root: str | None) -> dict[str, Any]:
    path, inside, lines_apply = annotated_file(fmu, finding, root=root)
    artifact: dict[str, Any] = {"uri": _uri(path, inside)}
    if inside:
        artifact["uriBaseId"] = _SRCROOT
    message = finding.message.strip() or f"{finding.code} {finding.name}"  # never empty
    where = inner_location(finding)
    if where and not lines_apply:  # the alert sits on the archive: say where inside it
        message = f"{message} (in {where})"
    # SARIF reads [text](target) in a message as a link: literal brackets are escaped (3.11.6).
    message = message.replace("[", "\\[").replace("]", "\\]")
    location: dict[str, Any] = {
        "physicalLocation": {"artifactLocation": artifact,
                             "region": _region(finding, lines_apply)},
    }
    if finding.location.path:
        location["logicalLocations"] = [{"fullyQualifiedName": finding.location.path,
                                         "kind": "element"}]
    digest = fingerprint(fmu, finding, root=root)
    seen[digest] = seen.get(digest, 0) + 1
    # GitHub only reads primaryLocationLineHash ("<hash>:<occurrence>") and would compute it
    # from the text at the line when absent; ours is keyed on the subject so it survives edits.
    fingerprints = {"primaryLocationLineHash": f"{digest[:16]}:{seen[digest]}",
                    _FINGERPRINT: digest}
    properties: dict[str, Any] = {"fmu": fmu.path, "count": finding.count}
    for key, value in (("file", finding.location.file), ("line", finding.location.line),
                       ("path", finding.location.path), ("subject", finding.subject)):
        if value is not None:
            properties[key] = value
    if finding.evidence:
        properties["evidence"] = plain(finding.evidence)
    result: dict[str, Any] = {
        "ruleId": finding.code,
        "ruleIndex": rule_index,
        "level": LEVEL[finding.severity],
        "message": {"text": message},
        "locations": [location],
        "partialFingerprints": fingerprints,
        "properties": properties,
    }
    if is_baselined(finding):
        result["baselineState"] = "unchanged"
        result["suppressions"] = [{"kind": "external", "status": "accepted",
                                   "justification": "accepted by the lsdae baseline"}]
    return result


def _invocation(report: Report) -> dict[str, Any]:
    failures = [(fmu, f) for fmu in report.fmus for f in fmu.findings
                if f.name == "internal-error"]
    invocation: dict[str, Any] = {"executionSuccessful": not failures
                                  and not report.interrupted}
    notifications = [
        {"level": "error", "message": {"text": f"{fmu.path}: {f.message}"},
         "descriptor": {"id": f.code}} for fmu, f in failures]
    # A clean result without probes is not a verified binary: say so where SARIF viewers look.
    notifications += [
        {"level": "note", "message": {"text": f"{fmu.path}: binary not checked: "
                                              f"{fmu.binary_not_checked}"}}
        for fmu in report.fmus if fmu.binary_not_checked]
    notifications += [
        {"level": "warning", "message": {"text": f"{fmu.path}: {code} not run: {reason}"},
         "descriptor": {"id": code}}
        for fmu in report.fmus for code, reason in fmu.rules_not_run]
    notifications += [
        {"level": "error", "message": {"text": f"{path}: not checked, the run was interrupted"}}
        for path in report.not_checked]
    if notifications:
        invocation["toolExecutionNotifications"] = notifications
    invocation["properties"] = {"options": plain(report.options)}
    return invocation


def _fmu_summary(fmu: FmuReport) -> dict[str, Any]:
    return {"path": fmu.path, "draft": fmu.draft,
            "errors": fmu.count(Severity.ERROR), "warnings": fmu.count(Severity.WARNING),
            "info": fmu.count(Severity.INFO)}


def sarif_log(report: Report, catalogue: Catalogue | None = None, *, root: str | None = None,
              category: str | None = None, docs_url: str = RULES_DOC_URL) -> dict[str, Any]:
    """The SARIF log as a dict. ``category`` sets ``automationDetails.id`` (left out by default
    so that upload-sarif's own ``category`` input applies)."""
    rules, index = descriptors(report, catalogue, docs_url)
    seen: dict[str, int] = {}
    results = [_result(fmu, f, index[f.code], seen, root)
               for fmu in report.fmus for f in fmu.findings]
    run: dict[str, Any] = {
        "tool": {"driver": {
            "name": "lsdae",
            "version": report.tool_version,
            "semanticVersion": report.tool_version,
            "informationUri": PROJECT_URL,
            "rules": rules,
        }},
        "invocations": [_invocation(report)],
        "columnKind": "utf16CodeUnits",
        "results": results,
        "properties": {"fmus": [_fmu_summary(f) for f in report.fmus]},
    }
    if category:
        run["automationDetails"] = {"id": category if category.endswith("/") else category + "/"}
    return {"$schema": SCHEMA_URI, "version": SARIF_VERSION, "runs": [run]}


def render(report: Report, catalogue: Catalogue | None = None, *, root: str | None = None,
           category: str | None = None, **_: Any) -> str:
    log = sarif_log(report, catalogue, root=root, category=category)
    return json.dumps(log, indent=2, ensure_ascii=False) + "\n"
