"""Issue 21: the stepping engines (play kernel, continuous engine) have bounded work per
advance call, proportional to the advanced time (StepBudgetError beyond it, one line)."""

import numpy as np
import pytest

import oscillators.engines.continuous as continuous
import oscillators.engines.play as play
from hysteresis import PlayOperator, PrandtlIshlinskii
from oscillators import ForcedOscillator
from oscillators.engines import base
from oscillators.engines.base import StepBudgetError, step_budget


def test_step_budget_scales_with_time_frequency_and_damping():
    assert step_budget(1.0, 0.0, 0.0) == base.STEP_BUDGET_FLOOR
    assert step_budget(1.0, 0.1, 2.0) == base.STEP_BUDGET_FLOOR + 2 * base.STEPS_PER_TIME
    assert step_budget(0.5, 50.0, 1.0) == base.STEP_BUDGET_FLOOR + 100 * base.STEPS_PER_TIME
    assert issubclass(StepBudgetError, RuntimeError)


def test_ordinary_runs_stay_far_below_the_budget():
    # the generic continuous engine on a Prandtl–Ishlinskii operator: a few periods
    # take a few hundred steps and events, the budget for them is > 1e6
    op = PrandtlIshlinskii([1.0, 2.0, 3.0], [0.2, 0.2, 0.2])
    osc = ForcedOscillator(op, coupling=0.5)
    eng = osc.engine(osc.initial_state())
    assert isinstance(eng, continuous.ContinuousEngine)
    eng.advance(np.linspace(0.0, 6.0, 4))


@pytest.mark.parametrize("kind", ["continuous", "play"])
def test_budget_exceeded_raises_one_line(monkeypatch, kind):
    module = continuous if kind == "continuous" else play
    monkeypatch.setattr(module, "step_budget", lambda omega, zeta, span: 3)
    if kind == "continuous":
        op = PrandtlIshlinskii([1.0, 2.0, 3.0], [0.2, 0.2, 0.2])
    else:
        op = PlayOperator(1.0)
    osc = ForcedOscillator(op, coupling=0.5)
    with pytest.raises(StepBudgetError, match="step budget exceeded") as info:
        osc.trajectory(60.0)
    assert info.value.budget == 3
    assert "\n" not in str(info.value) and "STEPS_PER_TIME" in str(info.value)
