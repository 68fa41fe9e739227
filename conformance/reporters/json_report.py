"""The complete machine-readable report (schema version 1, documented in docs/json-report.md)."""
from __future__ import annotations

import json
import math
from typing import Any

from ..report.catalogue import Catalogue, default_catalogue
from ..model.drafts.names import DRAFT_LABELS
from ..report.findings import Finding, FmuReport, Report, Severity, thaw

SCHEMA_VERSION = 1


def plain(value: Any) -> Any:
    """Frozen evidence as strict JSON: dicts and lists, non-finite floats as strings."""
    return _finite(thaw(value))


def _finite(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value


def finding_dict(f: Finding, catalogue: Catalogue | None = None, *,
                 snippet: bool = False) -> dict[str, Any]:
    """One finding; ``snippet`` adds its source line (shard reports and the result cache, so
    that a report read back shows what the original showed)."""
    loc = f.location
    rule = (catalogue or default_catalogue()).get(f.code)
    out = {
        "code": f.code, "name": f.name, "severity": str(f.severity), "message": f.message,
        "file": loc.file, "line": loc.line, "column": loc.column, "path": loc.path,
        "subject": f.subject, "count": f.count, "evidence": plain(f.evidence),
        "fix": rule.fix_kind if rule is not None else None,
    }
    if f.part is not None:   # a sub-check whose basis differs from the rule's (its severity)
        out["part"] = f.part
    if snippet:
        out["snippet"] = loc.snippet
    return out


def fmu_dict(fmu: FmuReport, catalogue: Catalogue | None = None, *,
             snippets: bool = False) -> dict[str, Any]:
    return {
        "path": fmu.path,
        "draft": fmu.draft,
        "draft_label": DRAFT_LABELS.get(fmu.draft) if fmu.draft else None,
        "summary": {str(s): fmu.count(s) for s in (Severity.ERROR, Severity.WARNING,
                                                   Severity.INFO)},
        "info": plain(fmu.info),
        "findings": [finding_dict(f, catalogue, snippet=snippets) for f in fmu.findings],
        "rules_run": list(fmu.rules_run),
        "rules_skipped": [{"code": c, "reason": r} for c, r in fmu.rules_skipped],
        "rules_not_run": [{"code": c, "reason": r} for c, r in fmu.rules_not_run],
    }


def report_dict(report: Report, catalogue: Catalogue | None = None) -> dict[str, Any]:
    out = {
        "tool": "lsdae", "version": report.tool_version, "schema_version": SCHEMA_VERSION,
        "options": plain(report.options),
        "fmus": [fmu_dict(f, catalogue, snippets=bool(report.shard)) for f in report.fmus],
    }
    if report.interrupted:  # Ctrl-C: the FMUs above were checked, these were not
        out["interrupted"] = {"not_checked": list(report.not_checked)}
    if report.shard:  # lsdae check --shard: what lsdae merge needs (docs/json-report.md)
        out["shard"] = plain(report.shard)
    return out


def render(report: Report, catalogue: Catalogue | None = None, **_: Any) -> str:
    return json.dumps(report_dict(report, catalogue), indent=2, sort_keys=False, ensure_ascii=False) + "\n"
