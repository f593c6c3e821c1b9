"""Issue 21: the stepping engines (play kernel, continuous engine) have bounded work per
advance call, proportional to the advanced time (StepBudgetError beyond it, one line)."""

import numpy as np
import pytest

import oscillators.engines.compiled_continuous as compiled_continuous
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


@pytest.mark.parametrize(
    "method, engine_class",
    [
        ("generic", continuous.ContinuousEngine),
        (None, compiled_continuous.CompiledContinuousEngine),
    ],
)
def test_ordinary_runs_stay_far_below_the_budget(method, engine_class):
    # a continuous engine on a Prandtl–Ishlinskii operator: a few periods take a few hundred
    # steps and events, the budget for them is > 1e6
    op = PrandtlIshlinskii([1.0, 2.0, 3.0], [0.2, 0.2, 0.2])
    osc = ForcedOscillator(op, coupling=0.5)
    options = {} if method is None else {"method": method}
    eng = osc.engine(osc.initial_state(), **options)
    assert isinstance(eng, engine_class)
    eng.advance(np.linspace(0.0, 6.0, 4))


@pytest.mark.parametrize("kind", ["continuous", "compiled", "play"])
def test_budget_exceeded_raises_one_line(monkeypatch, kind):
    module = {"continuous": continuous, "compiled": compiled_continuous, "play": play}[kind]
    monkeypatch.setattr(module, "step_budget", lambda omega, zeta, span: 3)
    options = {"method": "generic"} if kind == "continuous" else None
    if kind == "play":
        op = PlayOperator(1.0)
    else:
        op = PrandtlIshlinskii([1.0, 2.0, 3.0], [0.2, 0.2, 0.2])
    osc = ForcedOscillator(op, coupling=0.5)
    with pytest.raises(StepBudgetError, match="step budget exceeded") as info:
        osc.trajectory(60.0, engine_options=options)
    assert info.value.budget == 3
    assert "\n" not in str(info.value) and "STEPS_PER_TIME" in str(info.value)
