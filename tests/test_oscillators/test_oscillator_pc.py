"""Event-driven oscillator with piecewise-constant operators against independent truth.

The reference is a brute-force integration written here from the paper only: scipy's DOP853 at
rtol = atol = 1e-12 with terminal events on the nearest active thresholds, the dimers switched by
hand (up once q >= alpha = J - b1, down once q < beta = -J - b2), M = mean of the spins.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import pc_jacobian, pc_trajectory, relay_brute_force
from scipy.integrate import solve_ivp

from hysteresis.relay import Relay
from hysteresis.spin_dimers import SpinDimerEnsemble
from oscillators import ForcedOscillator, OscillatorState

ZETA = 0.05
OMEGA = 1.0
T = 2.0 * math.pi


def brute_force_dimers(fields, coupling_j, c, t_end, q0=-1.0, v0=0.1, zeta=ZETA, omega=OMEGA):
    """Switch events (time, q, v, dM) of q'' + 2ζq' + q = cos Ωt + C·M, dimers by hand: dimer i
    is the relay alpha = J - b1, beta = -J - b2 with weight 1/(number of dimers), M = mean of
    the spins (all spins down, relaxed at q0)."""
    fields = np.asarray(fields, dtype=float)
    alpha = coupling_j - fields.max(axis=1)
    beta = -coupling_j - fields.min(axis=1)
    assert np.all(alpha > beta), "test helper handles hysteretic dimers only"
    weights = np.full(alpha.size, 1.0 / alpha.size)
    events, _ = relay_brute_force(alpha, beta, weights, c, t_end, q0, v0, zeta, omega)
    return events


def dimer_system(fields, c, coupling_j=2.0):
    return ForcedOscillator(SpinDimerEnsemble(np.asarray(fields, float), coupling_j), c)


def assert_switches_match(traj, ref, tol):
    sw = traj.switches
    assert sw.size == ref.shape[0], (sw.size, ref.shape[0])
    np.testing.assert_allclose(sw["time"], ref[:, 0], rtol=0, atol=tol)
    np.testing.assert_allclose(sw["q"], ref[:, 1], rtol=0, atol=tol)
    np.testing.assert_allclose(sw["v"], ref[:, 2], rtol=0, atol=tol)
    np.testing.assert_allclose(sw["jump"], ref[:, 3], rtol=0, atol=1e-12)


@pytest.mark.parametrize("c", [2.0, 4.0])
def test_two_spins_match_brute_force(c):
    fields = [[2.0, 0.0]]  # paper Fig. 4: alpha = 0, beta = -2
    t_end = 20 * T
    traj = dimer_system(fields, c).trajectory(t_end, sample_dt=0.5)
    ref = brute_force_dimers(fields, 2.0, c, t_end)
    assert ref.shape[0] >= 5
    assert_switches_match(traj, ref, 1e-8)


@pytest.mark.parametrize("c", [2.9, 4.0])
def test_four_spins_match_brute_force(c):
    fields = [[2.0, 0.0], [-0.5, -2.5]]  # paper Fig. 5: alpha = (0, 2.5), beta = (-2, 0.5)
    t_end = 20 * T
    traj = dimer_system(fields, c).trajectory(t_end, sample_dt=0.5)
    ref = brute_force_dimers(fields, 2.0, c, t_end)
    assert ref.shape[0] >= 5
    assert_switches_match(traj, ref, 1e-8)


@pytest.mark.parametrize("c", [2.9, 4.0])
def test_two_hundred_spins_match_brute_force(c):
    ens = SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, seed=3)
    t_end = 20 * T
    traj = ForcedOscillator(ens, c).trajectory(t_end, sample_dt=0.5)
    ref = brute_force_dimers(ens.fields, 2.0, c, t_end)
    assert ref.shape[0] >= 500
    assert_switches_match(traj, ref, 1e-8)


def test_generic_engine_matches_kernel():
    """Same dimers through switching()/apply() (Python loop) and the equal-width kernel."""
    ens = SpinDimerEnsemble.random(40, 2.0, 1.0, 2.0, seed=1)
    sysm = ForcedOscillator(ens, 3.0)
    a = pc_trajectory(sysm, 10 * T, sample_dt=0.1, engine="kernel")
    b = pc_trajectory(sysm, 10 * T, sample_dt=0.1, engine="generic")
    assert a.switches.size == b.switches.size > 50
    np.testing.assert_allclose(a.switches["time"], b.switches["time"], atol=1e-11)
    np.testing.assert_allclose(a.q, b.q, atol=1e-10)
    np.testing.assert_allclose(a.M, b.M, rtol=0, atol=1e-12)
    # the kernel's final index is turned back into a full operator state: same relays up
    model = ens.to_preisach()
    np.testing.assert_array_equal(
        model.relay_states(a.final.operator_state), model.relay_states(b.final.operator_state)
    )


def test_taylor_hops_at_round_off():
    """Short-hop Taylor/Newton path against the exact propagator for every hop.

    ~3000 switches over 3 periods. Round-off (1e-16 per hop) is amplified by the saltation at
    low-velocity switches: perturbing v0 by 1e-15 in the exact engine moves the switch times by
    ~1e-12 over the same run, so 1e-11 is the round-off floor here, not a loosened tolerance.
    """
    ens = SpinDimerEnsemble.random(4000, 2.0, 1.0, 2.0, seed=0)
    sysm = ForcedOscillator(ens, 4.0)
    a = pc_trajectory(sysm, 3 * T, sample_dt=T / 16, taylor=True)
    b = pc_trajectory(sysm, 3 * T, sample_dt=T / 16, taylor=False)
    assert a.switches.size == b.switches.size > 2000
    np.testing.assert_allclose(a.switches["time"], b.switches["time"], rtol=0, atol=1e-11)
    np.testing.assert_allclose(a.switches["v"], b.switches["v"], rtol=0, atol=1e-11)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-11)
    first = a.switches["time"] < T  # before any amplification: plain round-off
    np.testing.assert_allclose(a.switches["time"][first], b.switches["time"][first], atol=1e-13)


def test_short_hop_fast_path_at_round_off():
    """N = 20 000 dimers: most hops are shorter than 1e-3 and take the kernel's fast short hop
    (series reversion + one Newton step). Every switch time, switch velocity and the tangent map
    of one forcing period agree with the exact-propagator path (``taylor=False``), and the
    tangent map has det = exp(-2ζt) (saltation matrices have det 1: Liouville)."""
    ens = SpinDimerEnsemble.random(20000, 2.0, 1.0, 2.0, seed=0)
    sysm = ForcedOscillator(ens, 4.0)
    s0 = pc_trajectory(sysm, 20 * T, sample_dt=T).final  # on the attractor
    x0 = dict(q0=s0.q, v0=s0.v, operator_state=s0.operator_state, phi0=s0.phi)
    a = pc_trajectory(sysm, T, sample_dt=T / 8, taylor=True, **x0)
    b = pc_trajectory(sysm, T, sample_dt=T / 8, taylor=False, **x0)
    assert a.switches.size == b.switches.size > 3000
    hops = np.diff(a.switches["time"])
    assert np.mean(hops < 1e-3) > 0.8  # the fast path is what is being tested
    np.testing.assert_allclose(a.switches["time"], b.switches["time"], rtol=0, atol=1e-11)
    np.testing.assert_allclose(a.switches["v"], b.switches["v"], rtol=0, atol=1e-11)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-11)
    jac_a = pc_jacobian(sysm, T, taylor=True, **x0)
    jac_b = pc_jacobian(sysm, T, taylor=False, **x0)
    np.testing.assert_allclose(jac_a, jac_b, rtol=1e-9, atol=1e-9 * np.abs(jac_b).max())
    det = np.linalg.det(jac_a[:2, :2])
    assert math.isclose(det, math.exp(-2 * ZETA * T), rel_tol=1e-9)


@pytest.mark.parametrize(
    "zeta, omega, c", [(0.05, 1.0, -4.0), (0.0, 1.3, 3.0), (0.05, 1.0, 10.0), (0.05, 0.3, 4.0)]
)
def test_short_hops_across_parameter_regimes(zeta, omega, c):
    """Negative feedback (chattering), no damping, strong coupling, slow forcing: the kernel with
    its short-hop paths gives the exact-propagator path's switches (two forcing periods)."""
    ens = SpinDimerEnsemble.random(20000, 2.0, 1.0, 2.0, seed=1)
    sysm = ForcedOscillator(ens, c, zeta, omega)
    period = 2 * math.pi / omega
    a = pc_trajectory(sysm, 2 * period, sample_dt=period / 4, taylor=True)
    b = pc_trajectory(sysm, 2 * period, sample_dt=period / 4, taylor=False)
    assert a.switches.size == b.switches.size > 200
    hops = np.diff(a.switches["time"])
    assert np.mean(hops < 1e-3 / max(1.0, omega)) > 0.3
    np.testing.assert_allclose(a.switches["time"], b.switches["time"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.switches["v"], b.switches["v"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-10)


def test_taylor_tables_against_the_exact_propagator():
    """The hop tables give q's Taylor coefficients as linear forms in (q, v, F, cos φ, sin φ);
    summed at h = 1e-2 they must reproduce the closed-form solution (truncation h^9/9! ~ 3e-24),
    for several damping ratios and forcing frequencies."""
    from oscillators.engines import _relay_kernels as kern
    from oscillators.linear import exact_step, particular_amplitudes

    rng = np.random.default_rng(5)
    h = 1e-2
    for zeta, omega in [(0.05, 1.0), (0.7, 0.4), (0.3, 2.3)]:
        tab = kern.taylor_matrix_coefficients(zeta, omega)
        amp_a, amp_b = particular_amplitudes(zeta, omega)
        for _ in range(20):
            q, v, phi, force = rng.uniform(-2, 2, size=4)
            c, s = math.cos(phi), math.sin(phi)
            e = tab[:, kern.TC_Q] * q + tab[:, kern.TC_V] * v + tab[:, kern.TC_F] * force
            e = e + tab[:, kern.TC_C] * c + tab[:, kern.TC_S] * s
            c1, s1 = math.cos(phi + omega * h), math.sin(phi + omega * h)
            q1, v1 = exact_step(q, v, c, s, c1, s1, force, h, zeta, omega, amp_a, amp_b)
            n = np.arange(e.size)
            assert abs(np.sum(e * h**n) - q1) < 1e-14
            assert abs(np.sum(n[1:] * e[1:] * h ** (n[1:] - 1)) - v1) < 1e-13
            # the propagator columns: Φ(h) = Σ A^n h^n / n!
            phi_h = (tab[:, :4] * (h**n)[:, None]).sum(axis=0)
            c0 = math.cos(phi)
            x = exact_step(1.0, 0.0, c0, s, c0, s, 0.0, h, zeta, omega, 0.0, 0.0)
            assert np.allclose(phi_h[[0, 2]], x, rtol=0, atol=1e-15)


def test_identical_thresholds_switch_together():
    fields = [[2.0, 0.0], [2.0, 0.0], [-0.5, -2.5]]
    sysm = dimer_system(fields, 1.5)
    traj = sysm.trajectory(10 * T, sample_dt=0.5)
    ref = brute_force_dimers(fields, 2.0, 1.5, 10 * T)
    assert_switches_match(traj, ref, 1e-8)
    # the two identical dimers flip in one event of size 2·(2/N)·2 = 4/3
    first_dimer_events = np.isclose(np.abs(traj.switches["jump"]), 4.0 / 3.0)
    assert first_dimer_events.sum() >= 4
    assert np.all(
        np.isclose(np.abs(traj.switches["jump"]), 4.0 / 3.0)
        | np.isclose(np.abs(traj.switches["jump"]), 2.0 / 3.0)
    )


def first_maximum_relay_down(c, t_end=10.0, q0=-1.0, v0=0.1):
    """Brute force: first maximum (t, q) of q with the relay output held at -1, and the solution."""

    def rhs(t, x):
        return [x[1], -2 * ZETA * x[1] - x[0] + math.cos(OMEGA * t) - c]

    def v_zero(t, x):
        return x[1]

    v_zero.direction = -1
    sol = solve_ivp(
        rhs,
        (0.0, t_end),
        [q0, v0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        events=[v_zero],
        dense_output=True,
    )
    return sol.t_events[0][0], sol.y_events[0][0][0], sol


@pytest.mark.parametrize("offset, switches", [(-1e-8, True), (1e-8, False)])
def test_grazing_maximum_against_brute_force(offset, switches):
    """A maximum that just reaches alpha switches the relay (u >= alpha); just short: no switch.

    Exact tangency (maximum == alpha in floating point) follows the same rule on the computed
    maximum: it switches up with v* = 0 (see ``oscillators.engines._relay_kernels``).
    """
    c = 1.0
    t_max, q_max, _ = first_maximum_relay_down(c)
    alpha = q_max + offset
    traj = ForcedOscillator(Relay(alpha, -50.0), c).trajectory(t_max + 0.5, sample_dt=0.25)
    if switches:
        assert traj.switches.size == 1
        assert abs(traj.switches["time"][0] - t_max) < 1e-3  # sqrt(2e-8/|q''|) away
        assert traj.switches["v"][0] > 0
    else:
        assert traj.switches.size == 0


def test_crossing_undone_inside_one_step_is_found():
    """q pokes above alpha for ~3e-3 time units only: the switch must still be found."""
    c = 1.0
    t_max, q_max, sol = first_maximum_relay_down(c)
    alpha = q_max - 1e-6
    from scipy.optimize import brentq

    t_ref = brentq(lambda t: sol.sol(t)[0] - alpha, t_max - 0.1, t_max, xtol=1e-14)
    traj = ForcedOscillator(Relay(alpha, alpha - 0.5), c).trajectory(t_max + 0.01, sample_dt=1.0)
    assert traj.switches.size >= 1
    assert abs(traj.switches["time"][0] - t_ref) < 1e-8
    assert traj.switches["jump"][0] == 2.0


def test_poincare_first_point_and_map_consistency():
    ens = SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, seed=5)
    sysm = ForcedOscillator(ens, 4.0)
    sec = sysm.poincare_section(5)
    assert sec.q[0] == -1.0 and sec.v[0] == 0.1
    assert abs(sec.M[0] - ens.output(ens.initial_state(-1.0))) < 1e-12
    state = OscillatorState(q=-1.0, v=0.1, phi=0.0, operator_state=ens.initial_state(-1.0))
    for i in range(1, 5):
        state = sysm.stroboscopic_map(state)
        assert abs(state.q - sec.q[i]) < 1e-12 and abs(state.v - sec.v[i]) < 1e-12
        assert abs(ens.output(state.operator_state) - sec.M[i]) < 1e-12
    assert abs(state.t - 4 * T) < 1e-12
    # the transient shifts the section
    sec2 = sysm.poincare_section(2, transient_periods=3)
    assert abs(sec2.q[0] - sec.q[3]) < 1e-12


def test_final_operator_state_is_consistent():
    ens = SpinDimerEnsemble.random(400, 2.0, 1.0, 2.0, seed=7)
    sysm = ForcedOscillator(ens, 4.0)
    traj = sysm.trajectory(3 * T)
    fin = traj.final
    assert abs(ens.output(fin.operator_state) - traj.M[-1]) < 1e-12
    # continuing from the final state equals one long run
    rest = sysm.trajectory(
        2 * T, q0=fin.q, v0=fin.v, operator_state=fin.operator_state, phi0=fin.phi
    )
    long = sysm.trajectory(5 * T)
    assert abs(rest.q[-1] - long.q[-1]) < 1e-9


def test_validation():
    ens = SpinDimerEnsemble.random(20, 2.0, 1.0, 2.0, seed=0)
    with pytest.raises(ValueError, match="damping_ratio"):
        ForcedOscillator(ens, 1.0, damping_ratio=-0.1)
    with pytest.raises(ValueError, match="frequency"):
        ForcedOscillator(ens, 1.0, frequency=0.0)
    with pytest.raises(ValueError, match="coupling"):
        ForcedOscillator(ens, float("nan"))
    sysm = ForcedOscillator(ens, 1.0)
    with pytest.raises(ValueError, match="t_end"):
        sysm.trajectory(-1.0)
    with pytest.raises(ValueError, match="n_periods"):
        sysm.poincare_section(0)
    # non-integer counts are rejected, not truncated
    with pytest.raises(ValueError, match="n_periods"):
        sysm.poincare_section(2.5)
    with pytest.raises(ValueError, match="transient_periods"):
        sysm.poincare_section(2, transient_periods=1.5)
    with pytest.raises(ValueError, match="transient_periods"):
        sysm.poincare_section(2, transient_periods=-1)
    # overdamped motion is fine for piecewise-constant operators (closed form for any ζ) ...
    ForcedOscillator(ens, 1.0, damping_ratio=1.5)
    # ... but rejected at construction for play-type operators (underdamped limit integrator)
    from hysteresis.play import GeneralizedPlay, PlayOperator

    for op in (GeneralizedPlay.erf(2.0, 1.0), PlayOperator(2.0)):
        with pytest.raises(ValueError, match="damping_ratio"):
            ForcedOscillator(op, 1.0, damping_ratio=1.0)


def test_final_phase_is_wrapped_to_zero_two_pi():
    """Negative phi0: the final phase is (phi0 + Ω t) mod 2π in [0, 2π), as on the play path."""
    sysm = ForcedOscillator(Relay(0.5, -0.5), 1.0, frequency=1.3)
    for phi0 in (-1.0, -7.5, 4.0):
        fin = sysm.trajectory(0.4, phi0=phi0).final
        expected = (phi0 + 1.3 * 0.4) % (2.0 * math.pi)
        assert 0.0 <= fin.phi < 2.0 * math.pi
        assert abs(fin.phi - expected) < 1e-12


def test_play_dispatch_uses_the_same_section_convention():
    """ForcedOscillator with a play: first section point = initial state, transient shifts."""
    from hysteresis.play import GeneralizedPlay

    sysm = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0)
    sec = sysm.poincare_section(4)
    assert sec.q[0] == -1.0 and sec.v[0] == 0.1 and sec.w[0] == -2.0
    assert abs(sec.M[0] - math.erf(-2.0 / math.sqrt(2.0))) < 1e-15
    sec2 = sysm.poincare_section(2, transient_periods=2)
    np.testing.assert_allclose(sec2.q, sec.q[2:], atol=1e-10)
    state = OscillatorState(-1.0, 0.1, 0.0, sysm.operator.initial_state(-1.0))
    nxt = sysm.stroboscopic_map(state)
    assert abs(nxt.q - sec.q[1]) < 1e-10 and abs(nxt.t - T) < 1e-12


def test_unequal_widths_generic_engine_matches_brute_force():
    """Dimers with different loop widths: relays do not nest, the generic engine is used."""
    rng = np.random.default_rng(11)
    centre = rng.normal(0.0, 1.0, 20)
    half = rng.uniform(0.25, 1.5, 20)
    alpha, beta = centre + half, centre - half
    j = 2.0
    fields = np.column_stack([j - alpha, -j - beta])  # alpha = J - b1, beta = -J - b2
    ens = SpinDimerEnsemble(fields, j)
    assert ens.relay_table().nested_plan() is None
    t_end = 10 * T
    traj = ForcedOscillator(ens, 3.0).trajectory(t_end, sample_dt=0.5)
    ref = brute_force_dimers(fields, j, 3.0, t_end)
    assert ref.shape[0] >= 50
    assert_switches_match(traj, ref, 1e-8)
