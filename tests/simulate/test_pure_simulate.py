"""The parts of conformance/simulate that decide from values already computed, without a binary:
whether the FMU's directional derivatives are used (jacobian_check), the worst residual along a
DAE run (integrate.residual_along) and the CSV of a trajectory (output).

A fake system stands for FmuDae: a linear residual ``A @ y`` evaluated exactly, and directional
derivatives ``B @ seed`` through the real coloured Jacobian of conformance/simulate/system.py
(``B`` = ``A``: confirmed; ``B`` off in chosen entries: refuted there).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
import pytest

from conformance.numerics.limits import EvaluationFailed
from conformance.numerics.settings import Trajectory
from conformance.runtime.errors import FmiError
from conformance.simulate import integrate, output
from conformance.simulate.jacobian_check import DerivativeCheck, choose_jacobian, refuted_at
from conformance.simulate.system import DIRECTIONAL, FINITE_DIFFERENCES, _Coloured, pattern_from

NAMES = {1: "x1", 2: "x2", 3: "w", 11: "r1", 12: "r2", 13: "r3"}
COLS, ROWS = [1, 2, 3], [11, 12, 13]
A = np.array([[2.0, 0.0, 1.0],
              [0.0, -3.0, 0.0],
              [1.0, 0.0, 4.0]])
CHECK = DerivativeCheck(rtol=1e-6, margin=10.0, ulps=64.0)


class _Layout:
    def __init__(self, scales: dict[int, float] | None = None):
        self.scales = scales or {}
        self.residuals = list(ROWS)
        self.states = [1, 2]
        self.algebraic = [3]

    def name(self, vr: int) -> str:
        return NAMES[vr]

    def scale(self, vr: int) -> float:
        return self.scales.get(vr, 1.0)


class _Inst:
    """Directional derivatives B @ seed (or an FmiError); holds ``held`` for get_float64."""

    def __init__(self, b: np.ndarray, held: list[float], error: FmiError | None = None):
        self.b, self.held, self.error = b, held, error
        self.gets: list[list[int]] = []

    def directional_as_set(self, rows, cols, seed):
        if self.error is not None:
            raise self.error
        return self.b @ np.asarray(seed, dtype=float)

    def get_float64(self, vrs):
        self.gets.append(list(vrs))
        return list(self.held)


class _System:
    def __init__(self, b: np.ndarray, *, held=(1.0, 2.0, 3.0), use_directional=True,
                 error: FmiError | None = None, fail_at: int | None = None, scales=None,
                 a: np.ndarray = A, nominal=(1.0, 1.0, 1.0)):
        self.inst = _Inst(b, list(held), error)
        self.layout = _Layout(scales)
        self.a = a
        pattern = pattern_from([None, None, None], COLS)
        self.jac = _Coloured(self.inst, ROWS, COLS, pattern, np.array(nominal, dtype=float),
                             use_directional)
        self.jacobian_source = self.jac.source
        self.calls: list[tuple[float, np.ndarray]] = []
        self.fail_at = fail_at

    def evaluate(self, t, y):
        self.calls.append((t, np.array(y, dtype=float)))
        if self.fail_at is not None and len(self.calls) >= self.fail_at:
            raise EvaluationFailed("fmi3GetFloat64", "fmi3Discard", "", recoverable=True)
        return self.a @ np.asarray(y, dtype=float)


def _off(i: int, j: int, by: float) -> np.ndarray:
    b = A.copy()
    b[i, j] += by
    return b


# ------------------------------------------------------------------------ refuted_at

def test_confirmed_derivatives_refute_nothing():
    system = _System(A.copy())
    assert refuted_at(system, 0.5, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=10.0,
                      ulps=64.0) == ""
    assert all(t == 0.5 for t, _ in system.calls)   # the differences are taken at t


def test_one_wrong_entry_is_named_with_both_values():
    system = _System(_off(0, 2, 0.5))   # d(r1)/d(w): 1.5 against 1
    note = refuted_at(system, 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=10.0,
                      ulps=64.0)
    assert note == ("the FMU's directional derivatives were not used: finite differences "
                    "refute 1 of their entries at the initial point, worst d(r1)/d(w) "
                    "(1.5 against 1)")


def test_the_worst_of_several_wrong_entries_is_named_and_all_are_counted():
    b = _off(1, 1, 0.01)          # d(r2)/d(x2): -2.99 against -3, a small miss
    b[2, 0] += 2.0                # d(r3)/d(x1): 3 against 1, the worst
    b[0, 1] += 0.5                # d(r1)/d(x2): 0.5 against 0 (undeclared zero: dense here)
    note = refuted_at(_System(b), 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=10.0,
                      ulps=64.0)
    assert note == ("the FMU's directional derivatives were not used: finite differences "
                    "refute 3 of their entries at the initial point, worst d(r3)/d(x1) "
                    "(3 against 1)")


def test_the_worst_entry_is_the_one_furthest_beyond_its_tolerance_not_the_largest_miss():
    # rows scaled apart: row r3's entries are large, so the same miss is within its tolerance
    # by rtol; row r1's small miss relative to its scale is the worst
    b = A.copy()
    b[0, 0] += 1e-3               # r1: scale 3 (|2|+|1|), miss 1e-3
    b[2, 2] += 1.2e-3             # r3: scale 5, miss 1.2e-3 (larger, but relatively smaller)
    note = refuted_at(_System(b), 0.0, np.array([1.0, 2.0, 3.0]), rtol=2e-4, margin=10.0,
                      ulps=64.0)
    assert note.endswith("refute 2 of their entries at the initial point, worst d(r1)/d(x1) "
                         "(2.001 against 2)")


def test_a_miss_within_rtol_of_the_row_scale_is_no_refutation():
    # r3's scale is |1| + |4| = 5: a miss of 4e-6 is within rtol 1e-6 * 5 / 1 = 5e-6 ...
    system = _System(_off(2, 2, 4e-6))
    assert refuted_at(system, 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=0.0,
                      ulps=0.0) == ""
    # ... and a miss of 6e-6 is not
    note = refuted_at(_System(_off(2, 2, 6e-6)), 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6,
                      margin=0.0, ulps=0.0)
    assert "refute 1 of their entries" in note and "worst d(r3)/d(w)" in note


def test_a_miss_exactly_at_the_tolerance_is_no_refutation():
    # at y = 0 the central differences of 2 * x1 are exactly 2; row r1's scale is |2| + |1|
    # = 3, so rtol 0.5 gives a tolerance of exactly 1.5: a miss of exactly 1.5 is within it
    y = np.zeros(3)
    assert refuted_at(_System(_off(0, 0, 1.5)), 0.0, y, rtol=0.5, margin=0.0, ulps=0.0) == ""
    assert "worst d(r1)/d(x1) (3.5625 against 2)" in refuted_at(
        _System(_off(0, 0, 1.5625)), 0.0, y, rtol=0.5, margin=0.0, ulps=0.0)


def test_the_steps_follow_the_values_so_the_rounding_tolerance_does():
    # large values: the step is relative to |y| (6e-3 at y = 1000), and the rounding error
    # estimate (margin * ulps * eps * |f| / h) stays far below a miss of 1e-5; a step taken
    # from the nominal alone (6e-6) would swallow the miss in a thousand times that estimate
    y = np.array([1000.0, 2000.0, 3000.0])
    note = refuted_at(_System(_off(0, 0, 1e-5)), 0.0, y, rtol=1e-12, margin=10.0, ulps=64.0)
    assert "refute 1 of their entries" in note and "worst d(r1)/d(x1)" in note


def test_the_steps_follow_the_nominal_values_where_the_values_are_small():
    # small values: the step is relative to each known's nominal (1000 here, a step of 6e-3,
    # a rounding estimate near 2e-10); with steps of 6e-6 the estimate (2e-7) would swallow
    # a miss of 1e-8
    note = refuted_at(_System(_off(0, 0, 1e-8), nominal=(1000.0, 1000.0, 1000.0)), 0.0,
                      np.array([1.0, 2.0, 3.0]), rtol=1e-12, margin=10.0, ulps=64.0)
    assert "refute 1 of their entries" in note and "worst d(r1)/d(x1)" in note


def test_a_residual_that_moves_with_nothing_is_judged_on_its_nominal_floor():
    # row r2 depends on nothing (its finite differences are all zero: an underflowing row);
    # the FMU's 1e-3 there is under the floor ulps * eps * nominal / h of a residual whose
    # nominal is 1e6 (about 2.3), not of one whose nominal is 1 (about 2.3e-6)
    a = A.copy()
    a[1, :] = 0.0
    b = a.copy()
    b[1, 1] = 1e-3
    y = np.array([1.0, 2.0, 3.0])
    assert refuted_at(_System(b, a=a, scales={12: 1e6}), 0.0, y, rtol=1e-6, margin=10.0,
                      ulps=64.0) == ""
    assert refuted_at(_System(b, a=a), 0.0, y, rtol=1e-6, margin=10.0, ulps=64.0).endswith(
        "refute 1 of their entries at the initial point, worst d(r2)/d(x2) (0.001 against 0)")


def test_the_check_takes_central_differences_and_no_random_direction():
    # one evaluation at the point, four per colour group (central differences at h and 2h
    # for their truncation estimate), and the point set again before each directional-
    # derivative call: 1 + 4 * 3 + 3 = 16; random directions would add evaluations
    system = _System(A.copy())
    refuted_at(system, 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=10.0, ulps=64.0)
    assert len(system.calls) == 16
    assert sum(1 for _, y in system.calls if np.array_equal(y, [1.0, 2.0, 3.0])) == 4


def test_a_failing_directional_call_refutes_them_with_the_call_and_status():
    error = FmiError("fmi3GetDirectionalDerivative", "fmi3Error")
    note = refuted_at(_System(A.copy(), error=error), 0.0, np.array([1.0, 2.0, 3.0]),
                      rtol=1e-6, margin=10.0, ulps=64.0)
    assert note == ("the FMU's directional derivatives were not used: "
                    "fmi3GetDirectionalDerivative returned fmi3Error at the initial point")


def test_a_point_that_cannot_be_evaluated_decides_nothing():
    system = _System(_off(0, 0, 1.0), fail_at=2)
    assert refuted_at(system, 0.0, np.array([1.0, 2.0, 3.0]), rtol=1e-6, margin=10.0,
                      ulps=64.0) == ""


# ------------------------------------------------------------------------ choose_jacobian

def test_no_check_keeps_the_fmus_derivatives_unchecked():
    system = _System(_off(0, 0, 1.0))
    assert choose_jacobian(system, 0.0, None) is system
    assert system.jac.use_directional and system.jacobian_source == DIRECTIONAL
    assert system.calls == [] and system.inst.gets == []


def test_finite_differences_already_are_not_checked():
    system = _System(_off(0, 0, 1.0), use_directional=False)
    assert choose_jacobian(system, 0.0, CHECK) is system
    assert system.jacobian_source == FINITE_DIFFERENCES and system.calls == []


def test_the_probes_verdict_is_taken_as_it_is():
    system = _System(A.copy())
    verdict = "refuted by directional-derivative-mismatch"
    chosen = choose_jacobian(system, 0.0, DerivativeCheck(1e-6, 10.0, 64.0, verdict=verdict))
    assert chosen is system and not system.jac.use_directional
    assert system.jacobian_source == f"{FINITE_DIFFERENCES} ({verdict})"
    assert system.calls == []   # nothing checked again


def test_the_probes_confirmation_is_taken_as_it_is():
    system = _System(_off(0, 0, 1.0))
    choose_jacobian(system, 0.0, DerivativeCheck(1e-6, 10.0, 64.0, verdict=""))
    assert system.jac.use_directional and system.jacobian_source == DIRECTIONAL
    assert system.calls == []


def test_without_a_verdict_the_initial_point_the_instance_holds_is_checked():
    system = _System(_off(0, 2, 0.5), held=(1.0, 2.0, 3.0))
    choose_jacobian(system, 0.25, CHECK)
    assert system.inst.gets == [COLS]
    assert system.calls and all(t == 0.25 for t, _ in system.calls)
    assert system.calls[0][1] == pytest.approx([1.0, 2.0, 3.0], rel=1e-6)
    assert not system.jac.use_directional
    assert system.jacobian_source == (
        f"{FINITE_DIFFERENCES} (the FMU's directional derivatives were not used: finite "
        "differences refute 1 of their entries at the initial point, worst d(r1)/d(w) "
        "(1.5 against 1))")


def test_confirmed_at_the_initial_point_keeps_the_fmus_derivatives():
    system = _System(A.copy())
    choose_jacobian(system, 0.0, CHECK)
    assert system.jac.use_directional and system.jacobian_source == DIRECTIONAL


# ------------------------------------------------------------------------ residual_along

@dataclass
class _RunInst:
    """Residuals r_k = sum of what was set, times (k + 1); an FmiError after ``fail_after``
    reads."""
    fail_after: int | None = None
    set_log: list = field(default_factory=list)
    reads: int = 0
    now: dict = field(default_factory=dict)

    def set_time(self, t):
        self.set_log.append(("time", t))
        self.now["t"] = t

    def set_states(self, values):
        self.set_log.append(("states", list(values)))
        self.now["x"] = list(values)

    def set_float64(self, vrs, values):
        self.set_log.append(("float64", list(vrs), list(values)))
        self.now["w"] = list(values)

    def get_float64(self, vrs):
        self.reads += 1
        if self.fail_after is not None and self.reads > self.fail_after:
            raise FmiError("fmi3GetFloat64", "fmi3Error")
        s = self.now["t"] + sum(self.now["x"]) + sum(self.now["w"])
        return [s * (k + 1) for k in range(len(vrs))]


def _traj(times, rows, names=("x1", "x2", "w")) -> Trajectory:
    return Trajectory("dae", list(names), ["state", "state", "algebraic"], list(times),
                      np.array(rows, dtype=float))


def test_residual_along_is_the_largest_residual_its_name_and_time():
    inst = _RunInst()
    traj = _traj([0.0, 1.0, 2.0], [[1.0, 0.0, 0.0], [0.0, 0.0, 3.0], [0.0, -1.0, 0.0]])
    worst = integrate.residual_along(inst, _Layout(), traj)
    # sums 1, 4, 1: r3 = 3 * sum is the largest, at t = 1
    assert worst == {"max_abs": 12.0, "residual": "r3", "t": 1.0}
    assert inst.set_log[:3] == [("time", 0.0), ("states", [1.0, 0.0]), ("float64", [3], [0.0])]


def test_residual_along_takes_the_absolute_value_and_keeps_the_first_of_equal_ones():
    inst = _RunInst()
    traj = _traj([0.0, 1.0, 2.0], [[-5.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 4.0]])
    # sums -5, 0, 6: |3 * -5| = 15 at t = 0 is above 3 * 6 = 18? no: 18 at t = 2 wins
    assert integrate.residual_along(inst, _Layout(), traj) == {
        "max_abs": 18.0, "residual": "r3", "t": 2.0}
    traj = _traj([0.0, 1.0], [[-4.0, 0.0, 0.0], [0.0, 3.0, 0.0]])   # sums -4 and 4: a tie
    assert integrate.residual_along(_RunInst(), _Layout(), traj) == {
        "max_abs": 12.0, "residual": "r3", "t": 0.0}


def test_residual_along_skips_rows_with_values_not_read():
    inst = _RunInst()
    traj = _traj([0.0, 1.0], [[100.0, np.nan, 0.0], [1.0, 0.0, 0.0]])
    assert integrate.residual_along(inst, _Layout(), traj) == {
        "max_abs": 6.0, "residual": "r3", "t": 1.0}
    assert ("time", 0.0) not in inst.set_log


def test_residual_along_keeps_what_it_had_when_the_fmu_fails():
    traj = _traj([0.0, 1.0, 2.0], [[1.0, 0.0, 0.0], [9.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert integrate.residual_along(_RunInst(fail_after=1), _Layout(), traj) == {
        "max_abs": 3.0, "residual": "r3", "t": 0.0}
    assert integrate.residual_along(_RunInst(fail_after=0), _Layout(), traj) == {}


def test_residual_along_needs_residuals_every_variable_and_times():
    traj = _traj([0.0], [[1.0, 0.0, 0.0]])
    layout = _Layout()
    layout.residuals = []
    assert integrate.residual_along(_RunInst(), layout, traj) == {}
    missing_state = _traj([0.0], [[1.0, 0.0, 0.0]], names=("x1", "y", "w"))
    assert integrate.residual_along(_RunInst(), _Layout(), missing_state) == {}
    missing_alg = _traj([0.0], [[1.0, 0.0, 0.0]], names=("x1", "x2", "v"))
    assert integrate.residual_along(_RunInst(), _Layout(), missing_alg) == {}
    assert integrate.residual_along(_RunInst(), _Layout(), _traj([], np.zeros((0, 3)))) == {}


def test_residual_along_without_states_sets_only_the_algebraic_variables():
    layout = _Layout()
    layout.states = []
    inst = _RunInst()
    inst.now["x"] = []
    traj = Trajectory("dae", ["w"], ["algebraic"], [0.5], np.array([[2.0]]))
    assert integrate.residual_along(inst, layout, traj) == {
        "max_abs": 7.5, "residual": "r3", "t": 0.5}
    assert [entry[0] for entry in inst.set_log] == ["time", "float64"]


# ------------------------------------------------------------------------ output

def test_csv_has_a_time_column_then_the_names_and_exact_values():
    traj = Trajectory("dae", ["x", "a,b"], ["state", "algebraic"], [0.0, 0.1],
                      np.array([[1.0, 1 / 3], [np.nan, np.inf]]))
    assert output.to_csv(traj) == ('time,x,"a,b"\n'
                                   "0.0,1.0,0.3333333333333333\n"
                                   "0.1,,\n")


def test_csv_of_integers_and_negative_values_round_trips():
    traj = Trajectory("ode", ["x"], ["state"], [1], np.array([[-2.5e-300]]))
    assert output.to_csv(traj) == "time,x\n1.0,-2.5e-300\n"
    assert output._number(-np.inf) == "" and output._number(np.float32(0.5)) == "0.5"


def test_write_csv_writes_utf8_into_an_existing_folder_whatever_the_locale(tmp_path,
                                                                          monkeypatch):
    import io

    real = io.text_encoding
    # a locale whose encoding cannot write the names: only an explicit encoding gets through
    monkeypatch.setattr(io, "text_encoding",
                        lambda encoding, *a: real(encoding, *a) if encoding else "ascii")
    traj = Trajectory("dae", ["Δp", "µ"], ["state", "algebraic"], [0.0], np.array([[1.0, 2.0]]))
    path = tmp_path / "out.csv"
    output.write_csv(traj, path)
    assert path.read_bytes().decode("utf-8") == "time,Δp,µ\n0.0,1.0,2.0\n"
    output.write_csv(traj, path)   # the folder exists, the file too: written again
    assert path.read_bytes().decode("utf-8") == "time,Δp,µ\n0.0,1.0,2.0\n"


def test_write_csv_makes_the_folder_and_writes_the_text(tmp_path):
    traj = Trajectory("dae", ["x"], ["state"], [0.0], np.array([[1.5]]))
    path = tmp_path / "deep" / "er" / "out.csv"
    output.write_csv(traj, str(path))
    assert path.read_text(encoding="utf-8") == "time,x\n0.0,1.5\n"


# ------------------------------------------------------------------------ simulate_instance

class _Recorded:
    """Stand-ins for the systems, the integrators and choose_jacobian: what each was given."""

    def __init__(self, monkeypatch, *, has_events=False):
        self.log: dict = {}
        self.traj = SimpleNamespace(has_events=has_events, residual_along={})
        log = self.log

        class Dae:
            def __init__(self, inst, layout, manifest, *, dense_up_to):
                log["system"] = ("dae", inst, layout, manifest, dense_up_to)
                self.states, self.algebraic = [1, 2], [3]

        class Ode:
            def __init__(self, inst, layout, model, *, dense_up_to):
                log["system"] = ("ode", inst, layout, model, dense_up_to)
                self.states, self.algebraic = [1, 2], [3, 4]

        def choose(system, t0, check):
            log["choose"] = (system, t0, check)
            return system

        def integrate_dae(system, settings, *, t0, y0, stop, start_update):
            log["integrate"] = dict(system=system, settings=settings, t0=t0, y0=y0, stop=stop,
                                    start_update=start_update)
            return self.traj

        def integrate_ode(system, settings, *, t0, x0, stop, algebraic_nominal=None,
                          start_update=None):
            log["integrate"] = dict(system=system, settings=settings, t0=t0, x0=x0, stop=stop,
                                    algebraic_nominal=algebraic_nominal,
                                    start_update=start_update)
            return self.traj

        def along(inst, layout, traj):
            log["along"] = (inst, layout, traj)
            return {"max_abs": 1.0}

        for name, value in (("FmuDae", Dae), ("FmuOde", Ode), ("choose_jacobian", choose),
                            ("integrate_dae", integrate_dae), ("integrate_ode", integrate_ode),
                            ("residual_along", along)):
            monkeypatch.setattr(integrate, name, value)


def _inst(mode: str, failure=None):
    inst = SimpleNamespace(mode=mode, discrete=object(), failure=failure, gets=[])

    def get_float64(vrs):
        inst.gets.append(list(vrs))
        return [float(v) * 10 for v in vrs]
    inst.get_float64 = get_float64
    return inst


SETTINGS = SimpleNamespace(dense_up_to=7)


def test_simulate_instance_in_dae_mode_hands_everything_on(monkeypatch):
    rec = _Recorded(monkeypatch)
    inst, layout, model, manifest = _inst("dae"), _Layout(), object(), object()
    check = DerivativeCheck(1e-6, 10.0, 64.0)
    traj = integrate.simulate_instance(inst, layout, SETTINGS, start=0.5, stop=2.0, model=model,
                                       manifest=manifest, derivatives=check)
    assert traj is rec.traj
    kind, got_inst, got_layout, got_manifest, dense = rec.log["system"]
    assert (kind, dense) == ("dae", 7)
    assert got_inst is inst and got_layout is layout and got_manifest is manifest
    system, t0, got_check = rec.log["choose"]
    assert (t0, got_check) == (0.5, check)
    run = rec.log["integrate"]
    assert run["system"] is system and run["settings"] is SETTINGS
    assert (run["t0"], run["stop"], list(run["y0"])) == (0.5, 2.0, [10.0, 20.0, 30.0])
    assert run["start_update"] is inst.discrete
    assert rec.log["along"] == (inst, layout, traj)
    assert traj.residual_along == {"max_abs": 1.0}


@pytest.mark.parametrize("has_events, failure", [(True, None), (False, FmiError("f", "s"))])
def test_residual_along_is_left_out_after_events_or_an_error(monkeypatch, has_events, failure):
    rec = _Recorded(monkeypatch, has_events=has_events)
    traj = integrate.simulate_instance(_inst("dae", failure), _Layout(), SETTINGS, start=0.0,
                                       stop=1.0, model=None, manifest=None)
    assert "along" not in rec.log and traj.residual_along == {}


def test_simulate_instance_in_ode_mode_hands_everything_on(monkeypatch):
    rec = _Recorded(monkeypatch)
    inst, model = _inst("ode"), object()
    layout = _Layout({3: 5.0, 4: 0.25})
    traj = integrate.simulate_instance(inst, layout, SETTINGS, start=0.25, stop=3.0, model=model,
                                       manifest=object())
    assert traj is rec.traj and "along" not in rec.log
    kind, got_inst, got_layout, got_model, dense = rec.log["system"]
    assert (kind, dense) == ("ode", 7)
    assert got_inst is inst and got_layout is layout and got_model is model
    system, t0, check = rec.log["choose"]
    assert (t0, check) == (0.25, None)
    run = rec.log["integrate"]
    assert run["system"] is system and run["settings"] is SETTINGS
    assert (run["t0"], run["stop"], list(run["x0"])) == (0.25, 3.0, [10.0, 20.0])
    assert list(run["algebraic_nominal"]) == [5.0, 0.25]
    assert run["start_update"] is inst.discrete
