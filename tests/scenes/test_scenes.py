"""Behaviour of the test-scene FMUs, checked against independent Python models.

Each scene is built with scenes.build, extracted and driven through fmpy.
The reference equations below are written out again in numpy, so a wrong C
model, a wrong Jacobian or a wrong ModelStructure shows up here first.
"""

from __future__ import annotations

import ctypes
import os
import re
import subprocess
import sys
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import fmpy
import numpy as np
import pytest
from fmpy.fmi3 import FMU3Model
from lxml import etree
from scipy.optimize import fsolve

from scenes.build import (MANIFEST_ENTRY, REPO_ROOT, SceneBuildError, build_scene, platform_tuple,
                          scene_names, scene_xml_dir, shared_library_extension)

FMPY_DIR = Path(fmpy.__file__).resolve().parent
FMI_ERROR = 3


# ------------------------------------------------------------- reference models

@dataclass(frozen=True)
class Scene:
    name: str
    vr_x: list[int]
    vr_der: list[int]
    vr_w: list[int]
    vr_res: list[int]
    vr_u: list[int]
    vr_y: list[int]
    vr_enable: int
    tunable: bool
    x0: list[float]
    w0: list[float]
    x_nominal: list[float]
    f: Callable  # der = f(x, w, u)
    g: Callable  # res = g(x, w, u)
    h: Callable  # y = h(x, w, u)
    x_test: list[float] = field(default_factory=list)   # a point away from the start
    u_test: list[float] = field(default_factory=list)
    x_alt: list[float] = field(default_factory=list)    # a second point (linearity checks)
    u_alt: list[float] = field(default_factory=list)
    vr_z: list[int] = field(default_factory=list)       # event indicators
    vr_d: list[int] = field(default_factory=list)       # discrete variables (f, g, h: at start)

    def solve_w(self, x, u, guess=None):
        guess = np.array(self.w0 if guess is None else guess, dtype=float)
        w, info, ier, msg = fsolve(lambda w: self.g(x, w, u), guess, full_output=True, xtol=1e-14)
        assert ier == 1 or np.max(np.abs(self.g(x, w, u))) < 1e-12, msg
        return w


def _simple_f(x, w, u):
    (x1, x2), (z1, z2), (u1, u2) = x, w, u
    return np.array([np.sin(x1) + np.sin(z1 * z2 * u1),
                     np.sin(x1 * x2) + np.sin(z1 * z2 * u2) + u1 ** 2])


def _simple_g(x, w, u):
    (x1, x2), (z1, z2), (u1, u2) = x, w, u
    return np.array([z1 * u1 ** 2 + np.tanh(3 * z1) + u2 * x1 ** 3,
                     np.exp(z1 * z2 * u1) / 3 - np.sin(z2 * x2)])


def _simple_h(x, w, u):
    (x1, x2), (z1, z2), (u1, u2) = x, w, u
    return np.array([u1 * x1 * z1 + np.sin(u2), u2 * x2 * z2 + np.sin(u1 * u2)])


SCENES = {
    "SimpleDAE": Scene(
        "SimpleDAE", vr_x=[1, 3], vr_der=[2, 4], vr_w=[5, 6], vr_res=[11, 12], vr_u=[7, 8],
        vr_y=[9, 10], vr_enable=13, tunable=True, x0=[0.5, 0.5], w0=[0.0, 0.0],
        x_nominal=[1.0, 1.0], f=_simple_f, g=_simple_g, h=_simple_h,
        x_test=[0.6, 0.8], u_test=[0.3, -0.2], x_alt=[0.7, 0.9], u_alt=[0.25, -0.3]),
    "Robertson": Scene(
        "Robertson", vr_x=[2, 4], vr_der=[3, 5], vr_w=[6], vr_res=[7], vr_u=[], vr_y=[],
        vr_enable=1, tunable=False, x0=[1.0, 0.0], w0=[0.0], x_nominal=[1.0, 1e-5],
        f=lambda x, w, u: np.array([-0.04 * x[0] + 1e4 * x[1] * w[0],
                                    0.04 * x[0] - 1e4 * x[1] * w[0] - 3e7 * x[1] ** 2]),
        g=lambda x, w, u: np.array([x[0] + x[1] + w[0] - 1.0]),
        h=lambda x, w, u: np.zeros(0),
        x_test=[0.9, 3e-5], u_test=[], x_alt=[0.7, 2e-5], u_alt=[]),
    "HelloWorldDAE": Scene(
        "HelloWorldDAE", vr_x=[2], vr_der=[3], vr_w=[4, 5], vr_res=[6, 7], vr_u=[], vr_y=[],
        vr_enable=1, tunable=False, x0=[1.0], w0=[0.0, 0.0], x_nominal=[1.0],
        f=lambda x, w, u: np.array([w[0]]),
        g=lambda x, w, u: np.array([w[0] + 2 * w[1] - x[0], w[0] - 3 * w[1] - 2 * x[0]]),
        h=lambda x, w, u: np.zeros(0),
        x_test=[1.7], u_test=[], x_alt=[-0.4], u_alt=[]),
}

PARAMS = sorted(SCENES)

def _chain_g(x, w, u):
    left = np.concatenate([[x[0]], w[:-1]])
    right = np.concatenate([w[1:], [u[0]]])
    return 4 * w + np.sin(w) - left - right


SCENES["Chain"] = Scene(
    "Chain", vr_x=[2], vr_der=[3], vr_w=[10, 12, 14, 16], vr_res=[11, 13, 15, 17], vr_u=[4],
    vr_y=[5], vr_enable=1, tunable=False, x0=[1.0], w0=[0.0] * 4, x_nominal=[1.0],
    f=lambda x, w, u: np.array([w[0] - x[0]]), g=_chain_g,
    h=lambda x, w, u: np.array([w[-1]]),
    x_test=[0.7], u_test=[0.3], x_alt=[-0.4], u_alt=[-0.2])


def _blocks_g(x, w, u, block=10):
    n = len(w)
    blocks = w.reshape(n // block, block)
    own = np.repeat(blocks.sum(axis=1), block) - w
    sums = blocks.sum(axis=1)
    beside = np.repeat(np.concatenate([[0.0], sums[:-1]]) + np.concatenate([sums[1:], [0.0]]),
                       block)
    g = 4 * w + np.sin(w) - 0.1 * own - 0.05 * beside
    g[:block] -= 0.5 * x[0]
    g[-block:] -= 0.5 * u[0]
    return g


SCENES["Blocks"] = Scene(
    "Blocks", vr_x=[2], vr_der=[3], vr_w=[10 + 2 * i for i in range(30)],
    vr_res=[11 + 2 * i for i in range(30)], vr_u=[4], vr_y=[5], vr_enable=1, tunable=False,
    x0=[1.0], w0=[0.0] * 30, x_nominal=[1.0],
    f=lambda x, w, u: np.array([w[0] - x[0]]), g=_blocks_g,
    h=lambda x, w, u: np.array([w[-1]]),
    x_test=[0.7], u_test=[0.3], x_alt=[-0.4], u_alt=[-0.2])


# ---------------------------------------------- hard scenes (issue 5; see their README.md)

def _akzo_rates(x, w):
    y1, y2, y3, y4, y5 = x
    s2 = np.sqrt(y2)
    return (18.7 * y1 ** 4 * s2, 0.58 * y3 * y4, 0.58 / 34.4 * y1 * y5, 0.09 * y1 * y4 ** 2,
            0.42 * w[0] ** 2 * s2, 3.3 * (0.9 / 737.0 - y2))


def _akzo_f(x, w, u):
    r1, r2, r3, r4, r5, fin = _akzo_rates(x, w)
    return np.array([-2 * r1 + r2 - r3 - r4, -0.5 * r1 - r4 - 0.5 * r5 + fin, r1 - r2 + r3,
                     -r2 + r3 - 2 * r4, r2 - r3 + r5])


def _fourbar(length_unit, force_unit):
    """f and g of scenes/FourBar/fourbar.h, written again in numpy (same operation
    order as the C code: the moment balances cancel terms of 1e3, so rounding shows)."""
    l1, l2, l3, fz, fy, pn, pt = 0.35, 0.30, 0.30, 1e4, -1e4, -0.1, 0.3
    mass1, mass3 = 4.0 * l1 * l1 / 3.0 + 20.0 * l1 * l1, 2.0 * l3 * l3 / 3.0 + 10.0 * l3 * l3
    wb, wc = (4.0 / 2.0 + 20.0) * 9.81 * l1, (2.0 / 2.0 + 10.0) * 9.81 * l3
    rscale = np.array([force_unit * length_unit] * 3 + [length_unit] * 2)

    def g(x, w, u):
        (t1, t2, t3, o1, o2, o3), (a1, a2, a3) = x, w[:3]
        lx, ly = w[3] * force_unit, w[4] * force_unit
        c1, s1, c2, s2, c3, s3 = np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2), np.cos(t3), \
            np.sin(t3)
        res = np.array([
            mass1 * a1 + l1 * (-s1 * lx + c1 * ly)
            - (-wb * c1 + l1 * (-fy * s1 + fz * c1) - 4e4 * (t1 - -0.013) - 100.0 * o1),
            -l2 * (c2 * lx + s2 * ly) - (-pn * (fy * c2 + fz * s2) + pt * (-fy * s2 + fz * c2)),
            mass3 * a3 - l3 * (-s3 * lx + c3 * ly) - (-wc * c3),
            -l1 * s1 * a1 - l2 * c2 * a2 + l3 * s3 * a3
            - l1 * c1 * o1 * o1 + l2 * s2 * o2 * o2 + l3 * c3 * o3 * o3,
            l1 * c1 * a1 - l2 * s2 * a2 - l3 * c3 * a3
            - l1 * s1 * o1 * o1 - l2 * c2 * o2 * o2 + l3 * s3 * o3 * o3])
        return res / rscale

    return (lambda x, w, u: np.array([x[3], x[4], x[5], w[0], w[1], w[2]])), g


_EPS_NS = 1e-3   # NearSingular's default NEAR_SINGULAR_EPS
_FB_SI, _FB_SCALED = _fourbar(1.0, 1.0), _fourbar(1e-3, 1e3)
_FB_X_TEST = [0.09, 0.1003, 0.085, -1.2, 0.002, -1.4]
_FB_X_ALT = [0.075, 0.1006, 0.07, 0.3, -0.004, 0.4]

SCENES.update({
    "Akzo": Scene(
        "Akzo", vr_x=[2, 4, 6, 8, 10], vr_der=[3, 5, 7, 9, 11], vr_w=[12], vr_res=[13], vr_u=[],
        vr_y=[], vr_enable=1, tunable=False, x0=[0.444, 0.00123, 0.0, 0.007, 0.0], w0=[0.36],
        x_nominal=[0.1, 1e-3, 0.1, 1e-3, 0.01], f=_akzo_f,
        g=lambda x, w, u: np.array([115.83 * x[0] * x[3] - w[0]]),
        h=lambda x, w, u: np.zeros(0),
        x_test=[0.3, 1.1e-3, 0.08, 2e-3, 0.01], u_test=[],
        x_alt=[0.2, 0.9e-3, 0.12, 1e-3, 0.015], u_alt=[]),
    "VanDerPolDAE": Scene(
        "VanDerPolDAE", vr_x=[2], vr_der=[3], vr_w=[4], vr_res=[5], vr_u=[], vr_y=[],
        vr_enable=1, tunable=False, x0=[2.0], w0=[-0.5], x_nominal=[1.0],
        f=lambda x, w, u: np.array([w[0]]),
        g=lambda x, w, u: np.array([(1 - x[0] ** 2) * w[0] - x[0]]),
        h=lambda x, w, u: np.zeros(0), x_test=[1.8], u_test=[], x_alt=[1.5], u_alt=[]),
    "NearSingular": Scene(
        "NearSingular", vr_x=[2], vr_der=[3], vr_w=[4, 5], vr_res=[6, 7], vr_u=[], vr_y=[],
        vr_enable=1, tunable=False, x0=[1.0], w0=[0.0, 0.0], x_nominal=[1.0],
        f=lambda x, w, u: np.array([-np.sin(w[0] + 2 * w[1])]),
        g=lambda x, w, u: np.array([w[0] + 2 * w[1] - x[0],
                                    w[0] + (2 + _EPS_NS) * w[1] - x[0] - _EPS_NS * np.sin(x[0])]),
        h=lambda x, w, u: np.zeros(0), x_test=[0.7], u_test=[], x_alt=[-0.4], u_alt=[]),
    **{name: Scene(
        name, vr_x=[2, 4, 6, 8, 10, 12], vr_der=[3, 5, 7, 9, 11, 13], vr_w=[14, 15, 16, 17, 18],
        vr_res=[19, 20, 21, 22, 23], vr_u=[], vr_y=[], vr_enable=1, tunable=False,
        x0=[0.1, 0.1, 0.1, 0.0, 0.0, 0.0], w0=[0.0] * 5, x_nominal=[0.1, 0.1, 0.1, 1.0, 1.0, 1.0],
        f=fg[0], g=fg[1], h=lambda x, w, u: np.zeros(0),
        x_test=_FB_X_TEST, u_test=[], x_alt=_FB_X_ALT, u_alt=[])
       for name, fg in (("FourBar", _FB_SI), ("FourBarScaled", _FB_SCALED))},
    "MassSpringDAE": Scene(
        "MassSpringDAE", vr_x=[2, 4], vr_der=[3, 5], vr_w=[6], vr_res=[7], vr_u=[], vr_y=[8],
        vr_enable=1, tunable=False, x0=[1.0, 0.0], w0=[0.0], x_nominal=[1.0, 1.0],
        f=lambda x, w, u: np.array([x[1], w[0] / 2.0]),
        g=lambda x, w, u: np.array([w[0] + 8.0 * x[0]]),
        h=lambda x, w, u: np.array([x[1] ** 2 + 4.0 * x[0] ** 2]),
        x_test=[0.6, -1.2], u_test=[], x_alt=[-0.3, 0.8], u_alt=[]),
    # the equations with the discrete variables at their start (k = 1, b = 0); the events
    # themselves are tested in test_event_scene.py
    "EventDAE": Scene(
        "EventDAE", vr_x=[1], vr_der=[2], vr_w=[3], vr_res=[5], vr_u=[], vr_y=[4],
        vr_enable=9, tunable=True, x0=[1.0], w0=[1.0], x_nominal=[1.0],
        f=lambda x, w, u: np.array([-w[0]]), g=lambda x, w, u: np.array([w[0] - x[0]]),
        h=lambda x, w, u: np.array([w[0]]), x_test=[0.8], u_test=[], x_alt=[0.6], u_alt=[],
        vr_z=[6], vr_d=[7, 8]),
})
PARAMS = sorted(SCENES)


# -------------------------------------------------------------------- fixtures

@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """name -> (fmu path, unzip dir, fmpy model description)."""
    out = {}
    for name in PARAMS:
        fmu = build_scene(name)
        unzip = fmpy.extract(str(fmu), str(tmp_path_factory.mktemp(name)))
        out[name] = (fmu, Path(unzip), fmpy.read_model_description(str(fmu)))
    return out


class Instance:
    """A thin wrapper around fmpy's FMU3Model with raw (non-raising) calls."""

    def __init__(self, scene: Scene, built_entry):
        fmu, unzip, md = built_entry
        self.scene = scene
        self.mode = "ct"   # "ct" or "init": how _perturb sets states
        self.fmu = FMU3Model(guid=md.guid, unzipDirectory=str(unzip),
                             modelIdentifier=md.modelExchange.modelIdentifier,
                             instanceName=scene.name)
        self.fmu.instantiate()

    def raw(self, fname: str, *args) -> int:
        return self.fmu._functions[fname](self.fmu.component, *args)

    def raw_set_float64(self, vrs, values) -> int:
        n = len(vrs)
        return self.raw("fmi3SetFloat64", (ctypes.c_uint32 * n)(*vrs), n,
                        (ctypes.c_double * n)(*values), n)

    def raw_set_boolean(self, vrs, values) -> int:
        n = len(vrs)
        return self.raw("fmi3SetBoolean", (ctypes.c_uint32 * n)(*vrs), n,
                        (ctypes.c_bool * n)(*values), n)

    def get(self, vrs) -> np.ndarray:
        return np.array(self.fmu.getFloat64(list(vrs))) if vrs else np.zeros(0)

    def set(self, vrs, values) -> None:
        if vrs:
            self.fmu.setFloat64(list(vrs), [float(v) for v in values])

    def set_states(self, x) -> None:
        n = len(x)
        self.fmu.setContinuousStates((ctypes.c_double * n)(*x), n)

    def derivatives(self) -> np.ndarray:
        n = len(self.scene.vr_x)
        buf = (ctypes.c_double * n)()
        self.fmu.getContinuousStateDerivatives(buf, n)
        return np.array(buf)

    def enable_dae(self) -> None:
        self.fmu.enterConfigurationMode()
        self.fmu.setBoolean([self.scene.vr_enable], [True])
        self.fmu.exitConfigurationMode()

    def initialize(self, x=None, u=None, t0=0.0) -> None:
        if x is not None:
            self.set(self.scene.vr_x, x)
        if u is not None:
            self.set(self.scene.vr_u, u)
        self.fmu.enterInitializationMode(startTime=t0)
        self.fmu.exitInitializationMode()

    def to_continuous(self, dae=False, x=None, u=None) -> "Instance":
        if dae:
            self.enable_dae()
        self.initialize(x, u)
        self.fmu.enterContinuousTimeMode()
        return self

    def dd(self, unknowns, knowns, seed) -> np.ndarray:
        return np.array(self.fmu.getDirectionalDerivative(list(unknowns), list(knowns),
                                                          list(seed)))

    def adj(self, unknowns, knowns, seed) -> np.ndarray:
        return np.array(self.fmu.getAdjointDerivative(list(unknowns), list(knowns), list(seed),
                                                      nSensitivity=len(knowns)))

    def jacobian(self, unknowns, knowns) -> np.ndarray:
        cols = [self.dd(unknowns, knowns, np.eye(len(knowns))[j]) for j in range(len(knowns))]
        return np.array(cols).T.reshape(len(unknowns), len(knowns))

    def free(self) -> None:
        self.fmu.freeInstance()


@pytest.fixture
def make(built):
    created = []

    def factory(name: str) -> Instance:
        inst = Instance(SCENES[name], built[name])
        created.append(inst)
        return inst

    yield factory
    for inst in created:
        inst.free()


# ------------------------------------------------------------------ XML helpers

def _md_root(name):
    return etree.parse(str(scene_xml_dir(name) / "modelDescription.xml")).getroot()


def _manifest_root(name):
    return etree.parse(str(scene_xml_dir(name) / "fmi-ls-manifest.xml")).getroot()


def _variables(name) -> dict[int, etree._Element]:
    return {int(v.get("valueReference")): v for v in _md_root(name).find("ModelVariables")}


def _structure(root, tags) -> dict[int, tuple[list[int] | None, list[str] | None]]:
    """vr -> (dependencies or None if absent, dependenciesKind or None)."""
    out = {}
    for el in root.find("ModelStructure"):
        if el.tag in tags:
            deps = el.get("dependencies")
            kinds = el.get("dependenciesKind")
            out[int(el.get("valueReference"))] = (
                None if deps is None else [int(d) for d in deps.split()],
                None if kinds is None else kinds.split())
    return out


def _perturb(inst: Instance, vr: int, value: float, kind: str) -> None:
    """Set a known; states through fmi3SetContinuousStates in Continuous-Time Mode."""
    sc = inst.scene
    if kind == "x" and inst.mode == "ct":
        x = inst.get(sc.vr_x)
        x[sc.vr_x.index(vr)] = value
        inst.set_states(x)
    else:
        inst.set([vr], [value])


def _fd_jacobian(inst: Instance, unknowns, knowns, kinds, steps) -> np.ndarray:
    J = np.zeros((len(unknowns), len(knowns)))
    for j, (vr, kind, h) in enumerate(zip(knowns, kinds, steps)):
        v0 = inst.get([vr])[0]
        _perturb(inst, vr, v0 + h, kind)
        plus = inst.get(unknowns)
        _perturb(inst, vr, v0 - h, kind)
        minus = inst.get(unknowns)
        _perturb(inst, vr, v0, kind)
        J[:, j] = (plus - minus) / (2 * h)
    return J


def _knowns(sc: Scene, dae: bool):
    knowns = list(sc.vr_x) + (list(sc.vr_w) if dae else []) + list(sc.vr_u)
    kinds = ["x"] * len(sc.vr_x) + (["w"] * len(sc.vr_w) if dae else []) + ["u"] * len(sc.vr_u)
    noms = list(sc.x_nominal) + ([1.0] * len(sc.vr_w) if dae else []) + [1.0] * len(sc.vr_u)
    return knowns, kinds, [1e-6 * n for n in noms]


def _assert_close_jac(J, J_fd, what):
    scale = max(1.0, float(np.abs(J_fd).max(initial=0.0)))
    np.testing.assert_allclose(J, J_fd, rtol=1e-5, atol=1e-7 * scale, err_msg=what)


# ------------------------------------------------------------------ static tests

def test_scene_list():
    assert scene_names() == PARAMS


@pytest.mark.parametrize("name", PARAMS)
def test_model_description_validates_against_fmi3_xsd(name):
    schema = etree.XMLSchema(etree.parse(str(FMPY_DIR / "schema" / "fmi3" /
                                             "fmi3ModelDescription.xsd")))
    doc = etree.parse(str(scene_xml_dir(name) / "modelDescription.xml"))
    assert schema.validate(doc), schema.error_log


@pytest.mark.parametrize("name", PARAMS)
def test_variables_match_reference_tables(name):
    sc = SCENES[name]
    var = _variables(name)
    assert var[0].get("causality") == "independent" and var[0].get("start") is None
    assert [v for v in var.values() if v.get("causality") == "independent"] == [var[0]]
    for vr, der in zip(sc.vr_x, sc.vr_der):
        assert var[der].get("derivative") == str(vr)
        assert var[vr].get("initial") == "exact" and var[vr].get("nominal")
    for vr, x0 in zip(sc.vr_x, sc.x0):
        assert float(var[vr].get("start")) == x0
    for vr, w0 in zip(sc.vr_w, sc.w0):
        v = var[vr]
        assert (v.tag, v.get("causality"), v.get("variability"), v.get("initial")) == \
            ("Float64", "local", "continuous", "approx")
        assert float(v.get("start")) == w0 and v.get("nominal")
    for vr in sc.vr_res:
        v = var[vr]
        assert (v.tag, v.get("causality", "local"), v.get("variability", "continuous")) == \
            ("Float64", "local", "continuous")
        assert v.get("start") is None and v.get("initial") is None
    for vr in sc.vr_u:
        assert var[vr].get("causality") == "input"
    assert sorted(vr for vr, v in var.items() if v.get("causality") == "output") == sc.vr_y
    en = var[sc.vr_enable]
    assert (en.tag, en.get("causality"), en.get("start")) == \
        ("Boolean", "structuralParameter", "false")
    assert en.get("variability") == ("tunable" if sc.tunable else "fixed")
    for vr in sc.vr_z:
        v = var[vr]
        assert (v.tag, v.get("causality"), v.get("variability"), v.get("start")) == \
            ("Float64", "local", "continuous", None)
    for vr in sc.vr_d:
        v = var[vr]
        assert (v.tag, v.get("causality"), v.get("variability"), v.get("start")) == \
            ("Float64", "local", "discrete", None)
    all_vrs = {0, sc.vr_enable, *sc.vr_x, *sc.vr_der, *sc.vr_w, *sc.vr_res, *sc.vr_u, *sc.vr_y,
               *sc.vr_z, *sc.vr_d}
    assert set(var) == all_vrs


@pytest.mark.parametrize("name", PARAMS)
def test_model_structure_lists(name):
    """Outputs, all derivatives, and InitialUnknowns exactly per MS-05."""
    sc = SCENES[name]
    root = _md_root(name)
    var = _variables(name)
    order = [el.tag for el in root.find("ModelStructure")]
    assert order == sorted(order, key=["Output", "ContinuousStateDerivative",
                                       "InitialUnknown", "EventIndicator"].index)
    assert list(_structure(root, {"Output"})) == sc.vr_y
    assert list(_structure(root, {"EventIndicator"})) == sc.vr_z
    assert list(_structure(root, {"ContinuousStateDerivative"})) == sc.vr_der
    expected = sorted(
        vr for vr, v in var.items()
        if (v.get("causality") == "output" and v.get("initial", "calculated") != "exact")
        or ((vr in sc.vr_x or vr in sc.vr_der) and v.get("initial", "calculated") != "exact"))
    assert sorted(_structure(root, {"InitialUnknown"})) == expected


@pytest.mark.parametrize("name", PARAMS)
def test_manifest_shape(name):
    sc = SCENES[name]
    root = _manifest_root(name)
    ns = "{http://fmi-standard.org/fmi-ls-manifest}"
    assert root.tag == "fmiDAEManifest"
    assert root.get(ns + "fmi-ls-name") == "org.fmi-standard.fmi-ls-dae"
    assert root.get(ns + "fmi-ls-version") == "1.0.0-alpha.1"
    assert root.get(ns + "fmi-ls-description") == "Layered standard for DAE support in FMI."
    assert [c.tag for c in root] == ["EnableDAEParameter", "AlgebraicVariables", "ModelStructure"]
    assert int(root[0].get("valueReference")) == sc.vr_enable
    assert [int(a.get("valueReference")) for a in root[1]] == sc.vr_w
    order = [el.tag for el in root.find("ModelStructure")]
    rank = ["Output", "ContinuousStateDerivative", "InitialUnknown", "EventIndicator", "Residual"]
    assert order == sorted(order, key=rank.index)
    assert list(_structure(root, {"EventIndicator"})) == sc.vr_z
    assert list(_structure(root, {"Residual"})) == sc.vr_res
    assert list(_structure(root, {"Output"})) == sc.vr_y
    assert list(_structure(root, {"ContinuousStateDerivative"})) == sc.vr_der
    for deps, kinds in _structure(root, set(rank)).values():
        if kinds is not None:
            assert deps is not None and len(deps) == len(kinds)


# -------------------------------------------------------------- build / archive

def test_archive_layout_and_clean_build():
    for name in PARAMS:
        fmu = build_scene(name)
        assert fmu.name == f"{name}.fmu"
        assert (fmu.parent / "build.log").read_text() == "", "compiler warnings"
        with zipfile.ZipFile(fmu) as zf:
            names = sorted(zf.namelist())
            assert names == sorted(["modelDescription.xml", MANIFEST_ENTRY,
                                    f"binaries/{platform_tuple()}/{name}{shared_library_extension()}"])
            assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in zf.infolist())
            assert zf.read("modelDescription.xml") == \
                (scene_xml_dir(name) / "modelDescription.xml").read_bytes()


def test_cache_reuse_and_defines(tmp_path):
    first = build_scene("HelloWorldDAE", cache_dir=tmp_path)
    mtime = first.stat().st_mtime_ns
    assert build_scene("HelloWorldDAE", cache_dir=tmp_path) == first
    assert first.stat().st_mtime_ns == mtime
    other = build_scene("HelloWorldDAE", defines=["LSDAE_UNUSED_MACRO"], cache_dir=tmp_path)
    assert other != first and other.is_file()
    assert build_scene("HelloWorldDAE", defines=["-DLSDAE_UNUSED_MACRO"],
                       cache_dir=tmp_path) == other


def test_cache_env_var_and_concurrent_builds(tmp_path):
    env = dict(os.environ, LSDAE_SCENE_CACHE=str(tmp_path))
    code = "from scenes.build import build_scene; print(build_scene('Robertson'))"
    procs = [subprocess.Popen([sys.executable, "-c", code], cwd=REPO_ROOT, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    results = [p.communicate(timeout=120) for p in procs]
    assert all(p.returncode == 0 for p in procs), results
    paths = {Path(out.strip()) for out, _ in results}
    assert len(paths) == 1
    fmu = paths.pop()
    assert fmu.parent.parent == tmp_path
    with zipfile.ZipFile(fmu) as zf:
        assert zf.testzip() is None
    assert not [p for p in fmu.parent.iterdir() if p.name.startswith(".build-")]


def test_cli_copies_to_out(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "scenes.build", "SimpleDAE", "Robertson",
                           "--out", str(tmp_path)], cwd=REPO_ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Robertson.fmu", "SimpleDAE.fmu"]


# ------------------------------------------------------------- dynamic: basics

def test_all_fmi3_functions_exported(built):
    header = (FMPY_DIR / "c-code" / "fmi3Functions.h").read_text()
    names = re.findall(r"FMI3_Export\s+\w+TYPE\s+(\w+);", header)
    assert len(names) > 60
    for name in PARAMS:
        lib = ctypes.CDLL(str(built[name][1] / "binaries" / platform_tuple() /
                               f"{name}{shared_library_extension()}"))
        missing = [n for n in names if not hasattr(lib, n)]
        assert not missing, f"{name}: {missing}"


@pytest.mark.parametrize("name", PARAMS)
def test_start_values_and_counts(make, name):
    sc = SCENES[name]
    inst = make(name)
    np.testing.assert_array_equal(inst.get(sc.vr_x), sc.x0)
    np.testing.assert_array_equal(inst.get(sc.vr_w), sc.w0)
    assert inst.fmu.getBoolean([sc.vr_enable]) == [False]
    assert inst.fmu.getNumberOfContinuousStates() == len(sc.vr_x)
    assert inst.fmu.getNumberOfEventIndicators() == len(sc.vr_z)
    n = len(sc.vr_x)
    buf = (ctypes.c_double * n)()
    inst.fmu.getNominalsOfContinuousStates(buf, n)
    assert list(buf) == sc.x_nominal


@pytest.mark.parametrize("name", PARAMS)
def test_ode_mode_derivatives_match_reference(make, name):
    sc = SCENES[name]
    # at the FMU's own start point
    inst = make(name).to_continuous()
    w = sc.solve_w(np.array(sc.x0), np.zeros(len(sc.vr_u)))
    np.testing.assert_allclose(inst.get(sc.vr_w), w, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(inst.derivatives(), sc.f(sc.x0, w, np.zeros(len(sc.vr_u))),
                               rtol=1e-10, atol=1e-12)
    # at a second point, reached in Continuous-Time Mode (warm-started Newton)
    x, u = np.array(sc.x_test), np.array(sc.u_test)
    inst.set_states(x)
    inst.set(sc.vr_u, u)
    inst.fmu.setTime(0.25)
    w = sc.solve_w(x, u)
    np.testing.assert_allclose(inst.get(sc.vr_w), w, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(inst.derivatives(), sc.f(x, w, u), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(inst.get(sc.vr_der), sc.f(x, w, u), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(inst.get(sc.vr_y), sc.h(x, w, u), rtol=1e-9, atol=1e-12)
    assert inst.get([0])[0] == 0.25


def test_simple_dae_start_point_solution(make):
    inst = make("SimpleDAE").to_continuous()
    z1, z2 = inst.get([5, 6])
    assert abs(z1) < 1e-14
    assert z2 == pytest.approx(2 * np.arcsin(1 / 3), rel=1e-12)


def test_hello_world_closed_form(make):
    inst = make("HelloWorldDAE").to_continuous(x=[2.0])
    np.testing.assert_allclose(inst.get([4, 5]), [2.8, -0.4], rtol=1e-13)
    np.testing.assert_allclose(inst.derivatives(), [2.8], rtol=1e-13)


def test_fmpy_simulation_ode_mode(built):
    """A standard importer runs the ODE-mode FMUs; known Robertson and closed-form values."""
    result = fmpy.simulate_fmu(str(built["Robertson"][0]), fmi_type="ModelExchange",
                               stop_time=40.0)
    assert result["y1"][-1] == pytest.approx(0.7158, abs=2e-4)
    assert result["y2"][-1] == pytest.approx(9.185e-6, rel=2e-3)
    result = fmpy.simulate_fmu(str(built["HelloWorldDAE"][0]), fmi_type="ModelExchange",
                               stop_time=1.0, output=["x"])
    assert result["x"][-1] == pytest.approx(np.exp(1.4), rel=1e-4)


@pytest.mark.parametrize("name", PARAMS)
def test_setting_algebraic_variable_in_ode_mode_is_rejected(make, name):
    sc = SCENES[name]
    inst = make(name)
    assert inst.raw_set_float64(sc.vr_w[:1], [0.1]) == 0   # Instantiated: a guess value
    inst.to_continuous()
    assert inst.raw_set_float64(sc.vr_w[:1], [0.3]) == FMI_ERROR
    inst2 = make(name)
    inst2.initialize()                                       # Event Mode
    assert inst2.raw_set_float64(sc.vr_w[:1], [0.3]) == FMI_ERROR
    assert inst2.raw_set_float64(sc.vr_res[:1], [0.3]) == FMI_ERROR
    assert inst2.raw_set_float64([0], [1.0]) == FMI_ERROR   # time


# --------------------------------------------------------------- dynamic: DAE

@pytest.mark.parametrize("name", PARAMS)
def test_dae_handshake_and_consistent_start(make, name):
    sc = SCENES[name]
    inst = make(name)
    inst.enable_dae()
    assert inst.fmu.getBoolean([sc.vr_enable]) == [True]
    inst.initialize()
    assert inst.fmu.getBoolean([sc.vr_enable]) == [True]
    assert inst.fmu.getNumberOfContinuousStates() == len(sc.vr_x)
    res = inst.get(sc.vr_res)
    assert np.all(np.abs(res) <= 1e-10), res
    u0 = np.zeros(len(sc.vr_u))
    np.testing.assert_allclose(inst.get(sc.vr_w), sc.solve_w(np.array(sc.x0), u0),
                               rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("name", PARAMS)
def test_dae_mode_uses_the_algebraic_values_it_is_given(make, name):
    sc = SCENES[name]
    inst = make(name).to_continuous(dae=True)
    x, u = np.array(sc.x_test), np.array(sc.u_test)
    inst.set_states(x)
    inst.set(sc.vr_u, u)
    w_star = sc.solve_w(x, u) + 0.05 * np.arange(1, len(sc.vr_w) + 1)
    assert inst.raw_set_float64(sc.vr_w, w_star) == 0
    np.testing.assert_array_equal(inst.get(sc.vr_w), w_star)
    res = inst.get(sc.vr_res)
    np.testing.assert_allclose(res, sc.g(x, w_star, u), rtol=1e-12, atol=1e-14)
    assert np.abs(res).max() > 1e-3
    np.testing.assert_allclose(inst.derivatives(), sc.f(x, w_star, u), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(inst.get(sc.vr_y), sc.h(x, w_star, u), rtol=1e-12, atol=1e-14)
    # changing the states must not overwrite w
    inst.set_states(x * 1.01)
    np.testing.assert_array_equal(inst.get(sc.vr_w), w_star)
    # Event Mode accepts w too
    inst.fmu.enterEventMode()
    assert inst.raw_set_float64(sc.vr_w, w_star * 0.5) == 0
    np.testing.assert_array_equal(inst.get(sc.vr_w), w_star * 0.5)


@pytest.mark.parametrize("name", PARAMS)
def test_cross_mode_consistency(make, name):
    """DAE-42: ODE-mode w and derivatives make the residual vanish in DAE mode."""
    sc = SCENES[name]
    x, u = sc.x_test, sc.u_test
    ode = make(name).to_continuous(x=x, u=u)
    w, der, y = ode.get(sc.vr_w), ode.derivatives(), ode.get(sc.vr_y)
    dae = make(name).to_continuous(dae=True)
    dae.set_states(x)
    dae.set(sc.vr_u, u)
    dae.set(sc.vr_w, w)
    assert np.abs(dae.get(sc.vr_res)).max(initial=0.0) < 1e-10
    np.testing.assert_allclose(dae.derivatives(), der, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dae.get(sc.vr_y), y, rtol=1e-12, atol=1e-14)


# ---------------------------------------------------- dynamic: state machine

@pytest.mark.parametrize("name", PARAMS)
def test_state_machine_rejections(make, name):
    sc = SCENES[name]
    inst = make(name)
    assert inst.raw_set_boolean([sc.vr_enable], [True]) == FMI_ERROR       # Instantiated
    assert inst.raw("fmi3EnterContinuousTimeMode") == FMI_ERROR
    assert inst.raw("fmi3ExitInitializationMode") == FMI_ERROR
    assert inst.raw("fmi3ExitConfigurationMode") == FMI_ERROR
    one, seed, out = (ctypes.c_uint32 * 1)(sc.vr_der[0]), (ctypes.c_double * 1)(1.0), \
        (ctypes.c_double * 1)()
    assert inst.raw("fmi3GetDirectionalDerivative", one, 1, (ctypes.c_uint32 * 1)(sc.vr_x[0]),
                    1, seed, 1, out, 1) == FMI_ERROR
    inst.fmu.enterConfigurationMode()
    assert inst.raw_set_float64(sc.vr_x[:1], [0.1]) == FMI_ERROR           # Configuration Mode
    assert inst.raw("fmi3EnterInitializationMode", False, 0.0, 0.0, False, 0.0) == FMI_ERROR
    inst.fmu.exitConfigurationMode()
    inst.initialize()
    assert inst.raw_set_boolean([sc.vr_enable], [True]) == FMI_ERROR       # Event Mode
    assert inst.raw("fmi3EnterEventMode") == FMI_ERROR
    assert inst.raw("fmi3SetTime", ctypes.c_double(1.0)) == FMI_ERROR
    inst.fmu.enterContinuousTimeMode()
    assert inst.raw_set_boolean([sc.vr_enable], [True]) == FMI_ERROR       # CT Mode
    assert inst.raw("fmi3EnterConfigurationMode") == FMI_ERROR
    assert inst.raw_set_float64(sc.vr_der[:1], [0.1]) == FMI_ERROR
    inst.fmu.enterEventMode()
    status = inst.raw("fmi3EnterConfigurationMode")
    assert status == (0 if sc.tunable else FMI_ERROR)
    if sc.tunable:
        inst.fmu.exitConfigurationMode()
    inst.fmu.terminate()
    assert inst.raw_set_float64(sc.vr_x[:1], [0.1]) == FMI_ERROR           # Terminated
    inst.fmu.getFloat64(sc.vr_der)                                         # Get still allowed


@pytest.mark.parametrize("name", PARAMS)
def test_reset_restores_start(make, name):
    sc = SCENES[name]
    inst = make(name).to_continuous(dae=True)
    inst.set_states(sc.x_test)
    inst.fmu.reset()
    assert inst.fmu.getBoolean([sc.vr_enable]) == [False]
    np.testing.assert_array_equal(inst.get(sc.vr_x), sc.x0)
    np.testing.assert_array_equal(inst.get(sc.vr_w), sc.w0)
    inst.to_continuous()
    assert inst.raw_set_float64(sc.vr_w[:1], [0.3]) == FMI_ERROR   # ODE mode again


def test_runtime_switch_simple_dae(make):
    """Tunable switch: Event Mode -> Reconfiguration Mode -> DAE mode and back."""
    sc = SCENES["SimpleDAE"]
    inst = make("SimpleDAE").to_continuous(x=sc.x_test, u=sc.u_test)
    w_ode = inst.get(sc.vr_w)
    inst.fmu.enterEventMode()
    inst.fmu.enterConfigurationMode()
    inst.fmu.setBoolean([sc.vr_enable], [True])
    inst.fmu.exitConfigurationMode()
    assert inst.fmu.getBoolean([sc.vr_enable]) == [True]
    np.testing.assert_array_equal(inst.get(sc.vr_w), w_ode)
    assert np.abs(inst.get(sc.vr_res)).max() < 1e-10
    inst.fmu.enterContinuousTimeMode()
    assert inst.raw_set_float64(sc.vr_w, w_ode + 0.1) == 0
    inst.fmu.enterEventMode()
    inst.fmu.enterConfigurationMode()
    inst.fmu.setBoolean([sc.vr_enable], [False])
    inst.fmu.exitConfigurationMode()
    np.testing.assert_allclose(inst.get(sc.vr_w), w_ode, rtol=1e-10)   # re-solved
    inst.fmu.enterContinuousTimeMode()
    assert inst.raw_set_float64(sc.vr_w, w_ode) == FMI_ERROR


@pytest.mark.parametrize("name", PARAMS)
def test_fmu_state_roundtrip(make, name):
    sc = SCENES[name]
    inst = make(name).to_continuous(x=sc.x_test, u=sc.u_test)
    der = inst.derivatives()
    state = inst.fmu.getFMUState()
    inst.set_states(np.array(sc.x_alt))
    assert not np.allclose(inst.derivatives(), der)
    inst.fmu.setFMUState(state)
    np.testing.assert_array_equal(inst.derivatives(), der)
    inst.fmu.freeFMUState(state)


# -------------------------------------------------- dynamic: partial derivatives

def _enter(make, name, dae, x, u, mode="ct"):
    inst = make(name)
    if mode == "ct":
        inst.to_continuous(dae=dae, x=x, u=u)
    else:  # Initialization Mode, knowns set there
        if dae:
            inst.enable_dae()
        inst.set(inst.scene.vr_x, x)
        inst.set(inst.scene.vr_u, u)
        inst.fmu.enterInitializationMode()
    inst.mode = mode
    if mode == "ct" and dae:
        # move w away from the consistent value: partials are taken at any point
        sc = inst.scene
        inst.set(sc.vr_w, inst.get(sc.vr_w) + 0.03)
    return inst


@pytest.mark.parametrize("dae", [False, True], ids=["ode", "dae"])
@pytest.mark.parametrize("name", PARAMS)
def test_directional_derivatives_match_finite_differences(make, name, dae):
    sc = SCENES[name]
    inst = _enter(make, name, dae, sc.x_test, sc.u_test)
    unknowns = sc.vr_der + (sc.vr_res if dae else []) + sc.vr_y
    knowns, kinds, steps = _knowns(sc, dae)
    J = inst.jacobian(unknowns, knowns)
    J_fd = _fd_jacobian(inst, unknowns, knowns, kinds, steps)
    _assert_close_jac(J, J_fd, f"{name} {'DAE' if dae else 'ODE'}")
    # one call with a dense seed, and the adjoint as the transpose
    rng = np.random.default_rng(1)
    seed = rng.normal(size=len(knowns))
    np.testing.assert_allclose(inst.dd(unknowns, knowns, seed), J @ seed, rtol=1e-12, atol=1e-12)
    v = rng.normal(size=len(unknowns))
    np.testing.assert_allclose(inst.adj(unknowns, knowns, v), J.T @ v, rtol=1e-12,
                               atol=1e-12 * max(1.0, np.abs(J).max()))
    # time is a known with a zero column (no explicit time dependence)
    np.testing.assert_array_equal(inst.dd(unknowns, [0], [1.0]), np.zeros(len(unknowns)))


@pytest.mark.parametrize("dae", [False, True], ids=["ode", "dae"])
@pytest.mark.parametrize("name", PARAMS)
def test_jacobian_pattern_matches_model_structure(make, name, dae):
    """Unlisted entries are exactly 0, listed ones nonzero, 'constant' ones constant."""
    sc = SCENES[name]
    root = _manifest_root(name) if dae else _md_root(name)
    structure = _structure(root, {"Output", "ContinuousStateDerivative", "Residual"})
    unknowns = list(structure)
    knowns, _, _ = _knowns(sc, dae)
    J = _enter(make, name, dae, sc.x_test, sc.u_test).jacobian(unknowns, knowns)
    J2 = _enter(make, name, dae, sc.x_alt, sc.u_alt).jacobian(unknowns, knowns)
    for i, vr in enumerate(unknowns):
        deps, kinds = structure[vr]
        kinds = kinds or ["dependent"] * len(deps)
        for j, k in enumerate(knowns):
            if k in deps:
                assert J[i, j] != 0.0, f"d{vr}/d{k} listed but zero"
                if kinds[deps.index(k)] in ("constant", "fixed", "tunable", "discrete"):
                    # a factor that changes only with parameters or at events (EventDAE's k)
                    assert J2[i, j] == pytest.approx(J[i, j], rel=1e-12), f"d{vr}/d{k}"
                else:
                    assert J2[i, j] != pytest.approx(J[i, j], rel=1e-9), \
                        f"d{vr}/d{k} looks constant but is declared dependent"
            else:
                assert J[i, j] == 0.0 and J2[i, j] == 0.0, f"d{vr}/d{k} not listed but nonzero"


@pytest.mark.parametrize("dae", [False, True], ids=["ode", "dae"])
@pytest.mark.parametrize("name", PARAMS)
def test_initial_unknowns_in_initialization_mode(make, name, dae):
    """InitialUnknown partials (total: the FMU solves g = 0 here in both modes)."""
    sc = SCENES[name]
    root = _manifest_root(name) if dae else _md_root(name)
    structure = _structure(root, {"InitialUnknown"})
    unknowns = list(structure)
    knowns = sc.vr_x + sc.vr_u
    kinds = ["x"] * len(sc.vr_x) + ["u"] * len(sc.vr_u)
    steps = [1e-6 * n for n in sc.x_nominal] + [1e-6] * len(sc.vr_u)
    inst = _enter(make, name, dae, sc.x_test, sc.u_test, mode="init")
    J = inst.jacobian(unknowns, knowns)
    J_fd = _fd_jacobian(inst, unknowns, knowns, kinds, steps)
    _assert_close_jac(J, J_fd, f"{name} initial unknowns")
    for i, vr in enumerate(unknowns):
        deps, _ = structure[vr]
        if deps is None:
            continue
        for j, k in enumerate(knowns):
            assert (J[i, j] != 0.0) == (k in deps), f"d{vr}/d{k}"
    inst.fmu.exitInitializationMode()
    if dae:
        assert np.abs(inst.get(sc.vr_res)).max() < 1e-10


@pytest.mark.parametrize("name", PARAMS)
def test_invalid_knowns_and_unknowns(make, name):
    sc = SCENES[name]
    ode = _enter(make, name, False, sc.x_test, sc.u_test)
    u32 = ctypes.c_uint32 * 1
    one, out = (ctypes.c_double * 1)(1.0), (ctypes.c_double * 1)()
    # ODE mode: w is no known, the residual no unknown
    assert ode.raw("fmi3GetDirectionalDerivative", u32(sc.vr_der[0]), 1, u32(sc.vr_w[0]), 1,
                   one, 1, out, 1) == FMI_ERROR
    assert ode.raw("fmi3GetDirectionalDerivative", u32(sc.vr_res[0]), 1, u32(sc.vr_x[0]), 1,
                   one, 1, out, 1) == FMI_ERROR
    # wrong sizes
    assert ode.raw("fmi3GetDirectionalDerivative", u32(sc.vr_der[0]), 1, u32(sc.vr_x[0]), 1,
                   one, 0, out, 1) == FMI_ERROR
    dae = _enter(make, name, True, sc.x_test, sc.u_test)
    assert dae.raw("fmi3GetDirectionalDerivative", u32(sc.vr_res[0]), 1, u32(sc.vr_w[0]), 1,
                   one, 1, out, 1) == 0
    assert dae.raw("fmi3GetDirectionalDerivative", u32(sc.vr_w[0]), 1, u32(sc.vr_x[0]), 1,
                   one, 1, out, 1) == FMI_ERROR   # w is no unknown after initialisation


def _ode_derivative(fmu: Path, unzip: Path) -> float:
    """der(x) of HelloWorldDAE after initialisation in ODE mode."""
    md = fmpy.read_model_description(str(fmu))
    model = FMU3Model(guid=md.guid, unzipDirectory=str(fmpy.extract(str(fmu), str(unzip))),
                      modelIdentifier=md.modelExchange.modelIdentifier, instanceName="ovr")
    model.instantiate()
    model.enterInitializationMode()
    model.exitInitializationMode()
    value = model.getFloat64([3])[0]
    model.terminate()
    model.freeInstance()
    return value


def test_overrides_build_the_replaced_source_and_key_the_cache_on_it(tmp_path):
    source = (scene_xml_dir("HelloWorldDAE") / "model.c").read_text()
    assert source.count("der[0] = w[0];") == 1
    doubled = source.replace("der[0] = w[0];", "der[0] = 2 * w[0];")
    plain = build_scene("HelloWorldDAE", cache_dir=tmp_path)
    mutant = build_scene("HelloWorldDAE", cache_dir=tmp_path,
                         overrides={"HelloWorldDAE/model.c": doubled})
    assert mutant != plain
    assert build_scene("HelloWorldDAE", cache_dir=tmp_path,
                       overrides={"HelloWorldDAE/model.c": doubled}) == mutant
    # the same text as the file is the same build as no override at all
    assert build_scene("HelloWorldDAE", cache_dir=tmp_path,
                       overrides={"HelloWorldDAE/model.c": source}) == plain
    assert (scene_xml_dir("HelloWorldDAE") / "model.c").read_text() == source
    assert _ode_derivative(plain, tmp_path / "p") == pytest.approx(1.4, rel=1e-12)
    assert _ode_derivative(mutant, tmp_path / "m") == pytest.approx(2.8, rel=1e-12)


def test_overrides_of_the_framework_and_their_errors(tmp_path):
    framework = (REPO_ROOT / "scenes" / "common" / "fmi3_framework.c").read_text()
    with pytest.raises(SceneBuildError, match="compiling"):
        build_scene("HelloWorldDAE", cache_dir=tmp_path,
                    overrides={"common/fmi3_framework.c": framework + "\nint broken = ;\n"})
    with pytest.raises(SceneBuildError, match="not a C source"):
        build_scene("HelloWorldDAE", cache_dir=tmp_path, overrides={"SimpleDAE/model.c": ""})
    with pytest.raises(SceneBuildError, match="not a C source"):
        build_scene("HelloWorldDAE", cache_dir=tmp_path,
                    overrides={"HelloWorldDAE/modelDescription.xml": ""})
    assert not [p for p in tmp_path.rglob("*.fmu")]
