"""Bringing an instance into Continuous-Time Mode in DAE mode or ODE mode (the enable handshake),
or into Initialization Mode with given start values."""
from __future__ import annotations

from collections.abc import Mapping

from .errors import FmiError, Unavailable
from .instance import Instance
from .layout import Layout
from .library import Library

INIT_CALLS = ("fmi3EnterInitializationMode", "fmi3ExitInitializationMode")


def configure(inst: Instance, value: bool) -> None:
    """Configuration Mode: set the enable parameter (Instantiated -> Instantiated)."""
    vr = inst.layout.enable
    assert vr is not None
    inst.enter_configuration_mode()
    inst.set_boolean(vr, value)
    inst.exit_configuration_mode()


def reconfigure(inst: Instance, value: bool) -> None:
    """Reconfiguration Mode: set the enable parameter (Event Mode -> Event Mode)."""
    configure(inst, value)


def _free_quietly(inst: Instance) -> None:
    """Free an instance that failed on its way to the mode asked for; the first error stands."""
    try:
        inst.free()
    except FmiError:
        pass


def _check_mode(layout: Layout, mode: str) -> None:
    if mode == "dae" and layout.enable_status == "no-layer":
        raise Unavailable("no fmi-ls-dae manifest was read: only ODE mode can be probed")
    if mode == "ode" and layout.enable_status not in ("ok", "no-layer"):
        raise Unavailable("the FMU has no usable enable parameter, hence no ODE mode"
                           if layout.enable_status == "unusable" else
                           "the FMU has no enable parameter: it is permanently in DAE mode")
    if mode == "dae" and layout.enable_status == "unusable":
        raise Unavailable("the enable parameter cannot be used (see the static findings)")


def start_initialization(library: Library, mode: str, values: Mapping[int, float],
                         start_time: float) -> Instance:
    """A new instance in Initialization Mode, in ``mode`` ("dae" or "ode"), whose Float64
    ``values`` (value reference -> value) were set in Instantiated, as start values (SG-01),
    and whose fmi3EnterInitializationMode was given ``start_time``.

    The caller reads it in Initialization Mode and frees it (:meth:`Instance.free` calls no
    fmi3Terminate there). An FmiError names the call that failed: fmi3SetFloat64 when the FMU
    rejects a start value, fmi3EnterInitializationMode when it refuses to initialise (in DAE
    mode alpha.1 allows that, DAE-14). No runtime switch: the instance is initialised in
    ``mode`` or not at all.
    """
    _check_mode(library.layout, mode)
    inst = Instance(library, name=library.next_initialization_name(mode))
    try:
        if mode == "dae" and library.layout.enable is not None:
            configure(inst, True)
        vrs = list(values)
        inst.set_float64(vrs, [float(values[vr]) for vr in vrs])
        inst.enter_initialization_mode(start_time)
    except BaseException:
        _free_quietly(inst)
        raise
    inst.mode = mode
    return inst


def start_instance(library: Library, mode: str, *, runtime_switch: bool = True,
                   start_values: Mapping[int, float] | None = None) -> Instance:
    """A new instance in Continuous-Time Mode, in ``mode`` ("dae" or "ode"); ``start_values``
    (Float64 value reference -> value) are set in Instantiated, before the initialisation.

    DAE mode: Configuration Mode with the switch set true, then the ordinary initialisation
    (DAE-12). An FMU without an enable parameter is permanently in DAE mode and is initialised
    without Configuration Mode. Under alpha.1 an FMU may refuse to initialise in DAE mode
    (DAE-14); then, when the switch is tunable and ``runtime_switch`` is true, the instance is
    initialised in ODE mode and switched in Reconfiguration Mode (DAE-13).
    """
    layout = library.layout
    _check_mode(layout, mode)
    inst = Instance(library, name=library.next_name(mode))
    given = list(start_values or {})
    try:
        if mode == "dae" and layout.enable is not None:
            configure(inst, True)
        inst.set_float64(given, [float(start_values[vr]) for vr in given])  # type: ignore
        try:
            inst.enter_initialization_mode(layout.start_time)
            inst.exit_initialization_mode()
            inst.started = "configuration"
        except FmiError as exc:
            if not (mode == "dae" and runtime_switch and layout.enable_tunable
                    and exc.call in INIT_CALLS):
                raise
            inst.free()
            inst = Instance(library, name=library.next_name(mode))
            inst.set_float64(given, [float(start_values[vr]) for vr in given])  # type: ignore
            inst.enter_initialization_mode(layout.start_time)
            inst.exit_initialization_mode()
            reconfigure(inst, True)
            inst.started = "runtime-switch"
        inst.discrete = inst.update_discrete_states()
        inst.enter_continuous_time_mode()
    except BaseException:
        _free_quietly(inst)
        raise
    inst.mode = mode
    return inst
