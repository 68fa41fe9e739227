"""The recorded verdicts on survivors (``verdicts.toml``), and how a survivor is explained.

A survivor (built, not equivalent, no new error or warning) is one of:

- ``consistent-model-change``: the FMU still keeps every promise (declared dependencies and
  kinds, derivatives that agree with finite differences, ODE and DAE mode that agree, start
  values, reset, independent instances); it computes a different model, which no checker can
  tell from the intended one.
- ``missed-defect``: a promise is broken and lsdae did not say so; the reason names the promise
  and the evidence.
- ``undetectable``: broken only in a way no outside observer can see (the reason says why).

The file is keyed by mutant id::

    [verdict."SimpleDAE/model.c:71:0123456789"]
    class = "missed-defect"
    promise = "MV-23 start values"          # missed-defect only: the promise broken
    reason = "x_start of x1 is 0.6 in the binary, 0.5 in the XML; no rule reads it"
    evidence = "promises: MV-23 start value in Instantiated (ode) x1"
    line = ".x_start = {0.6, 0.5}, ..."     # the mutated line, for the reader
    closed_by = "start-value-not-applied (DAE713) ..."   # optional, for the reader: what kills
                                            # the mutant since (checked by hand; the next
                                            # campaign confirms it and the entry goes unused)

A survivor without an entry is UNEXPLAINED; one recorded as a consistent model change while
the promise checks find a promise it newly breaks is CONTRADICTED. Both make the campaign exit
non-zero. :func:`stub` writes an entry from the evidence for a human to review; its reason
starts with REVIEW, which :func:`load` refuses, so a stub never passes for a verdict.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

CLASSES = ("consistent-model-change", "missed-defect", "undetectable")
DEFAULT_FILE = Path(__file__).resolve().parent / "verdicts.toml"


class VerdictError(ValueError):
    """verdicts.toml is malformed."""


@dataclass(frozen=True)
class Verdict:
    cls: str
    reason: str
    promise: str = ""
    evidence: str = ""

    def to_json(self) -> dict[str, str]:
        return {"class": self.cls, "reason": self.reason, "promise": self.promise,
                "evidence": self.evidence}


def load(path: Path = DEFAULT_FILE) -> dict[str, Verdict]:
    if not path.is_file():
        return {}
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8")).get("verdict", {})
    except tomllib.TOMLDecodeError as exc:
        raise VerdictError(f"{path}: {exc}") from None
    out: dict[str, Verdict] = {}
    for key, entry in table.items():
        cls = entry.get("class")
        if cls not in CLASSES or not entry.get("reason"):
            raise VerdictError(f"{path}: verdict {key!r} needs class (one of "
                               f"{', '.join(CLASSES)}) and reason")
        if entry["reason"].startswith("REVIEW"):
            raise VerdictError(f"{path}: verdict {key!r} is a stub nobody reviewed (its reason "
                               "starts with REVIEW)")
        if cls == "missed-defect" and not entry.get("promise"):
            raise VerdictError(f"{path}: missed-defect {key!r} needs the promise it breaks")
        out[key] = Verdict(cls, entry["reason"], entry.get("promise", ""),
                           entry.get("evidence", ""))
    return out


def explain(record: dict[str, Any], verdicts: dict[str, Verdict]) -> str:
    """``explained``, ``UNEXPLAINED`` or ``CONTRADICTED`` for a survivor's record."""
    verdict = verdicts.get(record["id"])
    if verdict is None:
        return "UNEXPLAINED"
    if verdict.cls == "consistent-model-change" and record.get("promises"):
        return "CONTRADICTED"
    return "explained"


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def stub(record: dict[str, Any]) -> str:
    """A verdicts.toml entry suggested by the evidence, to be reviewed before it is kept."""
    broken = sorted(record.get("promises") or {})
    if broken:
        cls = "missed-defect"
        reason = "REVIEW: breaks " + "; ".join(broken[:3])
        lines = [f"promise = {_quote(broken[0])}"]
    else:
        cls, reason, lines = "consistent-model-change", "REVIEW: no promise broken", []
    evidence = "promises: " + ("; ".join(f"{k}: {record['promises'][k]}" for k in broken[:3])
                               if broken else "none newly broken") + \
        "; oracle: " + "; ".join(record.get("oracle_detail", [])[:2])
    return "\n".join([f"[verdict.{_quote(record['id'])}]", f"class = {_quote(cls)}", *lines,
                      f"reason = {_quote(reason)}", f"evidence = {_quote(evidence)}",
                      f"line = {_quote(record['mutated'].strip())}", ""])
