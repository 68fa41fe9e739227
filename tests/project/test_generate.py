"""Tests of the benchmark FMU generator: the archive, the FMI 3 XSD, and the DAE structure."""
from __future__ import annotations

import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import maximum_bipartite_matching

REPO_ROOT = Path(__file__).resolve().parents[2]
if str(REPO_ROOT) not in sys.path:  # plain `pytest` without pythonpath configured
    sys.path.insert(0, str(REPO_ROOT))

from bench.generate import MANIFEST_PATH, blocks_for, generate  # noqa: E402

LS_NS = "http://fmi-standard.org/fmi-ls-manifest"


def _fmi3_schema() -> etree.XMLSchema:
    import fmpy

    xsd = Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3ModelDescription.xsd"
    return etree.XMLSchema(file=str(xsd))


def _vrs(text: str | None) -> list[int]:
    return [int(t) for t in (text or "").split()]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return generate(200, tmp_path_factory.mktemp("gen") / "chain.fmu")


@pytest.fixture(scope="module")
def trees(fmu: Path) -> tuple[etree._Element, etree._Element]:
    with zipfile.ZipFile(fmu) as zf:
        return (etree.fromstring(zf.read("modelDescription.xml")),
                etree.fromstring(zf.read(MANIFEST_PATH)))


def test_archive_holds_both_files(fmu: Path) -> None:
    assert zipfile.is_zipfile(fmu)
    with zipfile.ZipFile(fmu) as zf:
        assert set(zf.namelist()) == {"modelDescription.xml", MANIFEST_PATH}
        assert zf.testzip() is None


def test_model_description_validates_against_fmi3_xsd(trees) -> None:
    md, _ = trees
    schema = _fmi3_schema()
    assert schema.validate(md), schema.error_log


def test_manifest_header(trees) -> None:
    _, man = trees
    assert man.tag == "fmiDAEManifest"  # no namespace
    assert man.get(f"{{{LS_NS}}}fmi-ls-name") == "org.fmi-standard.fmi-ls-dae"
    assert man.get(f"{{{LS_NS}}}fmi-ls-version") == "1.0.0-alpha.1"
    assert man.get(f"{{{LS_NS}}}fmi-ls-description") == "Layered standard for DAE support in FMI."
    assert [c.tag for c in man] == ["EnableDAEParameter", "AlgebraicVariables", "ModelStructure"]
    order = ["Output", "ContinuousStateDerivative", "ClockedState", "InitialUnknown",
             "EventIndicator", "Residual", "Invariant"]
    ranks = [order.index(c.tag) for c in man.find("ModelStructure")]
    assert ranks == sorted(ranks)


def test_variable_categories_and_counts(trees) -> None:
    md, man = trees
    m = blocks_for(200)
    variables = {int(v.get("valueReference")): v for v in md.find("ModelVariables")}
    assert abs(len(variables) - 200) <= 4

    enable = variables[int(man.find("EnableDAEParameter").get("valueReference"))]
    assert (enable.tag, enable.get("causality"), enable.get("variability"), enable.get("start")) \
        == ("Boolean", "structuralParameter", "fixed", "false")
    assert [v.get("causality") for v in variables.values()].count("independent") == 1

    states = [int(v.get("derivative")) for v in variables.values() if v.get("derivative")]
    algebraic = _vrs(" ".join(a.get("valueReference") for a in man.iter("AlgebraicVariable")))
    residuals = [int(r.get("valueReference")) for r in man.iter("Residual")]
    assert len(states) == len(set(states)) == m
    assert len(algebraic) == len(set(algebraic)) == m
    assert len(residuals) == len(set(residuals)) == m
    assert not (set(states) & set(algebraic) or set(states) & set(residuals)
                or set(algebraic) & set(residuals))
    for vr in states:
        v = variables[vr]
        assert (v.tag, v.get("causality"), v.get("variability"), v.get("initial")) \
            == ("Float64", "local", "continuous", "exact") and v.get("start") is not None
    for vr in algebraic:
        v = variables[vr]
        assert (v.tag, v.get("causality"), v.get("variability"), v.get("initial")) \
            == ("Float64", "local", "continuous", "approx") and v.get("start") is not None
    for vr in residuals:
        v = variables[vr]
        assert (v.tag, v.get("causality"), v.get("variability")) \
            == ("Float64", "local", "continuous")
        assert v.get("start") is None and v.get("initial") is None
    assert len(md.findall("ModelStructure/ContinuousStateDerivative")) == m
    assert len(man.findall("ModelStructure/ContinuousStateDerivative")) == m


def test_value_references_unique_and_resolved(trees) -> None:
    md, man = trees
    all_vrs = [int(v.get("valueReference")) for v in md.find("ModelVariables")]
    assert len(all_vrs) == len(set(all_vrs))
    known = set(all_vrs)
    names = [v.get("name") for v in md.find("ModelVariables")]
    assert len(names) == len(set(names))

    referenced = [int(v.get("derivative")) for v in md.iter() if v.get("derivative")]
    for root in (md, man):
        for el in root.iter():
            if el.tag in {"Output", "ContinuousStateDerivative", "InitialUnknown", "Residual",
                          "EventIndicator", "ClockedState"}:
                referenced.append(int(el.get("valueReference")))
                deps = _vrs(el.get("dependencies"))
                referenced.extend(deps)
                if el.get("dependenciesKind") is not None:
                    assert len(el.get("dependenciesKind").split()) == len(deps)
            elif el.tag in {"EnableDAEParameter", "AlgebraicVariable"}:
                referenced.append(int(el.get("valueReference")))
    assert set(referenced) <= known


def test_initial_unknowns_follow_ms05(trees) -> None:
    md, _ = trees
    variables = list(md.find("ModelVariables"))
    expected = {int(v.get("valueReference")) for v in variables
                if v.get("causality") == "output"
                and v.get("initial") in (None, "approx", "calculated")}
    expected |= {int(v.get("valueReference")) for v in variables if v.get("derivative")}
    listed = [int(u.get("valueReference")) for u in md.iterfind("ModelStructure/InitialUnknown")]
    assert len(listed) == len(set(listed))
    assert set(listed) == expected


def test_residual_incidence_is_lower_bidiagonal_with_perfect_matching(trees) -> None:
    _, man = trees
    algebraic = [int(a.get("valueReference")) for a in man.iter("AlgebraicVariable")]
    column = {vr: j for j, vr in enumerate(algebraic)}
    rows, cols = [], []
    for i, res in enumerate(man.iter("Residual")):
        js = sorted(column[vr] for vr in _vrs(res.get("dependencies")) if vr in column)
        assert js == ([i] if i == 0 else [i - 1, i])
        rows += [i] * len(js)
        cols += js
    n = len(algebraic)
    incidence = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    matching = maximum_bipartite_matching(incidence, perm_type="column")
    assert (matching >= 0).all()


def test_generation_is_deterministic(tmp_path: Path) -> None:
    a = generate(60, tmp_path / "a.fmu")
    b = generate(60, tmp_path / "b.fmu")
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("naming", ["structured", "flat"])
def test_fmpy_validate_reports_no_problems(tmp_path: Path, naming: str) -> None:
    from fmpy.validation import validate_fmu

    path = generate(300, tmp_path / f"chain-{naming}.fmu", naming=naming)
    assert validate_fmu(str(path)) == []
