"""Periodic orbits and Floquet multipliers against independent truth: the linear oscillator's
closed form, the Lyapunov spectrum of the same orbit, central finite differences of P^k, and
Newton's quadratic convergence."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import (
    OrbitNotFoundError,
    find_periodic_orbit,
    refine_periodic_orbit,
    shoot,
)
from hysteresis import GeneralizedPlay, Relay, SpinDimerEnsemble
from oscillators import ForcedOscillator


def _relay_system(coupling: float = 1.5) -> ForcedOscillator:
    return ForcedOscillator(Relay(1.0, -1.0), coupling)


def _erf_system(coupling: float = 3.85) -> ForcedOscillator:
    return ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), coupling)


@pytest.mark.parametrize(("zeta", "omega"), [(0.05, 1.0), (0.3, 1.3), (0.8, 0.7)])
def test_linear_oscillator_multipliers_closed_form(zeta, omega):
    # C = 0: P is affine with the fundamental matrix of q'' + 2ζq' + q = 0 over T, whose
    # eigenvalues are exp((−ζ ± i√(1−ζ²))·T); the relay engine propagates the closed form, so the
    # only error is round-off (~1e-15 per operation, a few hundred operations): 1e-10 is safe
    system = ForcedOscillator(Relay(1.0, -1.0), 0.0, zeta, omega)
    orbit = find_periodic_orbit(system, max_period=4)
    assert orbit.period == 1
    t = system.period
    wd = math.sqrt(1.0 - zeta**2)
    expected = np.exp((-zeta + 1j * np.array([wd, -wd])) * t)
    got = orbit.multipliers
    assert np.max(np.abs(np.sort_complex(got) - np.sort_complex(expected))) < 1e-10
    assert np.allclose(orbit.exponents, -zeta, atol=1e-12)
    assert orbit.stable
    assert orbit.tangent_space == ("q", "v")
    assert orbit.residual <= orbit.tolerance * max(1.0, np.max(np.abs(orbit.points)))


def _sorted_desc(x: np.ndarray) -> np.ndarray:
    return np.sort(x)[::-1]


@pytest.mark.parametrize(
    ("system", "label"),
    [
        (_relay_system(1.5), "relay"),
        (ForcedOscillator(SpinDimerEnsemble.random(20, 2.0, 1.0, 2.0, seed=1), 4.0), "dimers"),
        (_erf_system(3.85), "erf-play"),
    ],
    ids=["relay", "dimers", "erf-play"],
)
def test_floquet_exponents_equal_lyapunov_exponents(system, label):
    orbit = find_periodic_orbit(system, max_period=16)
    k = orbit.period
    # the QR average on a periodic orbit converges as B/t (B ≈ log of the eigenvector basis'
    # condition, O(1)); over 4000 orbit periods (t ≈ 2.5e4·k) that is below 1e-4
    ly = lyapunov_spectrum(
        system, 4000 * k * system.period, 0.0, state=orbit.start, renormalize_dt=k * system.period
    )
    floquet = _sorted_desc(orbit.exponents)
    finite = np.isfinite(floquet)
    assert np.array_equal(finite, np.isfinite(ly.exponents)), (floquet, ly.exponents)
    print(label, "period", k, "Floquet", floquet, "Lyapunov", ly.exponents)
    assert np.max(np.abs(floquet[finite] - ly.exponents[finite])) < 1e-4
    if label == "erf-play":
        # the wagon hits a wall along the orbit: V_out resets δw := δq, multiplier exactly 0
        assert orbit.multipliers[-1] == 0 and orbit.exponents[-1] == -np.inf
    else:
        # relays: every saltation has determinant 1, Σλ = −2ζ
        assert abs(floquet.sum() + 2 * system.damping_ratio) < 1e-10


def _central_differences(system, start, k: int, h: float) -> np.ndarray:
    coords = StateCoordinates(system, start)
    x = coords.vector(start)
    cols = []
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = h
        plus = shoot(system, coords.state(x + e, start), k).states[-1]
        minus = shoot(system, coords.state(x - e, start), k).states[-1]
        cols.append((coords.vector(plus) - coords.vector(minus)) / (2 * h))
    return np.column_stack(cols)


@pytest.mark.parametrize("which", ["relay", "erf-play"])
def test_monodromy_matches_central_differences(which):
    system = _relay_system(1.5) if which == "relay" else _erf_system(3.85)
    orbit = find_periodic_orbit(system, max_period=16)
    i = 0
    if which == "erf-play":
        # a point strictly inside the play, so that ±h in w stays on the same branch (on a wall
        # moving outward the w-derivative is one-sided); every orbit point is a fixed point of
        # P^k, and the monodromy there is the engine's Jacobian from that point
        gaps = np.abs(orbit.points[:, 0] - orbit.points[:, 2])
        inside = np.nonzero(gaps < 1.0 - 1e-3)[0]
        assert inside.size, gaps
        i = int(inside[0])
    start = orbit.states[i]
    jac = shoot(system, start, orbit.period).jacobian
    fd = _central_differences(system, start, orbit.period, h=1e-6)
    # central differences: truncation h²/6·|D³P| (|D³P| = O(|J|·10) here) plus round-off
    # ~ε·|x|·|J|/h ≈ 1e-10·|J|; both well below 1e-6·max(1, |J|)
    scale = max(1.0, float(np.max(np.abs(jac))))
    assert np.max(np.abs(fd - jac)) < 1e-6 * scale
    # the multipliers are the same at every point of the orbit (conjugate monodromies)
    mu_fd = np.sort(np.abs(np.linalg.eigvals(fd)))
    assert np.max(np.abs(mu_fd - np.sort(np.abs(orbit.multipliers)))) < 1e-6 * scale


def test_newton_converges_quadratically():
    # the erf play at C = 3.85: a smooth (in the state) period-5 orbit; start 1e-2 off in q
    system = _erf_system(3.85)
    orbit = find_periodic_orbit(system, max_period=16)
    guess = replace(orbit.start, q=orbit.start.q + 1e-2)
    guess = StateCoordinates(system, orbit.start).state(
        np.array([guess.q, guess.v, orbit.points[0, 2]]), orbit.start
    )
    refined = refine_periodic_orbit(system, guess, orbit.period, tolerance=1e-12)
    e = np.array(refined.residuals)
    print("Newton residuals", e)
    # K from the problem: e_{n+1} ≈ ½·|(J − I)^{-1}|·|D²P^k|·e_n² with |D²P^k| estimated by a
    # forward difference of the Jacobian (step 1e-4 along each coordinate); a factor 10 covers
    # the norm inequalities (∞-norms of vectors vs matrices, higher-order terms at e ~ 1e-2)
    coords = StateCoordinates(system, orbit.start)
    x = coords.vector(orbit.start)
    d2 = 0.0
    for j in range(x.size):
        dx = np.zeros(x.size)
        dx[j] = 1e-4
        jac = shoot(system, coords.state(x + dx, orbit.start), orbit.period).jacobian
        d2 = max(d2, np.max(np.abs(jac - orbit.monodromy)) / 1e-4)
    inv = np.max(np.abs(np.linalg.inv(orbit.monodromy - np.eye(x.size))).sum(axis=1))
    k_bound = 10 * 0.5 * inv * d2 * x.size
    before_roundoff = e[:-1] > 1e-9  # below that the next residual is round-off (~1e-13)
    assert before_roundoff.sum() >= 2, e
    for n in np.nonzero(before_roundoff)[0]:
        assert e[n + 1] <= k_bound * e[n] ** 2, (n, e, k_bound)
    assert e[-1] <= 1e-12 * max(1.0, np.max(np.abs(refined.points)))


def test_to_dict_is_json_with_minus_inf_strings():
    orbit = find_periodic_orbit(_erf_system(3.85), max_period=16)
    d = json.loads(json.dumps(orbit.to_dict()))
    assert d["period"] == orbit.period == len(orbit.states)
    assert d["exponents"][-1] == "-inf"
    assert d["tangent_space"] == ["q", "v", "w"]
    assert len(d["multipliers"]) == 3 and all(len(m) == 2 for m in d["multipliers"])
    assert d["stable"] is True
    # the orbit points are one orbit: P maps each to the next and the last to the first
    system = _erf_system(3.85)
    images = shoot(system, orbit.start, orbit.period).states
    coords = StateCoordinates(system, orbit.start)
    got = np.array([coords.vector(s) for s in images])
    assert np.allclose(np.roll(got, 1, axis=0), orbit.points, atol=1e-9)
    # the event sequence: k wall hits and k reversals or more, alternating
    kinds = [e[0] for e in orbit.sequence]
    assert len(kinds) >= 2 and all(a != b for a, b in zip(kinds, kinds[1:], strict=False))


def test_chaos_raises_orbit_not_found():
    # the erf play at C = 2.9 is chaotic (paper fig:bif; λ_max ≈ 0.03 > 0)
    with pytest.raises(OrbitNotFoundError, match="period"):
        find_periodic_orbit(_erf_system(2.9), transient=50, max_period=8)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"transient": -1}, "transient"),
        ({"max_period": 0}, "max_period"),
        ({"tolerance": 0.0}, "tolerance"),
        ({"max_iterations": 1.5}, "max_iterations"),
        ({"max_period": 10**6}, "max_period"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        find_periodic_orbit(_relay_system(), **kwargs)


def test_state_and_q0_are_exclusive():
    system = _relay_system()
    with pytest.raises(ValueError, match="either state or q0"):
        find_periodic_orbit(system, system.initial_state(), q0=0.5)


@pytest.mark.parametrize("operator", [GeneralizedPlay.erf(2.0, 1.0), Relay(1.0, -1.0)])
def test_undamped_resonant_orbit_is_neutral_not_stable(operator):
    # ζ = 0, C = 0, Ω = 0.7: seven forcing periods are ten free periods, P^7 is the identity on
    # (q, v) and every state is a period-7 orbit: its multipliers are exactly 1 in exact
    # arithmetic, and the computed ones (1 − 4e-16 for the play engine) are neither stable nor
    # unstable. Genuinely stable/unstable orbits keep their verdict (the other tests).
    system = ForcedOscillator(operator, 0.0, 0.0, 0.7)
    orbit = find_periodic_orbit(system, max_period=10)
    assert orbit.period == 7
    free = np.abs(orbit.multipliers[:2])
    assert np.all(np.abs(free - 1.0) < 1e-13)  # round-off of the closed form, a few ulp
    assert orbit.stability == "neutral" and orbit.stable is False
    d = json.loads(json.dumps(orbit.to_dict()))
    assert d["stability"] == "neutral" and d["stable"] is False


def test_stable_orbits_stay_stable():
    assert find_periodic_orbit(_erf_system(3.85), max_period=16).stability == "stable"
    system = ForcedOscillator(Relay(1.0, -1.0), 0.0, 0.05, 1.0)
    assert find_periodic_orbit(system, max_period=4).stability == "stable"
