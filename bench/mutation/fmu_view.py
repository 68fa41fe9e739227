"""A scene FMU as the oracle sees it: its XML read with the standard library, and an fmpy session.

Nothing here uses lsdae: the equivalence oracle and the promise checks must not share the
checker's reading of the files or its way of driving the binary, or they would inherit its
blind spots. A :class:`Session` wraps one ``fmpy.fmi3.FMU3Model`` instance; a call that
returns fmi3Error, fmi3Discard or fmi3Fatal (fmpy raises) becomes a :class:`Failure` carrying
the call and status, so that a sequence records it as an observation.
"""
from __future__ import annotations

import ctypes
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from fmpy.fmi3 import FMU3Model

MANIFEST = Path("extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml")
Value = Any  # a float, or a string naming a failure ("error: fmi3GetFloat64 status 3")


class Failure(Exception):
    """An FMI call that did not return fmi3OK or fmi3Warning."""


@dataclass(frozen=True)
class Unknown:
    vr: int
    dependencies: tuple[int, ...] | None   # None: the attribute is absent (depends on all)
    kinds: tuple[str, ...]


@dataclass(frozen=True)
class Variable:
    name: str
    vr: int
    causality: str
    variability: str
    start: float | None
    nominal: float | None
    derivative: int | None


@dataclass(frozen=True)
class SceneLayout:
    """The variables and structure an importer reads from modelDescription.xml and the manifest."""
    identifier: str
    token: str
    variables: dict[int, Variable]
    enable_vr: int
    enable_tunable: bool
    states: tuple[int, ...]
    derivatives: tuple[int, ...]
    algebraic: tuple[int, ...]
    residuals: tuple[int, ...]
    inputs: tuple[int, ...]
    outputs: tuple[int, ...]
    indicators: tuple[int, ...]
    ode: dict[str, tuple[Unknown, ...]] = field(default_factory=dict)   # by element name
    dae: dict[str, tuple[Unknown, ...]] = field(default_factory=dict)

    def all_vrs(self) -> list[int]:
        return sorted(self.variables)

    def structure(self, mode: str) -> dict[int, Unknown]:
        """Unknown by value reference: outputs, derivatives (and residuals in DAE mode)."""
        parts = self.dae if mode == "dae" else self.ode
        return {u.vr: u for name in ("Output", "ContinuousStateDerivative", "Residual")
                for u in parts.get(name, ())}


def _float(text: str | None) -> float | None:
    return None if text is None else float(text)


def _unknowns(structure: ET.Element | None) -> dict[str, tuple[Unknown, ...]]:
    out: dict[str, list[Unknown]] = {}
    for el in list(structure) if structure is not None else []:
        deps = el.get("dependencies")
        dep_vrs = None if deps is None else tuple(int(v) for v in deps.split())
        kinds = tuple((el.get("dependenciesKind") or "").split()) or \
            tuple("dependent" for _ in dep_vrs or ())
        out.setdefault(el.tag, []).append(Unknown(int(el.get("valueReference", "-1")), dep_vrs,
                                                  kinds))
    return {k: tuple(v) for k, v in out.items()}


def read_layout(unzipped: Path) -> SceneLayout:
    """The layout of an unpacked scene FMU (alpha.1 manifest)."""
    md = ET.parse(unzipped / "modelDescription.xml").getroot()
    manifest = ET.parse(unzipped / MANIFEST).getroot()
    variables: dict[int, Variable] = {}
    enable_tunable = False
    enable_vr = int(manifest.find("EnableDAEParameter").get("valueReference"))  # type: ignore
    for el in md.find("ModelVariables") or []:
        vr = int(el.get("valueReference", "-1"))
        if el.tag == "Boolean" and vr == enable_vr:
            enable_tunable = el.get("variability") == "tunable"
        if el.tag != "Float64":
            continue
        derivative = el.get("derivative")
        variables[vr] = Variable(el.get("name", ""), vr, el.get("causality", "local"),
                                 el.get("variability", "continuous"), _float(el.get("start")),
                                 _float(el.get("nominal")),
                                 None if derivative is None else int(derivative))
    ode = _unknowns(md.find("ModelStructure"))
    dae = _unknowns(manifest.find("ModelStructure"))
    derivatives = tuple(u.vr for u in ode.get("ContinuousStateDerivative", ()))
    states = tuple(variables[d].derivative for d in derivatives)  # type: ignore[misc]
    return SceneLayout(
        identifier=md.find("ModelExchange").get("modelIdentifier", ""),  # type: ignore
        token=md.get("instantiationToken", ""), variables=variables, enable_vr=enable_vr,
        enable_tunable=enable_tunable, states=states, derivatives=derivatives,  # type: ignore
        algebraic=tuple(int(a.get("valueReference", "-1"))
                        for a in manifest.iter("AlgebraicVariable")),
        residuals=tuple(u.vr for u in dae.get("Residual", ())),
        inputs=tuple(v.vr for v in variables.values() if v.causality == "input"),
        outputs=tuple(u.vr for u in ode.get("Output", ())),
        indicators=tuple(u.vr for u in ode.get("EventIndicator", ())), ode=ode, dae=dae)


def clean(value: float) -> Value:
    """A float as JSON keeps it: non-finite values as strings."""
    return value if math.isfinite(value) else repr(value)


class Session:
    """One instance of the FMU, driven through fmpy; failures raise :class:`Failure`."""

    def __init__(self, unzipped: Path, layout: SceneLayout, name: str = "oracle"):
        self.layout = layout
        self.model = FMU3Model(guid=layout.token, unzipDirectory=str(unzipped),
                               modelIdentifier=layout.identifier, instanceName=name)
        self.call("instantiate", self.model.instantiate,
                  logMessage=lambda env, status, category, message: None)

    @staticmethod
    def call(label: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except Exception as exc:  # fmpy's FMICallException, or a ctypes error
            raise Failure(f"{label}: {exc}") from exc

    def configure_dae(self) -> None:
        self.call("fmi3EnterConfigurationMode", self.model.enterConfigurationMode)
        self.call("fmi3SetBoolean", self.model.setBoolean, [self.layout.enable_vr], [True])
        self.call("fmi3ExitConfigurationMode", self.model.exitConfigurationMode)

    def read(self, vrs: Sequence[int]) -> list[Value]:
        """Each variable read on its own, so one refusal does not hide the others."""
        out: list[Value] = []
        for vr in vrs:
            try:
                out.append(clean(self.call("fmi3GetFloat64", self.model.getFloat64, [vr])[0]))
            except Failure as exc:
                out.append(f"error: {exc}")
        return out

    def enable(self) -> Value:
        try:
            return bool(self.call("fmi3GetBoolean", self.model.getBoolean,
                                  [self.layout.enable_vr])[0])
        except Failure as exc:
            return f"error: {exc}"

    def vector(self, name: str, n: int, fill: float = -7.0) -> list[Value] | str:
        """fmi3GetContinuousStates, ...Derivatives, ...Nominals or fmi3GetEventIndicators,
        into a buffer that holds ``fill`` before the call."""
        buffer = (ctypes.c_double * max(n, 1))(*([fill] * max(n, 1)))
        fn = {"states": self.model.getContinuousStates,
              "derivatives": self.model.getContinuousStateDerivatives,
              "nominals": self.model.getNominalsOfContinuousStates,
              "indicators": self.model.getEventIndicators}[name]
        try:
            self.call(name, fn, buffer, n)
        except Failure as exc:
            return f"error: {exc}"
        return [clean(v) for v in buffer[:n]]

    def set_point(self, t: float | None, states: Sequence[float], inputs: Sequence[float],
                  algebraic: Sequence[float] | None, *, by_value: bool = False) -> None:
        """In Continuous-Time Mode: time, states (fmi3SetContinuousStates, or fmi3SetFloat64
        when ``by_value``), inputs, and w."""
        lay = self.layout
        if t is not None:
            self.call("fmi3SetTime", self.model.setTime, t)
        if lay.states and by_value:
            self.call("fmi3SetFloat64 (states)", self.model.setFloat64, list(lay.states),
                      list(states))
        elif lay.states:
            self.call("fmi3SetContinuousStates", self.model.setContinuousStates,
                      (ctypes.c_double * len(states))(*states), len(states))
        if lay.inputs:
            self.call("fmi3SetFloat64 (inputs)", self.model.setFloat64, list(lay.inputs),
                      list(inputs))
        if algebraic is not None and lay.algebraic:
            self.call("fmi3SetFloat64 (w)", self.model.setFloat64, list(lay.algebraic),
                      list(algebraic))

    def update_discrete_states(self, preset: bool) -> list[Value]:
        """fmi3UpdateDiscreteStates with its output arguments holding ``preset`` (and
        nextEventTime -1 or 1e300) before the call: an FMU must write every one of them."""
        flags = [ctypes.c_bool(preset) for _ in range(5)]
        when = ctypes.c_double(1e300 if preset else -1.0)
        self.call("fmi3UpdateDiscreteStates", self.model.fmi3UpdateDiscreteStates,
                  self.model.component, *map(ctypes.byref, flags), ctypes.byref(when))
        return [bool(f.value) for f in flags] + [clean(when.value)]

    def jacobian(self, unknowns: Sequence[int], knowns: Sequence[int],
                 adjoint: bool = False) -> list[list[Value]] | str:
        """The full matrix d(unknowns)/d(knowns) from unit seeds; rows are unknowns."""
        rows: list[list[Value]] = [[0.0] * len(knowns) for _ in unknowns]
        try:
            if adjoint:
                for i in range(len(unknowns)):
                    seed = [1.0 if k == i else 0.0 for k in range(len(unknowns))]
                    col = self.call("fmi3GetAdjointDerivative", self.model.getAdjointDerivative,
                                    list(unknowns), list(knowns), seed, len(knowns))
                    rows[i] = [clean(v) for v in col]
            else:
                for j in range(len(knowns)):
                    seed = [1.0 if k == j else 0.0 for k in range(len(knowns))]
                    col = self.call("fmi3GetDirectionalDerivative",
                                    self.model.getDirectionalDerivative, list(unknowns),
                                    list(knowns), seed)
                    for i, v in enumerate(col):
                        rows[i][j] = clean(v)
        except Failure as exc:
            return f"error: {exc}"
        return rows

    def status(self, label: str, fn: Callable[..., Any], *args: Any) -> str:
        """"ok" or the failure of a call whose result does not matter (an illegal call)."""
        try:
            self.call(label, fn, *args)
            return "ok"
        except Failure as exc:
            return f"refused: {exc}"

    def free(self) -> None:
        try:
            self.model.freeInstance()
        except Exception:  # a mutant may fail here too; the observation is already taken
            pass


def illegal_calls(fresh: Callable[[], Session], mode: str) -> dict[str, str]:
    """Calls FMI 3.0 does not allow, each on a fresh instance in Continuous-Time Mode (after an
    fmi3Error only Terminated is left), and their outcome: an unknown value reference, setting
    a derivative or an output, setting w in ODE mode (DAE-43), an event indicator or an output
    as the known of a directional derivative (PD-04, PD-05), a seed shorter than the knowns
    (PD-01)."""
    probe = fresh()
    lay = probe.layout
    probe.free()
    first = [*lay.derivatives, *lay.outputs][:1]
    vrs, floats = ctypes.c_uint32 * 4, ctypes.c_double * 4
    n = min(2, len(lay.states))
    calls: dict[str, Callable[[Session], Any]] = {
        "get unknown vr": lambda s: s.model.getFloat64([max(lay.variables) + 100]),
        "set a derivative": lambda s: s.model.setFloat64(list(lay.derivatives[:1]),
                                                         [0.5] * len(lay.derivatives[:1]))}
    if lay.outputs:
        calls["set an output"] = lambda s: s.model.setFloat64([lay.outputs[0]], [0.5])
    if mode == "ode" and lay.algebraic:
        calls["set w in ODE mode"] = lambda s: s.model.setFloat64([lay.algebraic[0]], [0.5])
    for label, known in (("indicator as known", lay.indicators[:1]),
                         ("output as known", lay.outputs[:1])):
        if known and first:
            calls[label] = lambda s, k=known: s.model.getDirectionalDerivative(first, list(k),
                                                                               [1.0])
    if first and n:
        calls["seed shorter than the knowns"] = lambda s: s.model.fmi3GetDirectionalDerivative(
            s.model.component, vrs(*first), 1, vrs(*lay.states[:n]), n, floats(1.0), n - 1,
            floats(), 1)
    out = {}
    for label, call in calls.items():
        s = fresh()
        out[label] = s.status(label, call, s)
        s.free()
    return out


def fixed_points(layout: SceneLayout, count: int = 2) -> list[dict[str, Any]]:
    """``count`` points derived from the XML only (so the same for every mutant): states and
    inputs moved from their start values by 2 k % (relative, or of the nominal at 0), the
    algebraic variables likewise from their start (guess) values, and times 0.15 and 0.7
    (either side of the 0.5 of the late defects, within the default stop time)."""
    def moved(vr: int, k: int, i: int) -> float:
        var = layout.variables[vr]
        start = var.start or 0.0
        sign = 1.0 if i % 2 == 0 else -1.0
        if start != 0.0:
            return start * (1.0 + 0.02 * k * sign)
        return 0.02 * k * sign * (var.nominal or 1.0) * (5.0 if var.causality == "input" else 1.0)

    times = [0.15, 0.7, 0.35, 0.9]
    return [{"t": times[(k - 1) % len(times)],
             "x": [moved(vr, k, i) for i, vr in enumerate(layout.states)],
             "u": [moved(vr, k, i) for i, vr in enumerate(layout.inputs)],
             "w": [moved(vr, k, i) for i, vr in enumerate(layout.algebraic)]}
            for k in range(1, count + 1)]
