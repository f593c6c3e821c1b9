"""The oscillator coupled to a random-field Ising lattice (no relay table: the relay engine's
Python reference path through ``switching()``/``apply()``), against an independent integrator
written here — solve_ivp between avalanches, the next trigger inputs and the relaxation by
brute force over all spins — and against invariants: the dimers' kernel on a pairs graph, the
Jacobian by central differences, Σλ = −2ζ."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from hysteresis import Relay, SpinDimerEnsemble
from hysteresis.algebra import SwitchingSum
from hysteresis.rfim import RandomFieldIsing
from oscillators import ForcedOscillator
from oscillators.engines.relay import RelayReferenceEngine
from oscillators.results import OscillatorState

ZETA, OMEGA, T = 0.05, 1.0, 2.0 * math.pi


# -- the independent integrator --------------------------------------------------------------------
def neighbour_sums(edges, s):
    n = np.zeros(s.size, dtype=np.int64)
    np.add.at(n, edges[:, 0], s[edges[:, 1]])
    np.add.at(n, edges[:, 1], s[edges[:, 0]])
    return n


def relax(s, u, f, edges, J):
    """Flip every spin against h = u + (f + J n) (h = 0: up) until none is left."""
    s = s.copy()
    while True:
        bad = ((u + (f + J * neighbour_sums(edges, s))) >= 0.0) != (s > 0)
        if not bad.any():
            return s
        s[bad] = -s[bad]


def brute_force(model, coupling, t_end, q0=-1.0, v0=0.1, samples=()):
    """Avalanche events (time, q, v, ΔM), the state at ``samples`` (times) and the final spins
    of q'' + 2ζq' + q = cos Ωt + C·M, M the mean spin: DOP853 at rtol = atol = 1e-12 with
    terminal events at the next trigger inputs, found over all spins; an avalanche relaxed at
    its trigger by flipping spins by hand."""
    f, e, J = np.asarray(model.fields), model.edges(), model.spin_coupling
    s = relax(-np.ones(model.n_spins, dtype=np.int64), q0, f, e, J)
    t, x = 0.0, np.array([q0, v0])
    events, states = [], []
    samples = np.asarray(samples, dtype=float)
    while t < t_end:
        m = float(np.mean(s))
        thr = -(f + J * neighbour_sums(e, s))
        upper = thr[s < 0].min() if np.any(s < 0) else np.inf
        lower = thr[s > 0].max() if np.any(s > 0) else -np.inf

        def rhs(tt, y, m=m):
            return [y[1], -2 * ZETA * y[1] - y[0] + math.cos(OMEGA * tt) + coupling * m]

        def ev_up(tt, y, a=upper):
            return y[0] - a

        def ev_down(tt, y, b=lower):
            return y[0] - b

        ev_up.terminal = ev_down.terminal = True
        ev_up.direction, ev_down.direction = 1, -1
        sol = solve_ivp(
            rhs, (t, t_end), x, method="DOP853", rtol=1e-12, atol=1e-12, max_step=0.05,
            events=[ev_up, ev_down], dense_output=True,
        )  # fmt: skip
        t_stop = sol.t[-1]
        for ts in samples[(samples >= t) & (samples < t_stop)]:
            states.append((ts, *sol.sol(ts)))
        if sol.status != 1:
            break
        if sol.t_events[0].size:
            t, x = sol.t_events[0][0], sol.y_events[0][0].copy()
            s = relax(s, upper, f, e, J)
        else:
            t, x = sol.t_events[1][0], sol.y_events[1][0].copy()
            s = relax(s, math.nextafter(lower, -math.inf), f, e, J)
        events.append((t, x[0], x[1], float(np.mean(s)) - m))
    return np.array(events).reshape(-1, 4), np.array(states).reshape(-1, 3), s


def start(q0=-1.0, v0=0.1):
    return OscillatorState(q=q0, v=v0, phi=0.0, operator_state=None, t=0.0)


def lattice():
    return RandomFieldIsing.lattice((6, 6, 6), 3.5, seed=3)


# -- exactness -------------------------------------------------------------------------------------
@pytest.mark.parametrize("coupling", [2.9, 4.0])
def test_trajectory_and_section_match_the_independent_integrator(coupling):
    """Every avalanche (time, q, v, ΔM) over 8 periods, the final spins and the section; the
    bound 1e-8 is the solver's (rtol = atol = 1e-12 over ~250 segments); measured 1.3e-13."""
    model = lattice()
    system = ForcedOscillator(model, coupling, ZETA, OMEGA)
    t_end = 8 * T
    ref, ref_states, spins = brute_force(model, coupling, t_end, samples=T * np.arange(1, 8))
    eng = system.engine(start())
    assert isinstance(eng, RelayReferenceEngine)
    eng.advance(np.array([t_end]), record=True)
    sw = eng.records()["switches"]
    assert ref.shape[0] >= 200 and sw.size == ref.shape[0]
    assert eng.n_events == sw.size and eng.records()["slides"].size == 0
    for j, name in enumerate(("time", "q", "v")):
        np.testing.assert_allclose(sw[name], ref[:, j], rtol=0, atol=1e-8)
    np.testing.assert_allclose(sw["jump"], ref[:, 3], rtol=0, atol=1e-14)
    np.testing.assert_array_equal(model.spins(eng.state().operator_state), spins)
    # the Poincaré section (φ = 0: t = T, ..., 7T) is the reference's state there
    section = system.poincare_section(8, 1, q0=-1.0, v0=0.1)
    np.testing.assert_allclose(section.q[:7], ref_states[:, 1], rtol=0, atol=1e-8)
    np.testing.assert_allclose(section.v[:7], ref_states[:, 2], rtol=0, atol=1e-8)


def test_pairs_graph_couples_like_the_dimers_kernel():
    """A pairs graph is the dimer ensemble: the Python path through avalanches gives the nested
    relay kernel's switches (a dimer's two spins flip as one avalanche: one switch)."""
    ens = SpinDimerEnsemble.random(200, width=1.0, spread=1.0, spin_coupling=1.0, seed=5)
    pairs = np.arange(ens.n_spins).reshape(-1, 2)
    model = RandomFieldIsing(ens.fields.reshape(-1), pairs, 1.0)
    runs = []
    for op in (model, ens):
        eng = ForcedOscillator(op, 2.9, ZETA, OMEGA).engine(start())
        eng.advance(np.array([10 * T]), record=True)
        runs.append((eng, eng.records()["switches"]))
    (a_eng, a), (b_eng, b) = runs
    assert b_eng.method == "nested" and a.size == b.size >= 500
    for name in ("time", "q", "v"):
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-9)
    np.testing.assert_allclose(a["jump"], b["jump"], rtol=0, atol=1e-14)
    assert a_eng.state().q == pytest.approx(b_eng.state().q, abs=1e-9)


# -- tangent flow ----------------------------------------------------------------------------------
def test_jacobian_matches_central_differences():
    """Saltation C·ΔM/v* of whole avalanches (48 of them): the flow map's Jacobian against
    central differences (step 1e-6: truncation ~h²·|D³φ| and rounding ~1e-16·|x|/h, each about
    1e-9; measured 2.4e-9; the avalanche sequence is unchanged within ±h)."""
    system = ForcedOscillator(lattice(), 2.9, ZETA, OMEGA)
    state = system.initial_state(-1.0, 0.1)
    jac, _ = system.jacobian(1.5 * T, state, False)
    h = 1e-6
    cols = []
    for dq, dv in ((h, 0.0), (0.0, h)):
        ends = []
        for sign in (1, -1):
            s = system.initial_state(-1.0 + sign * dq, 0.1 + sign * dv, state.operator_state)
            eng = system.engine(s)
            eng.advance(np.array([1.5 * T]))
            ends.append(np.array([eng.state().q, eng.state().v]))
        cols.append((ends[0] - ends[1]) / (2 * h))
    np.testing.assert_allclose(jac[:2, :2], np.column_stack(cols), rtol=0, atol=1e-7)


def test_lyapunov_spectrum_sums_to_minus_two_zeta():
    """Every saltation matrix has determinant 1, so Σλ over (q, v) is −2ζ (to rounding)."""
    system = ForcedOscillator(lattice(), 2.9, ZETA, OMEGA)
    res = lyapunov_spectrum(system, 30 * T, 5 * T)
    assert res.exponents.size == 2
    assert float(np.sum(res.exponents)) == pytest.approx(-2 * ZETA, abs=1e-9)


# -- the contract at the engine seam ---------------------------------------------------------------
def test_engine_choice_and_a_sum_with_a_lattice():
    model = lattice()
    system = ForcedOscillator(model, 2.9)
    assert system.engine_class.__name__ == "RelayEngine"
    assert isinstance(system.engine(method="generic"), RelayReferenceEngine)
    for method in ("nested", "heap"):
        with pytest.raises(ValueError, match="needs a relay table; RandomFieldIsing has none"):
            system.engine(method=method)
    with pytest.raises(AttributeError, match="relay_outputs"):
        system.engine().relay_outputs()  # no relay table: the engine's state() holds the spins
    # a lattice plus a relay (weights >= 0) is piecewise constant without a table
    mixed = 0.8 * model + 0.2 * Relay(0.5, -0.5)
    assert isinstance(mixed, SwitchingSum) and not mixed.has_relay_table
    assert mixed.n_units == model.n_spins + 1
    eng = ForcedOscillator(mixed, 2.9).engine(start())
    eng.advance(np.array([4 * T]), record=True)
    assert eng.n_events > 50


def test_periodic_orbits_are_refused_in_one_sentence():
    """Not built yet: a lattice's spins are no relay configuration to compare (the orbit
    finder's coordinates refuse them, named)."""
    system = ForcedOscillator(lattice(), 2.9)
    with pytest.raises(ValueError, match="RandomFieldIsing are not computed yet"):
        StateCoordinates(system, system.initial_state())
