"""``Instance.variable_dependencies`` on the Chain FMU, whose framework implements
fmi3GetNumberOfVariableDependencies / fmi3GetVariableDependencies from the model's pattern.

The runtime dependencies must be the manifest's in DAE mode, the modelDescription's in ODE mode
and the InitialUnknowns' before fmi3ExitInitializationMode (MS-13); the dense scenes declare no
pattern and refuse; the DEFECT_EXTRA_DEPENDENCY variant reports one dependency too many in DAE
mode only (its finding is tested in tests/probes/test_defects.py).
"""
from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Iterable, Iterator

import pytest
from lxml import etree

from conformance.model.manifest import MANIFEST, Manifest, read_manifest
from conformance.model.description import (MODEL_DESCRIPTION, ModelDescription, Unknown,
                                           read_model_description)
from conformance.probes.instruments.api import FmiError
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.instance import Dependency, Instance
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.runtime.modes import configure, start_instance
from tests.fixtures import build_scene, chain


class Opened:
    def __init__(self, fmu: Path, where: Path):
        with zipfile.ZipFile(fmu) as zf:
            zf.extractall(where)
        self.model: ModelDescription = read_model_description(
            etree.parse(str(where / MODEL_DESCRIPTION)))
        self.manifest: Manifest = read_manifest(etree.parse(str(where / MANIFEST)),
                                                draft="alpha1")
        self.library = Library(str(where), Layout.build(self.model, self.manifest),
                               CallRecord())

    def initialising(self, dae: bool) -> Instance:
        """A new instance in Initialization Mode (DAE mode switched on in Configuration Mode)."""
        inst = Instance(self.library, name=self.library.next_name("init"))
        if dae:
            configure(inst, True)
        inst.enter_initialization_mode(0.0)
        return inst


@pytest.fixture
def opened(tmp_path: Path) -> Iterator:
    handles: list[Opened] = []

    def open_fmu(fmu: Path) -> Opened:
        handles.append(Opened(fmu, tmp_path / str(len(handles))))
        return handles[-1]

    yield open_fmu
    for h in handles:
        h.library.free_all()


def _declared(unknowns: Iterable[Unknown]) -> dict[int, set[tuple[int, str]]]:
    out = {}
    for u in unknowns:
        assert u.vr is not None and u.dependencies is not None
        kinds = u.dependencies_kind or ("dependent",) * len(u.dependencies)
        out[u.vr] = set(zip(u.dependencies, kinds))
    return out


def _reported(inst: Instance, vrs: Iterable[int]) -> dict[int, set[tuple[int, str]]]:
    return {vr: {(d.vr, d.kind) for d in inst.variable_dependencies(vr)} for vr in vrs}


@pytest.mark.parametrize("n", [4, 40])
def test_dae_mode_reports_the_manifest_dependencies(opened, n):
    fmu = opened(chain.build_chain(n))
    declared = _declared(u for kind in ("Residual", "ContinuousStateDerivative", "Output")
                         for u in fmu.manifest.unknowns(kind))
    assert len(declared) == n + 2
    inst = start_instance(fmu.library, "dae")
    assert _reported(inst, declared) == declared
    (first,) = [d for d in inst.variable_dependencies(chain.vr_r(0)) if d.vr == chain.vr_w(0)]
    assert first == Dependency(chain.vr_w(0), "dependent", 0, 0)


@pytest.mark.parametrize("n", [4, 40])
def test_ode_mode_reports_the_model_description_dependencies(opened, n):
    fmu = opened(chain.build_chain(n))
    declared = _declared(u for kind in ("ContinuousStateDerivative", "Output")
                         for u in fmu.model.unknowns(kind))
    inst = start_instance(fmu.library, "ode")
    assert _reported(inst, declared) == declared
    # the algebraic variables are computed in ODE mode: through g = 0 they depend on x and u
    assert _reported(inst, [chain.vr_w(n // 2)]) == {chain.vr_w(n // 2): {(2, "dependent"),
                                                                          (4, "dependent")}}
    # the residuals are identically zero there, the knowns depend on nothing
    assert _reported(inst, [chain.vr_r(0), 2, 4, 0]) == {chain.vr_r(0): set(), 2: set(),
                                                         4: set(), 0: set()}


@pytest.mark.parametrize("dae", [True, False], ids=["dae", "ode"])
def test_initial_dependencies_before_initialisation_ends(opened, dae):
    fmu = opened(chain.build_chain(6))
    source = fmu.manifest.unknowns("InitialUnknown") if dae else fmu.model.unknowns(
        "InitialUnknown")
    declared = _declared(source)
    inst = fmu.initialising(dae)
    assert _reported(inst, declared) == declared
    if dae:  # after initialisation the runtime ones: w is a known, depends on nothing
        inst.exit_initialization_mode()
        assert _reported(inst, [chain.vr_w(0)]) == {chain.vr_w(0): set()}


def test_unknown_value_reference_is_refused(opened):
    inst = start_instance(opened(chain.build_chain()).library, "dae")
    with pytest.raises(FmiError) as caught:
        inst.variable_dependencies(999)
    assert caught.value.call == "fmi3GetNumberOfVariableDependencies"


def test_dense_scenes_offer_no_per_element_dependencies(opened):
    inst = start_instance(opened(build_scene("SimpleDAE")).library, "dae")
    with pytest.raises(FmiError):
        inst.variable_dependencies(9)


def test_extra_dependency_defect_differs_in_dae_mode_only(opened):
    fmu = opened(build_scene("Chain", defines=["DEFECT_EXTRA_DEPENDENCY"]))
    y = 5
    dae = start_instance(fmu.library, "dae")
    assert _reported(dae, [y]) == {y: {(chain.vr_w(3), "constant"), (2, "constant")}}
    ode = start_instance(fmu.library, "ode")
    assert _reported(ode, [y]) == _declared(u for u in fmu.model.unknowns("Output"))
