"""Jiles–Atherton (a Duhem operator in ``z = M_irr``) against independent truths: ``c = 1`` is the
anhysteretic curve, ``k → 0`` with ``α = 0`` tracks it by a closed-form expansion, the
ill-posed point of a linearised virgin curve, the odd settled major loop, the compiled ``apply``
against the ``solve_ivp`` path, and the coupled oscillator against an event-driven integration
of ``(q, v, M_irr)`` written here."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hysteresis import JilesAtherton
from hysteresis.duhem import Duhem
from hysteresis.jiles_atherton import JilesAthertonInstability
from oscillators import ForcedOscillator

STEEL = dict(ms=1.6e6, a=1100.0, k=400.0, c=0.2, alpha=1.6e-3)  # SI, a transformer steel


def _langevin(x):
    return 1.0 / math.tanh(x) - 1.0 / x


def test_signature_attributes_and_demagnetised_state():
    ja = JilesAtherton(1.0, 0.5, 0.4, 0.2, 0.3)
    assert (ja.ms, ja.a, ja.k, ja.c, ja.alpha) == (1.0, 0.5, 0.4, 0.2, 0.3)
    state = ja.state(0.0, 0.0)
    assert ja.output(state) == 0.0  # M = 0 at H = 0 with M_irr = 0 (M_an(0) = 0)
    with pytest.raises(ValueError, match="irreversible"):
        ja.state(1.0, 0.0)


def test_c_one_is_the_anhysteretic_curve():
    """``c = 1``: ``M = M_an(H + αM)`` at every H, whatever M_irr does."""
    ja = JilesAtherton(**{**STEEL, "c": 0.999999999})  # αc·ms/(3a) < 1 needs no more than α·ms
    exact = JilesAtherton(**{**STEEL, "c": 1.0})
    h = np.concatenate([np.linspace(-3000.0, 3000.0, 61), np.linspace(3000.0, -500.0, 36)])
    m, _ = exact.apply(h)
    for x, y in zip(h, m, strict=True):
        assert y == pytest.approx(exact.anhysteretic(x), rel=0, abs=1e-13 * exact.ms)
        # and the anhysteretic value solves its own equation, written out here
        he = (x + exact.alpha * y) / exact.a
        assert y == pytest.approx(exact.ms * _langevin(he), rel=0, abs=1e-13 * exact.ms)
    m_near, _ = ja.apply(h)  # c → 1 from below: O(1 − c) away
    np.testing.assert_allclose(m_near, m, rtol=0, atol=1e-8 * ja.ms)


def test_small_k_tracks_the_anhysteretic_curve_in_closed_form():
    """α = 0, c = 0: ``dM/dH = (M_an(H) − M)/k`` rising (δ_M = 1 below the curve), whose slow
    solution is ``M = M_an − k·M_an' + k²·M_an'' + O(k³·max|M_an'''|)`` (``|L'''| <= 2/15``);
    the start's offset decays like ``exp(−ΔH/k)``."""
    ms, a, k = 1.0, 1.0, 0.01
    ja = JilesAtherton(ms=ms, a=a, k=k, c=0.0, alpha=0.0)
    h = np.concatenate([[-10.0], np.linspace(-3.0, 3.0, 121)])
    h = h[np.abs(h) > 0.04]  # the closed forms below cancel near 0
    m, _ = ja.apply(h, ja.state(ms * _langevin(-10.0), -10.0))

    def slow(x):
        lv = _langevin(x)
        l1 = 1.0 / x**2 - 1.0 / math.sinh(x) ** 2
        l2 = -2.0 / x**3 + 2.0 * math.cosh(x) / math.sinh(x) ** 3
        return ms * (lv - k * l1 / a + k**2 * l2 / a**2)

    expected = np.array([slow(x / a) for x in h[1:]])
    np.testing.assert_allclose(m[1:], expected, rtol=0, atol=2.0 * k**3 * (2 / 15) * ms / a**3)


def test_ill_posed_where_the_linearised_virgin_curve_says():
    """c = 0 and ``α·s = 2`` (``s = ms/(3a)``, the initial anhysteretic slope) from the
    demagnetised state: with ``k ≪ a`` the Langevin function is linear, ``x = He``,
    ``M_irr = s·x − s·k(1 − e^{−x/k})``, ``χ_irr = s(1 − e^{−x/k})``, and ``1 − αχ_irr = 0`` at
    ``x* = k·ln 2``, i.e. ``H* = x* − α·M_irr = k(1 − ln 2)`` (relative error ~(x*/a)² from
    the linearisation)."""
    ms, a, k = 1.0, 1.0, 1e-3
    alpha = 2.0 * 3.0 * a / ms
    ja = JilesAtherton(ms=ms, a=a, k=k, c=0.0, alpha=alpha)
    h_star = k * (1.0 - math.log(2.0))
    for run in (ja.apply, lambda u, s: Duhem.apply(ja, u, s)):  # compiled and solve_ivp
        with pytest.raises(JilesAthertonInstability) as info:
            run(np.linspace(0.0, 10 * k, 11), ja.state(0.0, 0.0))
        assert info.value.field == pytest.approx(h_star, rel=1e-4)
        message = str(info.value)
        assert "\n" not in message and "alpha=6.0" in message and "k=0.001" in message
    # just before it the model is well-posed and the slope large and positive
    m, _ = ja.apply([0.0, 0.99 * h_star], ja.state(0.0, 0.0))
    assert 0.0 < ja.slope(0.99 * h_star, m[-1], 1) < math.inf


def test_ill_posed_state_raises_at_its_own_field():
    """c = 0, M_irr = −0.9, H = 0.3 rising: ``α(M_an − M_irr)/k = 0.2·(L(0.12) + 0.9)/0.1 =
    1.88 > 1`` at the start."""
    ja = JilesAtherton(ms=1.0, a=1.0, k=0.1, c=0.0, alpha=0.2)
    assert 0.2 * (_langevin(0.3 - 0.18) + 0.9) / 0.1 > 1.0
    with pytest.raises(JilesAthertonInstability) as info:
        ja.apply([0.5], ja.state(-0.9, 0.3))
    assert info.value.field == 0.3
    with pytest.raises(JilesAthertonInstability):
        ja.slope(0.3, -0.9, 1)
    assert ja.apply([0.1], ja.state(-0.9, 0.3))[0][0] < 0.0  # falling: δ_M = 0, fine


def test_settled_major_loop_is_odd_and_coercive():
    """On the settled major loop M↓(−H) = −M↑(H) (the model is odd), with a coercive field of
    the order of k and a remanence."""
    ja = JilesAtherton(**STEEL)
    h_up = np.linspace(-6000.0, 6000.0, 1201)
    cycle = np.concatenate([h_up, h_up[::-1][1:]])
    _, settled = ja.apply(cycle)
    m, _ = ja.apply(cycle, settled)
    m_up, m_down = m[:1201], m[1200:]
    np.testing.assert_allclose(m_down, -m_up, rtol=0, atol=1e-9 * ja.ms)
    coercive = h_up[np.flatnonzero(np.diff(np.sign(m_up)))[0]]
    assert 0.3 * ja.k < coercive < 3.0 * ja.k
    assert m_up[600] < -0.1 * ja.ms


def test_compiled_apply_matches_the_solve_ivp_path():
    """Two integrators (DOP853 at 1e-12 with dense output; Dormand–Prince 5(4) at 1e-12 per
    step): both a few 1e-12 of ms per unit loop, so 1e-10·ms over a few loops."""
    ja = JilesAtherton(**STEEL)
    u = 5000.0 * np.sin(np.linspace(0.0, 6 * np.pi, 900)) * np.linspace(1.0, 0.3, 900)
    start = ja.initial_state(0.0)
    fast, end = ja.apply(u, start)
    slow, end_slow = Duhem.apply(ja, u, start)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-10 * ja.ms)
    assert end.z == pytest.approx(end_slow.z, abs=1e-10 * ja.ms) and end.input == u[-1]
    # continuation from a returned state is one long call; resampling changes nothing
    first, mid = ja.apply(u[:400], start)
    second, _ = ja.apply(u[400:], mid)
    np.testing.assert_allclose(np.concatenate([first, second]), fast, rtol=0, atol=1e-11 * ja.ms)
    fine = np.sort(
        np.concatenate([np.linspace(-3000.0, 3000.0, 7), np.linspace(-3000, 3000, 5000)])
    )
    coarse, _ = ja.apply(fine[::1000], ja.initial_state(-3000.0))
    dense, _ = ja.apply(fine, ja.initial_state(-3000.0))
    np.testing.assert_allclose(coarse, dense[::1000], rtol=0, atol=1e-11 * ja.ms)


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("ms", 0.0, "ms"),
        ("a", -1.0, "a"),
        ("k", 0.0, "k"),
        ("c", 1.1, "c must lie in"),
        ("alpha", -0.1, "alpha must be >= 0"),
        ("alpha", 2.0, "alpha·c·ms/\\(3a\\) must be < 1"),
    ],
)
def test_bad_parameters_are_one_line_errors(name, value, message):
    with pytest.raises(ValueError, match=message) as info:
        JilesAtherton(**{**{**STEEL, "c": 0.5, "alpha": 1e-3}, name: value})
    assert "\n" not in str(info.value)


# -- coupled to the oscillator ------------------------------------------------------------------
ZETA, OMEGA, COUPLING = 0.1, 1.0, 0.5
UNIT = JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.3)  # in units of the oscillator's q


def _reference(times, q0, v0, m0):
    """``(q, v, M_irr)`` by solve_ivp in t (DOP853, 1e-12) with ``Ṁ_irr = v·g_{sign v}(q,
    M_irr)``, the force ``C·M(q, M_irr)`` and the direction flipped at the events ``v = 0``; g
    and M are the compiled functions (tested in test_duhem_kernels.py): this checks the coupling
    and the engine."""
    t, y, d = 0.0, np.array([q0, v0, m0]), 1 if v0 > 0 else -1
    out, done = np.empty((times.size, 3)), 0
    while done < times.size:

        def rhs(s, x, d=d):
            force = COUPLING * UNIT.map_output(x[0], x[2])
            acc = -2 * ZETA * x[1] - x[0] + math.cos(OMEGA * s) + force
            return [x[1], acc, x[1] * UNIT.slope(x[0], x[2], d)]

        def reversal(s, x):
            return x[1]

        reversal.terminal, reversal.direction = True, -d
        sol = solve_ivp(rhs, (t, times[-1]), y, method="DOP853", dense_output=True,
                        events=[reversal], rtol=1e-12, atol=1e-12)  # fmt: skip
        upto = np.searchsorted(times, sol.t[-1], side="right") if sol.status == 1 else times.size
        out[done:upto] = sol.sol(times[done:upto]).T
        done = upto
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            y[1], d = 0.0, -d
    return out


def test_coupled_trajectory_matches_an_independent_integration():
    system = ForcedOscillator(UNIT, coupling=COUPLING, damping_ratio=ZETA, frequency=OMEGA)
    state = UNIT.state(0.1, 0.2)
    traj = system.trajectory(30.0, q0=0.2, v0=0.4, operator_state=state, sample_dt=0.5)
    ref = _reference(traj.t, 0.2, 0.4, 0.1)
    m_ref = np.array([UNIT.map_output(q, m) for q, m in ref[:, [0, 2]]])
    # both at 1e-12 over ~10 reversals: ~1e-10; 1e-7 leaves room for the event timing
    np.testing.assert_allclose(traj.q, ref[:, 0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(traj.M, m_ref, rtol=0, atol=1e-7)


def test_coupled_virgin_curve_from_the_demagnetised_state():
    """From ``state(0.0, 0.0)`` the gap ``M_an − M_irr`` is exactly 0 and opens as soon as H
    moves (``d·dG/dH = M_an'/D > 0`` with M_irr frozen): δ_M switches on at once, which the
    engine must not miss (M_irr would stay 0). Against the independent integration."""
    system = ForcedOscillator(UNIT, coupling=COUPLING, damping_ratio=ZETA, frequency=OMEGA)
    state = UNIT.state(0.0, 0.0)
    traj = system.trajectory(10.0, q0=0.0, v0=0.4, operator_state=state, sample_dt=0.25)
    ref = _reference(traj.t, 0.0, 0.4, 0.0)
    assert ref[4, 2] > 0.01  # the virgin curve: M_irr grew on the first rise
    m_ref = np.array([UNIT.map_output(q, m) for q, m in ref[:, [0, 2]]])
    np.testing.assert_allclose(traj.q, ref[:, 0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(traj.M, m_ref, rtol=0, atol=1e-7)
    assert traj.final.operator_state.z == pytest.approx(ref[-1, 2], abs=1e-7)
