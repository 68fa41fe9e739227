"""Pure-Python DAE and ODE systems with exact derivatives, for testing the integrators without
a binary: Robertson, the reduced Van der Pol oscillator, HelloWorldDAE and variants that fail,
and systems with events (a hysteresis relay whose residual jumps, a bouncing ball).

Each follows the protocols of conformance/simulate/dae.py (``DaeSystem``) and ode.py
(``OdeSystem``): ``y = [x; w]``, ``evaluate`` gives ``[f; g]``, ``partials`` d[f; g]/d[x; w].
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from conformance.numerics.limits import EvaluationFailed

# Reference solution of Robertson (tight-tolerance solutions, consistent with the Hairer test set)
ROBERTSON_REFERENCE = {
    0.4: (9.851721139e-1, 3.386395379e-5, 1.479402219e-2),
    40.0: (7.158270687e-1, 9.185534765e-6, 2.841637457e-1),
    4e5: (4.938274521e-3, 1.984994088e-8, 9.950617056e-1),
    4e10: (5.208345181e-8, 2.083338179e-13, 9.999999479e-1),
}
VAN_DER_POL_IMPASSE = 1.5 - np.log(2.0)   # t* where dg/dw = 1 - y1^2 vanishes, from y1 = 2


class Robertson:
    """der(y1), der(y2) kinetics; 0 = y1 + y2 + y3 - 1 (y3 algebraic)."""

    nx, nw = 2, 1
    names = ("y1", "y2", "y3")
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, nominal: tuple[float, float, float] = (1.0, 1e-5, 1.0)):
        self.nominal = np.array(nominal)

    def evaluate(self, t, y):
        y1, y2, y3 = y
        return np.array([-0.04 * y1 + 1e4 * y2 * y3, 0.04 * y1 - 1e4 * y2 * y3 - 3e7 * y2**2,
                         y1 + y2 + y3 - 1])

    def partials(self, t, y):
        _, y2, y3 = y
        return np.array([[-0.04, 1e4 * y3, 1e4 * y2],
                         [0.04, -1e4 * y3 - 6e7 * y2, -1e4 * y2],
                         [1.0, 1.0, 1.0]])


class VanDerPol:
    """der(y1) = y2; 0 = (1 - y1^2) y2 - y1: an impasse point at t* from y1 = 2."""

    nx, nw = 1, 1
    names = ("y1", "y2")
    nominal = np.ones(2)
    jacobian_source = "exact"
    fmi_calls = 0

    def evaluate(self, t, y):
        y1, y2 = y
        return np.array([y2, (1 - y1**2) * y2 - y1])

    def partials(self, t, y):
        y1, y2 = y
        return np.array([[0.0, 1.0], [-2 * y1 * y2 - 1, 1 - y1**2]])


class HelloWorld:
    """der(x) = y; 0 = y + 2z - x; 0 = y - 3z - 2x, with an optional extra on [f; g] and a
    hook that may raise (the failure a variant injects)."""

    nx, nw = 1, 2
    names = ("x", "y", "z")
    nominal = np.ones(3)
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, extra: Callable[[float, np.ndarray], np.ndarray] | None = None,
                 fail: Callable[[float, np.ndarray], None] | None = None):
        self.extra, self.fail = extra, fail
        self.calls = 0

    def evaluate(self, t, y):
        self.calls += 1
        if self.fail is not None:
            self.fail(t, y)
        x, w1, w2 = y
        out = np.array([w1, w1 + 2 * w2 - x, w1 - 3 * w2 - 2 * x])
        return out + self.extra(t, y) if self.extra is not None else out

    def partials(self, t, y):
        return np.array([[0.0, 1.0, 0.0], [-1.0, 1.0, 2.0], [-2.0, 1.0, -3.0]])


def hello_start(x: float = 1.0) -> np.ndarray:
    return np.array([x, 1.4 * x, -0.2 * x])


def discard_when(condition: Callable[[float, np.ndarray], bool], *, recoverable: bool = True):
    def fail(t, y):
        if condition(t, y):
            raise EvaluationFailed("fmi3GetContinuousStateDerivatives",
                                   "fmi3Discard" if recoverable else "fmi3Error",
                                   recoverable=recoverable)
    return fail


class Decay:
    """x' = -x as an ODE, with the 'algebraic variable' w = 2x, and a hook that may fail."""

    nx = 1
    names = ("x",)
    algebraic_names = ("w",)
    nominal = np.ones(1)
    jacobian_source = "exact"
    fmi_calls = 0

    def __init__(self, fail: Callable[[float, np.ndarray], None] | None = None):
        self.fail = fail

    def evaluate(self, t, x):
        if self.fail is not None:
            self.fail(t, x)
        return -x

    def partials(self, t, x):
        return -np.eye(1)

    def algebraic_values(self, t, x):
        return 2 * x


# ----------------------------------------------------------------------- systems with events

class Update(NamedTuple):
    """What one fmi3UpdateDiscreteStates says (as runtime.instance.DiscreteStates)."""

    needs_update: bool
    terminate: bool
    nominals_changed: bool
    values_changed: bool
    next_time: float | None


class _Events:
    """The FMI event protocol of a plain Python model: it records the calls, checks their order
    (Continuous-Time Mode -> Event Mode -> ... -> Continuous-Time Mode) and settles a change in
    two updates (the first says another is needed), as an FMU's fixed-point iteration does."""

    indicator_names: tuple[str, ...] = ()

    def __init__(self):
        self.calls: list[str] = []
        self.in_event_mode = False
        self.at: tuple[float, np.ndarray] | None = None
        self._pending = False

    def enter_event_mode(self, t, y):
        assert not self.in_event_mode
        self.calls.append("enter")
        self.in_event_mode, self.at = True, (float(t), np.array(y, dtype=float))

    def update_discrete_states(self):
        assert self.in_event_mode
        self.calls.append("update")
        t, y = self.at
        if self._pending:
            self._pending = False
            return Update(False, self.terminates(t), False, False, self.next_time(t))
        changed, values = self.on_event(t, y)
        self._pending = changed
        return Update(changed, self.terminates(t), False, values, self.next_time(t))

    def enter_continuous_time_mode(self):
        assert self.in_event_mode
        self.calls.append("leave")
        self.in_event_mode = False

    def read_states(self, y):
        self.calls.append("read")
        out = np.array(y, dtype=float)
        out[:len(self.at[1])] = self.at[1]
        return out

    # the model's part
    def on_event(self, t, y) -> tuple[bool, bool]:
        """Update the discrete state at (t, y); (anything changed, the states changed)."""
        return False, False

    def next_time(self, t) -> float | None:
        return None

    def terminates(self, t) -> bool:
        return False


class Relay(_Events):
    """A hysteresis relay as a DAE whose residual jumps at its events:

        x' = w,   0 = w + k (x - c),   c = UP (after the time event BOOST_AT: BOOSTED) or 0

    The relay switches down where x rises to 1 (indicator 1 - x) and up where x falls to 0.5
    (indicator x - 0.5); a time event at ``boost_at`` raises the upper target. x relaxes
    exponentially towards c, so :func:`relay_reference` gives the exact solution. ``terminate``:
    the FMU asks to end the run at the first event at or after that time."""

    nx, nw = 1, 1
    names = ("x", "w")
    nominal = np.ones(2)
    jacobian_source = "exact"
    fmi_calls = 0
    indicator_names = ("relay",)
    K, UP, BOOSTED, HIGH, LOW, BOOST_AT = 2.0, 2.0, 3.0, 1.0, 0.5, 1.6

    def __init__(self, *, terminate: float | None = None, boost_at: float | None = BOOST_AT):
        super().__init__()
        self.up, self.boosted, self.terminate = True, False, terminate
        self.boost_at = boost_at

    def start_update(self) -> Update:
        """What the event update at the end of initialisation says (the first time event)."""
        return Update(False, False, False, False, self.next_time(0.0))

    def target(self) -> float:
        return (self.BOOSTED if self.boosted else self.UP) if self.up else 0.0

    def evaluate(self, t, y):
        x, w = y
        return np.array([w, w + self.K * (x - self.target())])

    def partials(self, t, y):
        return np.array([[0.0, 1.0], [self.K, 1.0]])

    def indicators(self, t, y):
        x = y[0]
        return np.array([self.HIGH - x if self.up else x - self.LOW])

    def on_event(self, t, y):
        changed = False
        if self.boost_at is not None and not self.boosted and t >= self.boost_at:
            self.boosted = changed = True
        if self.indicators(t, y)[0] <= 0:
            self.up, changed = not self.up, True
        return changed, False

    def next_time(self, t):
        times = [s for s in ((None if self.boosted else self.boost_at), self.terminate)
                 if s is not None and s > t]
        return min(times) if times else None

    def terminates(self, t):
        return self.terminate is not None and t >= self.terminate


class RelayOde(Relay):
    """The relay in ODE mode: x' = -k (x - c), and w read as the 'algebraic variable'."""

    nx = 1
    names = ("x",)
    algebraic_names = ("w",)
    nominal = np.ones(1)

    def evaluate(self, t, x):
        return np.array([-self.K * (x[0] - self.target())])

    def partials(self, t, x):
        return np.array([[-self.K]])

    def algebraic_values(self, t, x):
        return self.evaluate(t, x)


def relay_reference(times, *, stop: float, boost_at: float | None = Relay.BOOST_AT
                    ) -> tuple[np.ndarray, np.ndarray, list]:
    """The exact x(t) and w(t) of :class:`Relay` from x(0) = 0 at ``times`` (at an event: the
    values after it), and its events [(t, kind)]."""
    r = Relay
    events: list[tuple[float, str]] = []
    t0, x0, up, boosted = 0.0, 0.0, True, False
    pieces = []   # (t0, x0, c) valid from t0 on
    while t0 < stop:
        c = (r.BOOSTED if boosted else r.UP) if up else 0.0
        level = r.HIGH if up else r.LOW
        hit = t0 + np.log((x0 - c) / (level - c)) / r.K
        boost = boost_at if boost_at is not None and not boosted and boost_at > t0 else np.inf
        pieces.append((t0, x0, c))
        t1 = min(hit, boost)
        if t1 > stop:
            break
        x0 = c + (x0 - c) * np.exp(-r.K * (t1 - t0))
        if boost <= hit:
            boosted = True
            events.append((boost, "time"))
        if hit <= boost:
            up = not up
            events.append((hit, "state"))
        t0 = t1
    x_out, w_out = [], []
    for t in times:
        start, x, c = [p for p in pieces if p[0] <= t][-1]
        x_out.append(c + (x - c) * np.exp(-r.K * (t - start)))
        w_out.append(-r.K * (x_out[-1] - c))
    return np.array(x_out), np.array(w_out), events


class BouncingBall(_Events):
    """h' = v, v' = -G; where h falls to 0, v = -E v (the states change at the event). Bounce
    times from h(0) = 1, v(0) = 0: t1 = sqrt(2/G), then flights of 2 E^k v1 / G."""

    nx = 2
    names = ("h", "v")
    algebraic_names = ()
    nominal = np.ones(2)
    jacobian_source = "exact"
    fmi_calls = 0
    indicator_names = ("h",)
    G, E = 9.81, 0.5

    def evaluate(self, t, x):
        return np.array([x[1], -self.G])

    def partials(self, t, x):
        return np.array([[0.0, 1.0], [0.0, 0.0]])

    def algebraic_values(self, t, x):
        return np.zeros(0)

    def indicators(self, t, x):
        return np.array([x[0]])

    def on_event(self, t, x):
        h, v = self.at[1]
        if h <= 0 and v < 0:
            self.at = (t, np.array([abs(h), -self.E * v]))  # h just above 0: z non-zero
            return True, True
        return False, False

    @classmethod
    def bounces(cls, stop: float) -> list[float]:
        t, v, out = np.sqrt(2 / cls.G), np.sqrt(2 * cls.G), []
        while t <= stop:
            out.append(float(t))
            v *= cls.E
            t += 2 * v / cls.G
        return out
