"""The Chain FMU at large N: the framework's sparse interface (heap work arrays sized from the
model, O(nnz) derivatives, band LU of dg/dw) against finite differences and transposes.

The benchmark (bench/probe_bench.py) times it; these tests check the numbers.
"""
from __future__ import annotations

import tempfile
import zipfile
from typing import Iterator

import numpy as np
import pytest
from lxml import etree

from conformance.model.manifest import MANIFEST, read_manifest
from conformance.model.description import MODEL_DESCRIPTION, read_model_description
from conformance.probes.instruments.api import Point
from conformance.runtime.callrecord import CallRecord
from conformance.runtime.instance import Instance
from conformance.runtime.layout import Layout
from conformance.runtime.library import Library
from conformance.runtime.modes import configure, start_instance
from tests.fixtures import chain

N = 2000
X, DER, U, Y = 2, 3, 4, 5


@pytest.fixture(scope="module")
def library() -> Iterator[Library]:
    with tempfile.TemporaryDirectory() as where:
        with zipfile.ZipFile(chain.build_chain(N)) as zf:
            zf.extractall(where)
        model = read_model_description(etree.parse(f"{where}/{MODEL_DESCRIPTION}"))
        manifest = read_manifest(etree.parse(f"{where}/{MANIFEST}"), draft="alpha1")
        lib = Library(where, Layout.build(model, manifest), CallRecord())
        yield lib
        lib.free_all()


def _ode_outputs(inst: Instance, x: float, u: float) -> np.ndarray:
    return inst.evaluate(Point(0.0, {X: x, U: u}), [DER, Y])


def test_ode_mode_total_derivatives_match_finite_differences(library):
    inst = start_instance(library, "ode")
    x, u, h = 0.7, 0.3, 1e-6
    inst.evaluate(Point(0.0, {X: x, U: u}), [DER, Y])
    jac = np.column_stack([inst.directional(Point(0.0, {X: x, U: u}), [DER, Y], [X, U], e)
                           for e in np.eye(2)])
    fd = np.column_stack([
        (_ode_outputs(inst, x + h, u) - _ode_outputs(inst, x - h, u)) / (2 * h),
        (_ode_outputs(inst, x, u + h) - _ode_outputs(inst, x, u - h)) / (2 * h)])
    np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-9)
    # y = w[N-1] hardly feels x at the far end of the chain, der(x) = w[0] - x does
    assert abs(jac[0, 0] + 1) < 0.5 and abs(jac[1, 0]) < 1e-12 < abs(jac[1, 1])
    adj = np.vstack([inst.adjoint(Point(0.0, {X: x, U: u}), [DER, Y], [X, U], e)
                     for e in np.eye(2)])
    np.testing.assert_allclose(adj, jac, rtol=1e-12, atol=1e-15)


def test_dae_mode_adjoint_is_the_transpose_of_the_directional_derivative(library):
    inst = start_instance(library, "dae")
    rng = np.random.default_rng(3)
    unknowns = [chain.vr_r(i) for i in range(N)] + [DER, Y]
    knowns = [X, *(chain.vr_w(i) for i in range(N)), U]
    values = {X: 0.5, U: -0.2, **{chain.vr_w(i): float(w) for i, w in
                                  enumerate(rng.uniform(-1, 1, N))}}
    point = Point(0.0, values)
    s, v = rng.normal(size=len(knowns)), rng.normal(size=len(unknowns))
    js = inst.directional(point, unknowns, knowns, s)
    vj = inst.adjoint(point, unknowns, knowns, v)
    assert v @ js == pytest.approx(vj @ s, rel=1e-12)
    # the residual rows are the tridiagonal chain: check one interior row exactly
    i, w = N // 2, np.array([values[chain.vr_w(k)] for k in range(N)])
    expected = (4 + np.cos(w[i])) * s[1 + i] - s[i] - s[2 + i]
    assert js[i] == pytest.approx(expected, rel=1e-13)


def test_initial_unknowns_are_total_derivatives_at_large_n(library):
    inst = Instance(library, name="init")
    configure(inst, True)   # DAE mode: the algebraic variables are initial unknowns
    inst.enter_initialization_mode(0.0)
    w_mid = chain.vr_w(N // 2)
    total = inst._derivative("fmi3GetDirectionalDerivative", [DER, w_mid], [X, U],
                             np.array([1.0, 0.0]), 2)
    inst.exit_initialization_mode()
    assert np.all(np.isfinite(total)) and total[0] != 0.0
    inst.free()
