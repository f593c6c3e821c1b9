"""Tangent flow and Lyapunov spectra of the oscillator with spin dimers / relays.

Truth: Liouville (λ1 + λ2 = −2ζ exactly, det X = 1), the linear oscillator (C = 0: −ζ, −ζ),
finite differences of the flow map across switches, and the play limit N → ∞.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import pc_jacobian, pc_tangent, pc_trajectory
from scipy.stats import norm

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis.play import GeneralizedPlay
from hysteresis.spin_dimers import SpinDimerEnsemble
from oscillators import ForcedOscillator
from oscillators.engines import GrazingError
from oscillators.engines import _relay_kernels as relay_kernels

ZETA = 0.05
T = 2.0 * math.pi


def dimers(n_spins, seed=0):
    return SpinDimerEnsemble.random(n_spins, 2.0, 1.0, 2.0, seed=seed)


def quantile_dimers(n_spins, width=2.0, spread=1.0, j=2.0):
    """Deterministic disorder: centres at the normal quantiles (empirical CDF error <= 1/N)."""
    nd = n_spins // 2
    s = spread * norm.ppf((np.arange(nd) + 0.5) / nd)
    return SpinDimerEnsemble(np.column_stack([-s + j - width / 2, -s - j + width / 2]), j)


def test_uncoupled_oscillator_exponents():
    sysm = ForcedOscillator(dimers(200), 0.0)
    res = lyapunov_spectrum(sysm, 3000.0, 100.0, progress=False)
    np.testing.assert_allclose(res.exponents, [-ZETA, -ZETA], atol=1e-3)
    assert res.n_switches > 100  # the thresholds are crossed, the saltation is the identity
    res3 = lyapunov_spectrum(sysm, 3000.0, 100.0, include_phase=True, progress=False)
    np.testing.assert_allclose(res3.exponents, [0.0, -ZETA, -ZETA], atol=1e-3)
    assert res3.kaplan_yorke == 0.0 or res3.kaplan_yorke < 1.0 + 1e-9


@pytest.mark.parametrize("c", [1.0, 2.9, 4.0, -3.0])
@pytest.mark.parametrize("n_spins", [2, 200, 2000])
def test_sum_is_phase_space_contraction(c, n_spins):
    sysm = ForcedOscillator(dimers(n_spins, seed=1), c)
    res = lyapunov_spectrum(sysm, 400.0, 10.0, progress=False)
    assert abs(res.exponents.sum() + 2 * ZETA) < 1e-6
    assert np.all(np.diff(res.exponents) <= 0.0)
    res3 = lyapunov_spectrum(sysm, 400.0, 10.0, include_phase=True, progress=False)
    assert abs(res3.exponents.sum() + 2 * ZETA) < 1e-6
    assert np.min(np.abs(res3.exponents)) < 1e-9  # the phase exponent is exactly 0 here


def _flow(sysm, duration, x, opstate, engine):
    tr = pc_trajectory(
        sysm,
        duration,
        q0=x[0],
        v0=x[1],
        phi0=x[2],
        operator_state=opstate,
        sample_dt=duration,
        engine=engine,
    )
    return np.array([tr.q[-1], tr.v[-1]]), tr.switches.size


@pytest.mark.parametrize(
    "engine, n_spins, c",
    [
        ("kernel", 200, 4.0),
        ("kernel", 2000, 2.9),
        ("generic", 40, 3.0),
        ("kernel", 4, 2.9),
        ("kernel", 200, -3.0),
    ],
)
def test_tangent_flow_equals_finite_differences(engine, n_spins, c):
    ens = (
        dimers(n_spins, seed=2)
        if n_spins > 4
        else SpinDimerEnsemble(np.array([[2.0, 0.0], [-0.5, -2.5]]), 2.0)
    )
    sysm = ForcedOscillator(ens, c)
    x0 = np.array([-1.0, 0.1, 0.0])
    opstate = ens.initial_state(-1.0)
    duration = 3 * T
    jac = pc_jacobian(
        sysm, duration, *x0, operator_state=opstate, include_phase=True, engine=engine
    )
    _, n_sw = _flow(sysm, duration, x0, opstate, engine)
    assert n_sw >= 2
    eps = 1e-7
    fd = np.empty((2, 3))
    for j in range(3):
        dx = np.zeros(3)
        dx[j] = eps
        fp, np_ = _flow(sysm, duration, x0 + dx, opstate, engine)
        fm, nm = _flow(sysm, duration, x0 - dx, opstate, engine)
        assert np_ == nm == n_sw  # same switch sequence on both sides
        fd[:, j] = (fp - fm) / (2 * eps)
    scale = np.max(np.abs(fd))
    np.testing.assert_allclose(jac[:2, :], fd, atol=1e-5 * scale)
    # Liouville: det of the (q, v) block is exp(-2ζt) (saltation matrices have det 1)
    assert math.isclose(np.linalg.det(jac[:2, :2]), math.exp(-2 * ZETA * duration), rel_tol=1e-8)


def test_generic_and_kernel_spectra_agree():
    sysm = ForcedOscillator(dimers(40, seed=4), 3.5)
    a = pc_tangent(sysm, 60.0, progress=False, engine="kernel")
    b = pc_tangent(sysm, 60.0, progress=False, engine="generic")
    assert a.n_switches == b.n_switches
    np.testing.assert_allclose(a.exponents, b.exponents, atol=1e-8)


def test_relay_system_spectrum():
    """A single relay (generic shape: Relay class) obeys the same invariants."""
    from hysteresis.relay import Relay

    sysm = ForcedOscillator(Relay(0.0, -2.0), 2.0)
    res = lyapunov_spectrum(sysm, 2000.0, 100.0, progress=False)
    assert res.n_switches > 50
    assert abs(res.exponents.sum() + 2 * ZETA) < 1e-6
    assert res.history.shape[1] == 2 and res.history_t[-1] == 2000.0
    np.testing.assert_allclose(res.history[-1], res.exponents, atol=1e-12)


def test_history_converges_to_result():
    sysm = ForcedOscillator(dimers(2000, seed=0), 4.0)
    res = lyapunov_spectrum(sysm, 1000.0, 50.0, progress=False)
    assert res.history.shape[0] >= 10
    assert np.all(np.diff(res.history_t) > 0)
    np.testing.assert_allclose(res.history[-1], res.exponents, atol=1e-12)
    assert res.final.t == pytest.approx(1000.0, abs=1e-9)


def test_dimers_approach_play_limit():
    """First periods: N dimers vs the erf generalized play (same q0, v0; w0 = q0 - p/2).

    Deterministic quantile disorder, so the Preisach measure converges like 1/N and the
    trajectories must approach the limit as N grows. Random disorder (seed 0) at N = 20 000
    agrees within the 1/sqrt(N) fluctuation of its empirical centre distribution.
    """
    c = 4.0
    limit = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), c).trajectory(T, sample_dt=0.05)
    errors = []
    for n in (200, 2000, 20000):
        tr = ForcedOscillator(quantile_dimers(n), c).trajectory(T, sample_dt=0.05)
        np.testing.assert_allclose(tr.t, limit.t)
        errors.append(np.max(np.abs(tr.q - limit.q)))
    assert errors[1] < errors[0] / 5 and errors[2] < errors[1] / 5
    assert errors[2] < 10.0 / 20000
    tr = ForcedOscillator(dimers(20000, seed=0), c).trajectory(T, sample_dt=0.05)
    assert np.max(np.abs(tr.q - limit.q)) < 0.03


@pytest.mark.slow
def test_paper_c4_twenty_thousand_spins_chaotic():
    """Paper: for C in [3.8, 4.2] the piecewise-smooth system with N = 20 000 is chaotic."""
    sysm = ForcedOscillator(dimers(20000, seed=0), 4.0)
    res = lyapunov_spectrum(sysm, 50000.0, 5000.0, progress=False)
    assert res.exponents[0] > 0.01
    assert abs(res.exponents.sum() + 2 * ZETA) < 1e-6
    assert 1.0 < res.kaplan_yorke < 2.0


@pytest.mark.parametrize("engine", ["kernel", "generic"])
def test_labels_name_the_tangent_basis_not_the_exponents(engine):
    """C = 0 with the phase: exponents (0, -ζ, -ζ) come out in the order opposite to the basis
    (q, v, phi); ``labels`` stays the basis, the history rows stay descending."""
    sysm = ForcedOscillator(dimers(20), 0.0)
    res = pc_tangent(sysm, 600.0, 50.0, include_phase=True, progress=False, engine=engine)
    assert res.tangent_space == ("q", "v", "phi")
    np.testing.assert_allclose(res.exponents, [0.0, -ZETA, -ZETA], atol=5e-3)
    assert np.all(np.diff(res.history, axis=1) <= 0.0)
    res2 = pc_tangent(sysm, 100.0, progress=False, engine=engine)
    assert res2.tangent_space == ("q", "v")


def test_generic_engine_grazing_switch_raises(monkeypatch):
    """A switch found at a turning point (v* = 0, the kernels' rule: a maximum reaching the upper
    threshold switches) has an infinite saltation: a clear error, not NaN exponents."""
    from hysteresis.relay import Relay

    sysm = ForcedOscillator(Relay(0.5, -0.5), 2.0)
    scan = relay_kernels.scan_crossing
    calls = []

    def switch_here_once(par, force, q, v, c, s, tau, horizon, up, down):
        calls.append(v)
        if len(calls) == 1:
            return 0.0, 1  # the crossing is the current point, where v = 0
        return scan(par, force, q, v, c, s, tau, horizon, up, down)

    monkeypatch.setattr(relay_kernels, "scan_crossing", switch_here_once)
    with pytest.raises(GrazingError, match="grazing"):
        pc_jacobian(sysm, 1.0, q0=0.0, v0=0.0, engine="generic")
    # the trajectory itself is defined there: the relay switches (u >= alpha), no error
    calls.clear()
    traj = pc_trajectory(sysm, 0.05, q0=0.0, v0=0.0, engine="generic")
    assert traj.switches["v"][0] == 0.0 and traj.switches["jump"][0] == 2.0
