"""No silent failure: a diverged run raises, it is never reported as a result (issue 12).

The plain play at C >= 1: on a wall the stiffness is 1 - C < 0 (positive feedback), so the
motion runs away once the input drags the wagon. Closed form of the runaway rate on the wall:
q'' + 2ζq' + (1 - C) q = forcing, growth rate -ζ + sqrt(ζ² + C - 1).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import GeneralizedPlay, PlayOperator, SpinDimerEnsemble
from oscillators import DivergenceError, ForcedOscillator


def unstable_play() -> ForcedOscillator:
    with pytest.warns(RuntimeWarning, match="positive-feedback"):
        return ForcedOscillator(PlayOperator(2.0), coupling=4.0)


def test_unbounded_operator_with_strong_feedback_warns_at_construction():
    unstable_play()
    # below C = 1 the wall stiffness stays positive: no warning, bounded motion
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        stable = ForcedOscillator(PlayOperator(2.0), coupling=0.5)
    tr = stable.trajectory(500.0, sample_dt=0.5)
    assert np.all(np.isfinite(tr.q)) and np.abs(tr.q).max() < 50.0


def test_trajectory_section_and_spectrum_of_a_diverging_run_raise():
    system = unstable_play()
    # the wall growth rate at C = 4, ζ = 0.05 is about 1.68 per time unit: from O(1) to 1e12 in
    # well under 100 time units once the wagon is dragged
    rate = -0.05 + math.sqrt(0.05**2 + 4.0 - 1.0)
    assert rate > 1.6
    with pytest.raises(DivergenceError, match="diverged") as info:
        system.trajectory(1000.0, sample_dt=0.1)
    assert 0.0 < info.value.time < 100.0
    with pytest.raises(DivergenceError):
        system.poincare_section(500)
    with pytest.raises(DivergenceError):
        lyapunov_spectrum(system, 1000.0)
    with pytest.raises(DivergenceError):
        system.jacobian(200.0)


def test_the_first_diverged_sample_is_named():
    system = unstable_play()
    with pytest.raises(DivergenceError) as info:
        system.poincare_section(500)
    # the section point after which the motion is gone is within the first dozen periods,
    # not at the end of the requested run (500 periods)
    assert info.value.time < 20 * system.period


@pytest.mark.parametrize(
    "operator",
    [GeneralizedPlay.erf(2.0, 1.0), SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, seed=1)],
)
def test_bounded_operators_never_warn(operator):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        system = ForcedOscillator(operator, coupling=4.0)
    sec = system.poincare_section(20)
    assert np.all(np.isfinite(sec.q))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"coupling": "4"}, "coupling"),
        ({"coupling": float("nan")}, "coupling"),
        ({"coupling": 1e300}, "coupling"),
        ({"coupling": 1j}, "coupling"),
        ({"coupling": 1.0, "damping_ratio": -0.1}, "damping_ratio"),
        ({"coupling": 1.0, "damping_ratio": 1e308}, "damping_ratio"),
        ({"coupling": 1.0, "frequency": 0.0}, "frequency"),
        ({"coupling": 1.0, "frequency": 1e-300}, "frequency"),
        ({"coupling": 1.0, "frequency": "1"}, "frequency"),
        ({"coupling": 1.0, "frequency": 1e308}, "frequency"),
    ],
)
def test_oscillator_parameters_are_validated(kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), **kwargs)


def test_unbounded_work_is_refused_up_front():
    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 2.9)
    with pytest.raises(ValueError, match="sample_dt"):
        system.trajectory(1e6, sample_dt=1e-9)
    with pytest.raises(ValueError, match="n_periods"):
        system.poincare_section(10**9)
    with pytest.raises(TypeError, match="t_end"):
        system.trajectory("10")
    with pytest.raises(TypeError, match="operator"):
        ForcedOscillator("play", 1.0)


def test_operators_that_cannot_be_integrated_are_refused_at_construction():
    from hysteresis.base import ContinuousHysteron, Hysteron, PiecewiseConstantHysteron

    class Tanh:
        def initial_state(self, u0):
            return float(u0)

        def apply(self, inputs, state=None):
            u = np.asarray(inputs, dtype=float)
            return np.tanh(u), float(u[-1])

        def output(self, state):
            return float(np.tanh(state))

    class NoFlow(Tanh, ContinuousHysteron):
        """Continuous operator without branch_flow (the engine's contract)."""

    class NoSwitching(Tanh, PiecewiseConstantHysteron):
        """Piecewise-constant operator without switching()/relay_table()."""

    class NoFamily(Tanh, Hysteron):
        """An operator of neither family."""

    # the contract's required methods are abstract: such operators cannot even be built
    for cls, missing in ((NoFlow, "branch_flow"), (NoSwitching, "relay_table")):
        with pytest.raises(TypeError, match=missing):
            ForcedOscillator(cls(), coupling=1.0)
    with pytest.raises(TypeError, match="cannot be coupled"):
        ForcedOscillator(NoFamily(), coupling=1.0)
