"""The compiled Benettin loop of the relay kernel engine is the Python loop, bit for bit.

Independent truth: the same run with the compiled loop switched off (``qr_intervals`` doing
nothing, so every interval runs through the Python loop of ``lyapunov_spectrum``).
"""

import numpy as np
import pytest

import analysis.dynamics.lyapunov as lyapunov
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.experiments.ensemble import ensemble_task
from analysis.experiments.one_pass import one_pass_measurements
from hysteresis import Relay, SpinDimerEnsemble
from oscillators import ForcedOscillator


@pytest.fixture
def python_loop(monkeypatch):
    """Call ``run(compiled)``: with ``compiled=False`` the Python loop does every interval; the
    returned count is the intervals the compiled loop did."""
    compiled = lyapunov.qr_intervals

    def run(func, compiled_on: bool):
        done = [0]

        def counted(*args, **kwargs):
            n, rows = compiled(*args, **kwargs) if compiled_on else (0, np.empty((0, 4)))
            done[0] += n
            return n, rows

        monkeypatch.setattr(lyapunov, "qr_intervals", counted)
        try:
            return func(), done[0]
        finally:
            monkeypatch.setattr(lyapunov, "qr_intervals", compiled)

    return run


def _same(a, b) -> None:
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]), err_msg=key)


@pytest.mark.parametrize("coupling", [2.9, 4.0])
def test_ensemble_task_is_bit_identical(python_loop, coupling):
    task = dict(spins=300, coupling=coupling, seed=11, t_end=900.0, transient=100.0,
                keep_section=True)  # fmt: skip
    fast, done = python_loop(lambda: ensemble_task(**task), True)
    slow, none = python_loop(lambda: ensemble_task(**task), False)
    assert none == 0 and done > 10  # the compiled loop did (nearly) every interval
    _same(fast, slow)


@pytest.mark.parametrize("include_phase", [False, True])
def test_spectrum_history_and_state_are_bit_identical(python_loop, include_phase):
    system = ForcedOscillator(SpinDimerEnsemble.random(60, 2.0, 1.0, 2.0, seed=3), 3.2)

    def run():
        return lyapunov_spectrum(system, 400.0, 50.0, include_phase=include_phase,
                                 renormalize_dt=2.5, history_points=17)  # fmt: skip

    fast, done = python_loop(run, True)
    slow, _ = python_loop(run, False)
    assert done == 140  # ceil(350 / 2.5): every interval compiled
    for name in ("exponents", "history_t", "history"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name), err_msg=name)
    assert fast.n_switches == slow.n_switches and fast.extra == slow.extra
    assert (fast.final.q, fast.final.v, fast.final.t) == (slow.final.q, slow.final.v, slow.final.t)


def test_a_slide_mid_run_falls_back_to_the_python_loop(python_loop):
    # zero-width relay with negative feedback: it slides from t ≈ 21 on and never leaves
    # (tests/test_oscillators/test_sliding.py); the compiled loop does the intervals before
    # the slide, hands the one where it starts to the Python loop, and none after
    system = ForcedOscillator(Relay(0, 0), coupling=-5, damping_ratio=0.5)

    def run():
        return lyapunov_spectrum(system, 16 * system.period, 0.0, renormalize_dt=1.0)

    fast, done = python_loop(run, True)
    slow, _ = python_loop(run, False)
    assert 15 <= done <= 22  # the intervals before t ≈ 21
    np.testing.assert_array_equal(fast.exponents, slow.exponents)
    np.testing.assert_array_equal(fast.history, slow.history)
    assert np.all(np.isneginf(fast.exponents))


def test_batched_observer_sees_the_same_samples(python_loop):
    system = ForcedOscillator(SpinDimerEnsemble.random(40, 2.0, 1.0, 2.0, seed=5), 4.0)

    def run():
        return one_pass_measurements(system, 300.0, 30.0)

    (ly_fast, *fast), done = python_loop(run, True)
    (ly_slow, *slow), _ = python_loop(run, False)
    assert done > 0
    np.testing.assert_array_equal(ly_fast.exponents, ly_slow.exponents)
    for x, y in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
