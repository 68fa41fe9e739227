"""Check the same mutated FMUs with this tree and with another revision, and compare the verdicts.

A change meant to leave every finding as it was (a speed-up, a restructuring) is checked on the
report snapshot (:mod:`scripts.report_snapshot`), which covers our scenes and fixtures. This
covers what they do not: thousands of small FMUs from the benchmark's generator, each with a few
random faults (a causality, a variability, a start, a valueReference, a type, a dependency list,
an element removed or repeated, in the model or the manifest), checked statically by both trees
(the other from a temporary git worktree)::

    python -m scripts.differential --rev f640291 --count 3000

It prints how many FMUs and rules fired, and every FMU whose findings or rule lists differ; the
exit status is 1 when any does. The FMUs depend only on ``--seed`` and ``--count``.
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import random
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from bench.generate import MANIFEST_PATH, manifest_xml, model_description_xml

REPO_ROOT = Path(__file__).resolve().parents[1]

CAUSALITIES = ["local", "output", "input", "parameter", "calculatedParameter", "independent",
               "structuralParameter", "bogus"]
VARIABILITIES = ["continuous", "discrete", "fixed", "tunable", "constant"]
INITIALS = ["exact", "approx", "calculated"]
TYPES = ["Float64", "Float32", "Int32", "Boolean", "String", "UInt8"]
TOKENS = ["0", "1", "2", "5", "6", "7", "8", "9", "12", "13", "999", "x", "-1", "4294967296"]
KINDS = ["dependent", "constant", "fixed", "tunable", "discrete", "bogus"]


def _tokens(rng: random.Random, pool: list[str]) -> str:
    return " ".join(rng.choice(pool) for _ in range(rng.randint(0, 3)))


def _fault_in_structure(rng: random.Random, ms: etree._Element) -> None:
    element = rng.choice(list(ms))
    pick = rng.random()
    if pick < 0.3:
        element.set("dependencies", _tokens(rng, TOKENS))
    elif pick < 0.5:
        element.set("valueReference", rng.choice(TOKENS))
    elif pick < 0.7:
        ms.remove(element)
    elif pick < 0.85:
        element.set("dependenciesKind", _tokens(rng, KINDS))
    else:
        ms.append(copy.deepcopy(element))


def _fault_in_variable(rng: random.Random, mv: etree._Element, var: etree._Element) -> None:
    pick = rng.random()
    if pick < 0.14:
        var.set("causality", rng.choice(CAUSALITIES))
    elif pick < 0.28:
        var.set("variability", rng.choice(VARIABILITIES))
    elif pick < 0.38:
        var.set("initial", rng.choice(INITIALS))
    elif pick < 0.46:
        if var.get("start") is not None:
            del var.attrib["start"]
        else:
            var.set("start", rng.choice(["0", "1", "inf", "nan", "x"]))
    elif pick < 0.54:
        var.set("valueReference", rng.choice(TOKENS))
    elif pick < 0.60:
        var.set("derivative", rng.choice(TOKENS))
    elif pick < 0.66:
        var.tag = rng.choice(TYPES)
    elif pick < 0.72:
        var.set(rng.choice(["nominal", "min", "max"]), rng.choice(["-1", "0", "1", "inf", "x"]))
    elif pick < 0.77:
        var.set("name", rng.choice(["a", "x[1]", "1bad", "der(x)", var.get("name") or "v"]))
    elif pick < 0.82:
        mv.remove(var)
    elif pick < 0.87:
        mv.append(copy.deepcopy(var))
    elif pick < 0.90:
        var.set(rng.choice(["declaredType", "unit"]), "T")
    else:
        etree.SubElement(var, "Dimension", start="2")


def mutated_documents(rng: random.Random) -> tuple[bytes, bytes]:
    """A small generated chain (1-3 blocks) with a few random faults: its modelDescription.xml
    and manifest."""
    m = rng.choice([1, 2, 3])
    model = etree.fromstring(model_description_xml(m).encode())
    manifest = etree.fromstring(manifest_xml(m).encode())
    if rng.random() < 0.85:
        mv, ms = model.find("ModelVariables"), model.find("ModelStructure")
        for _ in range(rng.randint(1, 3)):
            if rng.random() < 0.1 and ms is not None and len(ms):
                _fault_in_structure(rng, ms)
            elif len(mv):
                _fault_in_variable(rng, mv, rng.choice(list(mv)))
    if rng.random() < 0.6:
        for _ in range(rng.randint(1, 2)):
            parents = [e for e in manifest.iter() if len(e) and e is not manifest]
            if parents:
                _fault_in_structure(rng, rng.choice(parents))
    return (etree.tostring(model, xml_declaration=True, encoding="UTF-8"),
            etree.tostring(manifest, xml_declaration=True, encoding="UTF-8"))


def write_fmus(folder: Path, count: int, seed: int) -> list[Path]:
    rng = random.Random(seed)
    paths = []
    for i in range(count):
        model, manifest = mutated_documents(rng)
        path = folder / f"mutant-{i:05d}.fmu"
        with zipfile.ZipFile(path, "w") as zf:
            zf.writestr("modelDescription.xml", model)
            zf.writestr(MANIFEST_PATH, manifest)
        paths.append(path)
    return paths


def verdicts(report: dict) -> dict[str, tuple]:
    """Per FMU (by file name): its findings and the rules run, skipped and not run."""
    return {Path(fmu["path"]).name: (fmu["findings"], fmu["rules_run"], fmu["rules_skipped"],
                                     fmu["rules_not_run"]) for fmu in report["fmus"]}


def _check(tree: Path, fmus: list[Path], out: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    proc = subprocess.run([sys.executable, "-m", "conformance", "check", "--no-probes",
                           "--format", "json", "-o", str(out), *map(str, fmus)],
                          cwd=tree, env=env, capture_output=True, text=True)
    if proc.returncode not in (0, 1) or not out.is_file():
        raise SystemExit(f"differential: the check in {tree} exited {proc.returncode}: "
                         f"{proc.stderr[-500:]}")
    return json.loads(out.read_text(encoding="utf-8"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", required=True, help="the revision to compare with")
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "fmus").mkdir()
        fmus = write_fmus(folder / "fmus", args.count, args.seed)
        other = folder / "other"
        subprocess.run(["git", "-C", str(REPO_ROOT), "worktree", "add", "--detach", "-q",
                        str(other), args.rev], check=True)
        try:
            mine = verdicts(_check(REPO_ROOT, fmus, folder / "this.json"))
            theirs = verdicts(_check(other, fmus, folder / "other.json"))
        finally:
            subprocess.run(["git", "-C", str(REPO_ROOT), "worktree", "remove", "--force",
                            str(other)], check=False)
    fired = {f["code"] for findings, *_ in mine.values() for f in findings}
    differing = sorted(name for name in mine if mine[name] != theirs.get(name))
    print(f"{len(mine)} mutated FMUs, {len(fired)} rules fired; {len(differing)} differ "
          f"from {args.rev}")
    for name in differing[:20]:
        print(f"  {name}")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
