"""Issue 21: a Filippov sliding motion on a relay threshold stops with SlidingError, and every
relay engine call has a bounded switch budget (SwitchBudgetError beyond it)."""

import numpy as np
import pytest

import oscillators
from hysteresis import Relay
from oscillators import ForcedOscillator, SlidingError, SwitchBudgetError
from oscillators.engines import base
from oscillators.engines.relay import _switch_budget


def _sliding_system():
    # zero-width relay at 0 (outputs ±1) with negative feedback: |cos φ| <= 1 < |C| = 5, so once
    # on the threshold q = 0, v = 0 the flow pushes into it from both sides
    return ForcedOscillator(Relay(0, 0), coupling=-5, damping_ratio=0.5)


@pytest.mark.parametrize("method", ["auto", "heap", "generic"])
def test_zero_width_negative_feedback_raises_sliding_error(method):
    osc = _sliding_system()
    eng = osc.engine(osc.initial_state(), method=method)
    period = eng.period
    with pytest.raises(SlidingError, match="slid") as info:
        eng.advance(period * np.arange(1, 17))
    # bounded work: the budget of the call (~1e5 switches, ~0.15 s compiled) instead of the
    # 48 million switches of the chattering orbit
    assert eng.n_events <= _switch_budget(1, osc.frequency, 16 * period) < 200_000
    with pytest.raises(SlidingError):
        osc.poincare_section(16, engine_options={"method": method})
    msg = str(info.value)
    assert "threshold q = 0.0" in msg and "Filippov" in msg
    assert info.value.threshold == 0.0
    assert 30.0 < info.value.time < 35.0  # the orbit reaches the threshold at t ≈ 32.5


def test_sliding_error_is_exported_and_a_value_error():
    assert oscillators.SlidingError is SlidingError
    assert issubclass(SlidingError, ValueError)
    assert issubclass(SwitchBudgetError, RuntimeError)


def test_sliding_error_with_tangent_flow_and_records():
    osc = _sliding_system()
    with pytest.raises(SlidingError):
        osc.trajectory(130)
    eng = osc.engine(osc.initial_state())
    eng.start_tangent()
    with pytest.raises(SlidingError):
        eng.advance(np.linspace(0.0, 40.0, 5), record=True)
    # the records of one call are bounded by the switch budget
    assert eng.records()["switches"].size <= _switch_budget(1, osc.frequency, 40.0)


def test_switch_budget_scales_with_time_relays_and_frequency():
    b = _switch_budget(1, 1.0, 0.0)
    assert b == base.SWITCH_BUDGET_FLOOR
    assert _switch_budget(10, 1.0, 2.0) == b + base.SWITCHES_PER_RELAY_AND_TIME * 20
    assert _switch_budget(1, 100.0, 1.0) == b + base.SWITCHES_PER_RELAY_AND_TIME * 100


def test_budget_error_when_not_sliding(monkeypatch):
    # a tiny budget on an ordinary (non-sliding) orbit: SwitchBudgetError naming the cap
    import oscillators.engines.relay as relay

    monkeypatch.setattr(relay, "_switch_budget", lambda n, omega, span: 3)
    osc = ForcedOscillator(Relay(0.1, -0.1), coupling=0.5)
    for method in ("auto", "generic"):
        with pytest.raises(SwitchBudgetError, match="switch budget exceeded") as info:
            osc.poincare_section(20, engine_options={"method": method})
        assert info.value.budget == 3
        assert "SWITCHES_PER_RELAY_AND_TIME" in str(info.value)
