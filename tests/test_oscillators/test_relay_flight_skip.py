"""The relay kernel's exact flights with proven-free stretches skipped
(:func:`oscillators.engines._relay_kernels.scan_crossing`) against the same scan without skips
(``scan_flight(..., span_max=0)``, the sub-interval by sub-interval scan): the same crossing,
bit for bit, on random flights, on flights that graze a threshold and on flights whose
threshold sits just inside or outside an extremum; and the fourth-derivative bound the skips
rest on against the analytic ``q⁗`` along the flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from oscillators.engines import _relay_kernels as kern
from oscillators.engines._play_kernels import _hit_possible
from oscillators.linear import particular_amplitudes


def _params(zeta: float, omega: float, coupling: float = 1.0, phi0: float = 0.0) -> np.ndarray:
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    return kern.make_params(zeta, omega, coupling, phi0, amp_a, amp_b, 0.0)


def _phase(par: np.ndarray, tau: float) -> tuple[float, float]:
    ph = par[kern.P_PHI0] + par[kern.P_OMEGA] * tau
    return math.cos(ph), math.sin(ph)


def _samples(par, force, q0, v0, tau0, horizon, n=4001):
    c0, s0 = _phase(par, tau0)
    ts = np.linspace(0.0, horizon, n)
    rows = np.array([kern._eval(par, force, q0, v0, c0, s0, tau0, t) for t in ts])
    return ts, rows


def _random_start(rng, par, force_max, q_max, v_max):
    """(force, q0, v0, tau0) of a random flight, drawn in that order."""
    force = rng.uniform(-force_max, force_max)
    q0 = rng.uniform(-q_max, q_max)
    v0 = rng.uniform(-v_max, v_max)
    return force, q0, v0, rng.uniform(0.0, par[kern.P_T])


def _both(par, force, q0, v0, tau0, horizon, up, down):
    c0, s0 = _phase(par, tau0)
    new = kern.scan_crossing(par, force, q0, v0, c0, s0, tau0, horizon, up, down)
    ref = kern.scan_flight(par, force, q0, v0, c0, s0, tau0, horizon, up, down, 0)
    return new, ref


SYSTEMS = [(0.05, 1.0), (0.05, 0.4), (0.3, 2.5), (0.9, 1.0), (1.0, 1.0), (2.0, 0.7)]


@pytest.mark.parametrize("zeta, omega", SYSTEMS)
def test_random_flights_find_the_same_crossing_bit_for_bit(zeta, omega):
    rng = np.random.default_rng(17)
    par = _params(zeta, omega)
    hits = 0
    for _ in range(300):
        force, q0, v0, tau0 = _random_start(rng, par, 3.0, 3.0, 2.0)
        horizon = rng.choice([0.03, 0.5, 3.0, 20.0]) * rng.uniform(0.5, 1.0)
        up = q0 + rng.exponential(1.0) * rng.choice([1e-6, 1e-2, 1.0])
        down = q0 - rng.exponential(1.0) * rng.choice([1e-6, 1e-2, 1.0])
        new, ref = _both(par, force, q0, v0, tau0, horizon, up, down)
        assert new == ref
        hits += ref[1] != 0
    assert 0 < hits < 300  # both kinds of flight are exercised


@pytest.mark.parametrize("zeta, omega", SYSTEMS[:4])
def test_flights_near_an_extremum_find_the_same_crossing(zeta, omega):
    """Thresholds placed at an extremum of the motion, and a hair inside or outside it: the
    cases where a coarse bound could hide a touch."""
    rng = np.random.default_rng(5)
    par = _params(zeta, omega)
    for _ in range(60):
        force, q0, v0, tau0 = _random_start(rng, par, 2.0, 2.0, 1.5)
        horizon = 15.0
        _, rows = _samples(par, force, q0, v0, tau0, horizon)
        top = rows[:, 0].max()
        bottom = rows[:, 0].min()
        for eps in (0.0, 1e-12, -1e-12, 1e-7, -1e-7, 1e-3):
            pairs = ((top + eps, -np.inf), (np.inf, bottom - eps), (top + eps, bottom - eps))
            for up, down in pairs:
                if not down <= q0 < up:  # a flight starts between its thresholds
                    continue
                new, ref = _both(par, force, q0, v0, tau0, horizon, up, down)
                assert new == ref


@pytest.mark.parametrize("zeta, omega", SYSTEMS[:4])
def test_fourth_derivative_bound_holds_along_the_flight(zeta, omega):
    """q⁗ = −2ζ q‴ − q'' − Ω² cos φ (differentiating the equation of motion twice)."""
    rng = np.random.default_rng(3)
    par = _params(zeta, omega)
    for _ in range(40):
        force, q0, v0, tau0 = _random_start(rng, par, 3.0, 4.0, 3.0)
        c0, s0 = _phase(par, tau0)
        bound = kern.flight_derivative_bound(par, force, q0, v0, c0, s0)
        ts, rows = _samples(par, force, q0, v0, tau0, 30.0)
        phase = par[kern.P_PHI0] + omega * (tau0 + ts)
        q4 = -2.0 * zeta * rows[:, 3] - rows[:, 2] - omega**2 * np.cos(phase)
        assert np.max(np.abs(q4)) <= bound * (1.0 + 1e-12)
        # not vacuous: the bound is within the amplitude's order of the true maximum
        assert bound <= 10.0 * np.max(np.abs(q4)) + 1e-12


def test_no_bound_and_no_skip_when_overdamped():
    par = _params(1.0, 1.0)
    assert kern.flight_derivative_bound(par, 0.3, 1.0, 0.2, 1.0, 0.0) == np.inf
    par = _params(3.0, 1.0)
    assert kern.flight_derivative_bound(par, 0.3, 1.0, 0.2, 1.0, 0.0) == np.inf


def test_a_far_threshold_stretch_is_skipped():
    """The skip test itself: far from both thresholds a whole stretch of SKIP_SPAN
    sub-intervals is provably free, next to a threshold it is not."""
    par = _params(0.05, 1.0)
    c0, s0 = _phase(par, 0.0)
    q0, v0, force = 0.2, 0.1, 0.0
    span = kern.SKIP_SPAN * par[kern.P_DSUB]
    qe, ve, _, _ = kern._eval(par, force, q0, v0, c0, s0, 0.0, span)
    m4 = kern.flight_derivative_bound(par, force, q0, v0, c0, s0)
    assert not _hit_possible(q0, v0, qe, ve, span, 50.0, -50.0, m4)
    assert _hit_possible(q0, v0, qe, ve, span, max(q0, qe) + 1e-6, -50.0, m4)
    new, ref = _both(par, force, q0, v0, 0.0, 40.0, 50.0, -50.0)
    assert new == ref == (40.0, 0)
