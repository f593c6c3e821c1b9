"""TangentStepper: sampling inside a QR interval, the observer hook, re-initialisation."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.lyapunov import TangentStepper, lyapunov_spectrum
from hysteresis.spin_dimers import SpinDimerEnsemble
from oscillators import ForcedOscillator


def _system(coupling: float = 4.0) -> ForcedOscillator:
    return ForcedOscillator(SpinDimerEnsemble.random(60, 2.0, 1.0, 2.0, 7), coupling)


def test_samples_are_the_poincare_section():
    # a QR interval of 5 periods, sampled every period: the rows are the section points that
    # poincare_section computes on its own (a separate engine run without tangent flow)
    system = _system()
    period = system.period
    stepper = TangentStepper(system, sample_dt=period)
    stepper.reinit(system.initial_state(-1.0, 0.1), transient=3 * period)
    rows = [stepper.samples]
    for _ in range(4):
        stepper.step(5 * period)
        rows.append(stepper.samples)
    assert [r.shape[0] for r in rows] == [1, 5, 5, 5, 5]
    t = np.concatenate([r[:, 0] for r in rows])
    assert np.allclose(t, period * np.arange(3, 24), rtol=0, atol=1e-9)
    sec = system.poincare_section(21, 3)
    q = np.concatenate([r[:, 1] for r in rows])
    v = np.concatenate([r[:, 2] for r in rows])
    assert np.allclose(q, sec.q, atol=1e-9) and np.allclose(v, sec.v, atol=1e-9)
    assert np.array_equal(stepper.sample, rows[-1][-1, 1:])


def test_step_between_sample_points_keeps_only_its_end():
    system = _system()
    stepper = TangentStepper(system, sample_dt=system.period)
    stepper.reinit(None, transient=0.0)
    stepper.step(0.3 * system.period)  # passes no multiple of T
    assert stepper.samples.shape == (1, 4)
    assert stepper.samples[0, 0] == pytest.approx(0.3 * system.period)


def test_sample_dt_is_validated():
    with pytest.raises(ValueError, match="sample_dt"):
        TangentStepper(_system(), sample_dt=0.0)


def test_observer_sees_every_step_and_the_qr_interval_does_not_change_the_exponents():
    system = _system(2.9)
    period = system.period
    seen: list[float] = []
    res1 = lyapunov_spectrum(
        system, 60 * period, 10 * period, renormalize_dt=period,
        observer=lambda st: seen.append(st.elapsed),
    )  # fmt: skip
    assert len(seen) == 51  # after the transient, then after each of the 50 QR steps
    assert np.allclose(seen, period * np.arange(10, 61), atol=1e-9)
    # QR every 10 periods: the same exponents up to round-off (QR telescopes)
    res10 = lyapunov_spectrum(system, 60 * period, 10 * period, renormalize_dt=10 * period)
    assert np.allclose(res1.exponents, res10.exponents, atol=1e-10)
    # and Σλ = −2ζ holds either way
    assert res10.exponents.sum() == pytest.approx(-2 * system.damping_ratio, abs=1e-10)


def test_reinit_reuses_the_stepper():
    system = _system()
    stepper = TangentStepper(system)
    a = lyapunov_spectrum(system, 200.0, 20.0, stepper=stepper)
    b = lyapunov_spectrum(system, 200.0, 20.0, stepper=stepper)
    assert np.array_equal(a.exponents, b.exponents)


def test_whole_intervals_leave_out_the_remainder():
    # 10.6 periods in QR intervals of one period: whole_intervals averages over the first 10
    # (the same run as t_end = 10 periods, to the last bit: the same targets and divisor);
    # by default an 11th, shorter interval ends at t_end
    system = _system()
    period = system.period
    whole = lyapunov_spectrum(system, 10.6 * period, whole_intervals=True)
    ten = lyapunov_spectrum(system, 10 * period)
    assert np.array_equal(whole.exponents, ten.exponents)
    assert whole.t_end == ten.t_end == 10 * period
    longer = lyapunov_spectrum(system, 10.6 * period)
    assert longer.t_end == 10.6 * period and not np.array_equal(longer.exponents, ten.exponents)
    with pytest.raises(ValueError, match="shorter than one renormalization interval"):
        lyapunov_spectrum(system, 0.5 * period, whole_intervals=True)
