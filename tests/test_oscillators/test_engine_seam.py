"""The engine contract (oscillators.engines.base): a small motion contract, the tangent flow a
separate base an engine adds, and the public checks that every engine runs through.

A motion-only engine is written here in a few lines (the linear oscillator at C = 0 in closed
form) and checked against the relay kernel, which integrates the same closed form; the Jacobian
is refused for it with one sentence.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hysteresis import PlayOperator, Relay
from oscillators import ForcedOscillator, OscillatorState
from oscillators.engines import (
    CompiledContinuousEngine,
    ContinuousEngine,
    Engine,
    PlayEngine,
    RelayKernelEngine,
    RelayReferenceEngine,
    TangentFlow,
)
from oscillators.linear import exact_step, particular_amplitudes

MOTION = {"_clock", "_advance", "state", "records", "n_events"}
TANGENT = {"_start_tangent", "tangent_space", "_deviations", "_set_deviations", "_rank_bound"}
ENGINES = (
    RelayKernelEngine,
    RelayReferenceEngine,
    PlayEngine,
    ContinuousEngine,
    CompiledContinuousEngine,
)


def test_the_motion_contract_is_five_members_and_the_tangent_flow_five_more():
    assert Engine.__abstractmethods__ == MOTION
    assert TangentFlow.__abstractmethods__ == TANGENT


@pytest.mark.parametrize("cls", ENGINES, ids=lambda c: c.__name__)
def test_every_engine_adds_the_tangent_flow_and_keeps_the_checked_advance(cls):
    """No engine overrides the public, checked methods: the base's checks always run."""
    assert issubclass(cls, TangentFlow) and issubclass(cls, Engine)
    for name in ("advance", "start_tangent", "deviations", "set_deviations", "rank_bound"):
        owner = Engine if name == "advance" else TangentFlow
        assert getattr(cls, name) is getattr(owner, name), name


class FreeEngine(Engine):
    """The linear oscillator ``q'' + 2ζq' + q = cos φ`` (C = 0), exact: motion only."""

    name = "free oscillator"

    def __init__(self, system, state: OscillatorState) -> None:
        super().__init__(system, state)
        self._q, self._v, self._t = float(state.q), float(state.v), 0.0
        self._zeta = float(system.damping_ratio)
        self._amp = particular_amplitudes(self._zeta, self._omega)

    def _clock(self):
        n = math.floor(self._t / self._period)
        return n, self._t - n * self._period

    def _advance(self, times, out, record):
        for i, t in enumerate(times):
            ph0, ph1 = self._phi0 + self._omega * self._t, self._phi0 + self._omega * t
            self._q, self._v = exact_step(
                self._q, self._v, math.cos(ph0), math.sin(ph0), math.cos(ph1), math.sin(ph1),
                0.0, t - self._t, self._zeta, self._omega, *self._amp,
            )  # fmt: skip
            self._t = float(t)
            if out is not None:
                out[i, :3] = (self._q, self._v, 0.0)

    def state(self):
        return OscillatorState(self._q, self._v, self.phase(), self.start.operator_state, self._t)

    def records(self):
        return {}

    @property
    def n_events(self):
        return 0


def test_a_motion_only_engine_runs_through_the_checked_advance_and_has_no_jacobian():
    system = ForcedOscillator(Relay(50.0, -50.0), coupling=0.0, damping_ratio=0.1)
    start = system.initial_state(0.3, -0.2)
    free = FreeEngine(system, start)
    relay = system.engine(start)  # the relay kernel: the same closed form, no switch here
    times = np.linspace(0.0, 30.0, 61)
    a, b = np.empty((61, 3)), np.empty((61, 3))
    free.advance(times, a)
    relay.advance(times, b)
    np.testing.assert_allclose(a[:, :2], b[:, :2], rtol=0, atol=1e-12)
    free.advance(31.0)  # the float path of the base
    relay.advance(31.0)
    assert free.state().q == pytest.approx(relay.state().q, abs=1e-12)
    # the base's checks run for every engine, here as for the relay kernel
    for engine in (free, relay):
        with pytest.raises(ValueError, match="times must be >= the current elapsed time"):
            engine.advance(30.0)
        with pytest.raises(ValueError, match="times must be finite"):
            engine.advance(math.inf)
        with pytest.raises(ValueError, match="times must be sorted"):
            engine.advance(np.array([40.0, 35.0]))
    system._engine_cls = FreeEngine  # as if select_engine had chosen it
    with pytest.raises(TypeError) as info:
        system.jacobian(1.0, start)
    assert str(info.value) == (
        "the free oscillator engine has no tangent flow (it does not derive from "
        "oscillators.engines.TangentFlow), so the flow map has no Jacobian here"
    )
    from analysis.dynamics.lyapunov import TangentStepper

    with pytest.raises(TypeError, match="free oscillator engine has no tangent flow .* so it has"):
        TangentStepper(system).reinit()


def test_the_float_fast_path_gives_the_array_path_bits():
    """One float target and the same target as an array reach the same state, bit for bit
    (both the relay kernel's scalar clock and the play kernel's one-element buffer)."""
    for op in (Relay(0.5, -0.5), PlayOperator(1.0)):
        system = ForcedOscillator(op, coupling=0.7)
        start = system.initial_state()
        one, arr = system.engine(start), system.engine(start)
        for t in (0.7, 3.2, 9.9, 25.0):
            out1, out2 = np.empty((1, 3)), np.empty((1, 3))
            one.advance(t, out1)
            arr.advance(np.array([t]), out2)
            assert np.array_equal(out1, out2)
        assert one.state() == arr.state()


def test_short_arrays_split_and_check_as_the_numpy_path():
    """split_times and the time checks take a plain-Python path for short arrays
    (SHORT_ARRAY): the same bits as the numpy path, the same errors."""
    from oscillators.engines import base

    period = 2.0 * np.pi / 1.3
    rng = np.random.default_rng(4)
    t = np.concatenate(
        [
            np.sort(rng.uniform(0.0, 1e4, 40)),
            np.arange(5) * period,  # exact multiples: tau on the boundary
            np.nextafter(np.arange(1, 6) * period, 0.0),
            [0.0, 1e-300],
        ]
    )
    for chunk in (t[:40], t[40:45], t[45:50], t[50:]):
        short = base.split_times(chunk, period)
        long_n, long_tau = base.split_times(np.tile(chunk, 20), period)  # > SHORT_ARRAY
        assert np.array_equal(np.tile(short[0], 20), long_n)
        assert np.array_equal(np.tile(short[1], 20), long_tau)
        assert short[0].dtype == np.int64 and short[1].dtype == np.float64
    eng = ForcedOscillator(Relay(1.0, -1.0), coupling=1.0).engine()
    for bad, message in (([1.0, np.nan], "finite"), ([2.0, 1.0], "sorted"), ([-1.0], ">=")):
        for times in (np.array(bad), np.tile(np.array(bad), 40)):
            with pytest.raises(ValueError, match=message):
                eng.advance(times)
