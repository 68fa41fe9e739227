"""Write the JSON report of every scene, corpus model, defect variant and rule fixture.

A restructuring that must not change behaviour is checked by running this before and after
and comparing the two folders::

    python -m scripts.report_snapshot --out build/snapshot-before
    ... change the code ...
    python -m scripts.report_snapshot --out build/snapshot-after
    diff -r build/snapshot-before build/snapshot-after

Scenes, corpus models and defect variants are checked with probes (seed 0), fixtures with the
static stage only, exactly as their tests do. Paths are replaced by the case name so that two
runs in different temporary folders compare equal.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from conformance.run.engine import EngineOptions, check_paths
from conformance.reporters import json_report


def _write(out: Path, name: str, path: Path, options: EngineOptions) -> None:
    report = check_paths([path], options=options)
    data = json_report.report_dict(report)
    for fmu in data["fmus"]:
        fmu["path"] = name
    text = json.dumps(data, indent=1, ensure_ascii=False).replace(str(path), name)
    (out / f"{name.replace('/', '__')}.json").write_text(text + "\n", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--only", choices=("scenes", "corpus", "defects", "fixtures"),
                        action="append")
    args = parser.parse_args(argv)
    kinds = set(args.only or ("scenes", "corpus", "defects", "fixtures"))
    args.out.mkdir(parents=True, exist_ok=True)
    from scenes.build import build_scene, corpus_names, scene_names
    from tests.fixturekit import all_cases, materialise
    from tests.fixtures.defects import DEFECTS
    from tests.fixtures.defects.variants import build as build_variant

    if "scenes" in kinds:
        for scene in scene_names():
            _write(args.out, f"scene-{scene}", build_scene(scene), EngineOptions(probes=True))
    if "corpus" in kinds:
        for name in corpus_names():
            _write(args.out, f"corpus-{name}", build_scene(name), EngineOptions(probes=True))
    if "defects" in kinds:
        for defect in DEFECTS:
            _write(args.out, f"defect-{defect.id}", build_variant(defect),
                   EngineOptions(probes=True))
    if "fixtures" in kinds:
        for case in all_cases():
            with tempfile.TemporaryDirectory() as tmp:
                path = materialise(case, Path(tmp))
                _write(args.out, f"fixture-{case.id}", path,
                       EngineOptions(probes=False, draft=case.spec.get("draft", "auto")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
