"""Bringing an instance into Continuous-Time Mode in DAE mode or ODE mode (the enable handshake)."""
from __future__ import annotations

from .errors import FmiError, Unavailable
from .instance import Instance
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


def start_instance(library: Library, mode: str, *, runtime_switch: bool = True) -> Instance:
    """A new instance in Continuous-Time Mode, in ``mode`` ("dae" or "ode").

    DAE mode: Configuration Mode with the switch set true, then the ordinary initialisation
    (DAE-12). An FMU without an enable parameter is permanently in DAE mode and is initialised
    without Configuration Mode. Under alpha.1 an FMU may refuse to initialise in DAE mode
    (DAE-14); then, when the switch is tunable and ``runtime_switch`` is true, the instance is
    initialised in ODE mode and switched in Reconfiguration Mode (DAE-13).
    """
    layout = library.layout
    if mode == "ode" and layout.enable_status != "ok":
        raise Unavailable("the FMU has no usable enable parameter, hence no ODE mode"
                           if layout.enable_status == "unusable" else
                           "the FMU has no enable parameter: it is permanently in DAE mode")
    if mode == "dae" and layout.enable_status == "unusable":
        raise Unavailable("the enable parameter cannot be used (see the static findings)")
    inst = Instance(library, name=library.next_name(mode))
    try:
        if mode == "dae" and layout.enable is not None:
            configure(inst, True)
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
            inst.enter_initialization_mode(layout.start_time)
            inst.exit_initialization_mode()
            reconfigure(inst, True)
            inst.started = "runtime-switch"
        inst.discrete = inst.update_discrete_states()
        inst.enter_continuous_time_mode()
    except BaseException:
        try:
            inst.free()
        except FmiError:
            pass
        raise
    inst.mode = mode
    return inst
