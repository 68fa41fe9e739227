"""fmi3UpdateDiscreteStates through the runtime: its flags and nextEventTime, the update that
ends initialisation kept on the instance (EventDAE announces its time event at 0.75, SimpleDAE
none), and one update at a time in Event Mode."""
from __future__ import annotations

import pytest

from conformance.runtime.modes import start_instance
from tests.runtime.test_event_indicators import _library


@pytest.mark.parametrize("mode", ["dae", "ode"])
def test_the_initial_update_announces_the_time_event(tmp_path, mode):
    library = _library("EventDAE", tmp_path)
    try:
        inst = start_instance(library, mode)
        assert inst.discrete is not None
        assert inst.discrete.next_time == 0.75 and not inst.discrete.terminate
        assert inst.discrete.calls == 1 and not inst.discrete.needs_update
    finally:
        library.free_all()


def test_one_update_at_a_time_in_event_mode(tmp_path):
    library = _library("EventDAE", tmp_path)
    try:
        inst = start_instance(library, "ode")
        inst.set_time(0.75)
        inst.enter_event_mode()
        first = inst.update_discrete_states_once()
        assert first.needs_update and first.next_time is None   # b changed: iterate
        second = inst.update_discrete_states_once()
        assert not second.needs_update and not second.values_changed
        inst.enter_continuous_time_mode()
        assert inst.get_float64([8])[0] == 0.5
    finally:
        library.free_all()


def test_a_model_without_events_has_no_next_time(tmp_path):
    library = _library("SimpleDAE", tmp_path)
    try:
        inst = start_instance(library, "dae")
        assert inst.discrete is not None and inst.discrete.next_time is None
        assert inst.discrete.calls == 1
    finally:
        library.free_all()
