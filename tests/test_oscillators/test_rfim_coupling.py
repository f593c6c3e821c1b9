"""The oscillator coupled to a random-field Ising lattice — the compiled switching engine
(``compiled_switching()``: sorted lists, the relay kernel's hops) and the relay engine's Python
reference path (``method="generic"``: ``switching()``/``apply()``) — against an independent
integrator written here (solve_ivp between avalanches, the next trigger inputs and the
relaxation by brute force over all spins) and against invariants: the dimers' kernel on a
pairs graph, a known flip count, the Jacobian by central differences, Σλ = −2ζ, periodic orbits
(det of the monodromy matrix) and basins."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from analysis.dynamics.basin_map import BasinGrid
from analysis.dynamics.basins import basins
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import Relay, SpinDimerEnsemble
from hysteresis.algebra import SwitchingSum
from hysteresis.rfim import RandomFieldIsing
from oscillators import ForcedOscillator
from oscillators.engines.relay import RelayReferenceEngine
from oscillators.engines.switching import SwitchingKernelEngine
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
    """Avalanche events (time, q, v, ΔM, spins flipped), the state at ``samples`` (times) and the
    final spins
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
        before = s
        if sol.t_events[0].size:
            t, x = sol.t_events[0][0], sol.y_events[0][0].copy()
            s = relax(s, upper, f, e, J)
        else:
            t, x = sol.t_events[1][0], sol.y_events[1][0].copy()
            s = relax(s, math.nextafter(lower, -math.inf), f, e, J)
        events.append((t, x[0], x[1], float(np.mean(s)) - m, int(np.sum(s != before))))
    return np.array(events).reshape(-1, 5), np.array(states).reshape(-1, 3), s


def start(q0=-1.0, v0=0.1):
    return OscillatorState(q=q0, v=v0, phi=0.0, operator_state=None, t=0.0)


def lattice():
    return RandomFieldIsing.lattice((6, 6, 6), 3.5, seed=3)


# -- exactness -------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["auto", "generic"])
@pytest.mark.parametrize("coupling", [2.9, 4.0])
def test_trajectory_and_section_match_the_independent_integrator(coupling, method):
    """Every avalanche (time, q, v, ΔM) over 8 periods, the final spins and the section, for the
    compiled engine and the reference path; the bound 1e-8 is the solver's (rtol = atol =
    1e-12 over ~250 segments); measured 1.7e-13. ``n_events``: spin flips (compiled), avalanches
    (reference)."""
    model = lattice()
    system = ForcedOscillator(model, coupling, ZETA, OMEGA)
    t_end = 8 * T
    ref, ref_states, spins = brute_force(model, coupling, t_end, samples=T * np.arange(1, 8))
    eng = system.engine(start(), method=method)
    assert isinstance(eng, SwitchingKernelEngine if method == "auto" else RelayReferenceEngine)
    eng.advance(np.array([t_end]), record=True)
    sw = eng.records()["switches"]
    assert ref.shape[0] >= 200 and sw.size == ref.shape[0]
    flips = int(ref[:, 4].sum()) if method == "auto" else ref.shape[0]
    assert flips > sw.size or method == "generic"
    assert eng.n_events == flips and eng.records()["slides"].size == 0
    for j, name in enumerate(("time", "q", "v")):
        np.testing.assert_allclose(sw[name], ref[:, j], rtol=0, atol=1e-8)
    np.testing.assert_allclose(sw["jump"], ref[:, 3], rtol=0, atol=1e-14)
    np.testing.assert_array_equal(model.spins(eng.state().operator_state), spins)
    # the Poincaré section (φ = 0: t = T, ..., 7T) is the reference's state there
    section = system.poincare_section(8, 1, q0=-1.0, v0=0.1, engine_options={"method": method})
    np.testing.assert_allclose(section.q[:7], ref_states[:, 1], rtol=0, atol=1e-8)
    np.testing.assert_allclose(section.v[:7], ref_states[:, 2], rtol=0, atol=1e-8)


def test_ties_and_a_general_graph_match_the_independent_integrator():
    """Exact ties (fields on a 1/4 grid, J = 1/2: many spins share a trigger and flip in one
    event) on a 2-D lattice, and a random graph of degrees 0–9 (compressed rows): the compiled
    engine against the brute force, as above."""
    rng = np.random.default_rng(7)
    tied = RandomFieldIsing.lattice((8, 8), 1.5, spin_coupling=0.5, seed=2)
    tied = RandomFieldIsing(np.round(np.asarray(tied.fields) * 4) / 4, tied.edges(), 0.5)
    pairs = np.unique(np.sort(rng.integers(0, 120, (300, 2)), axis=1), axis=0)
    graph = RandomFieldIsing(rng.normal(0, 2.5, 120), pairs[pairs[:, 0] != pairs[:, 1]], 0.7)
    for model in (tied, graph):
        ref, _, spins = brute_force(model, 2.9, 6 * T)
        eng = ForcedOscillator(model, 2.9, ZETA, OMEGA).engine(start())
        eng.advance(np.array([6 * T]), record=True)
        sw = eng.records()["switches"]
        assert sw.size == ref.shape[0] >= 50 and eng.n_events == int(ref[:, 4].sum())
        for j, name in enumerate(("time", "q", "v", "jump")):
            np.testing.assert_allclose(sw[name], ref[:, j], rtol=0, atol=1e-8)
        np.testing.assert_array_equal(model.spins(eng.state().operator_state), spins)
    assert np.max(ref[:, 4]) >= 1  # the graph too flips in avalanches


def test_n_switches_counts_spin_flips():
    """A weak lattice (R = 0.3, J = 0.2: every threshold within ±2.5) in an oscillation of
    amplitude ≈ 10 (ζ = 0.05 at resonance, C = 0.1): every spin flips up and down once per
    period, so a section of k periods counts exactly 2·N·k flips."""
    model = RandomFieldIsing.lattice((5, 5, 5), 0.3, spin_coupling=0.2, seed=1)
    system = ForcedOscillator(model, 0.1, ZETA, OMEGA)
    state = system.initial_state(-10.0, 0.0)
    # sampled at 2T, 3T, 4T: four whole periods integrated
    section = system.poincare_section(3, 2, operator_state=state.operator_state, q0=-10.0, v0=0.0)
    assert section.n_switches == 2 * model.n_spins * 4
    assert np.all(section.M == -1.0)  # all down again at every section point
    eng = system.engine(state, method="generic")  # the reference counts avalanches
    eng.advance(np.array([4 * T]), record=True)
    jumps = eng.records()["switches"]["jump"]
    assert round(float(np.abs(jumps).sum()) * model.n_spins / 2) == 2 * model.n_spins * 4
    assert eng.n_events == jumps.size < 2 * model.n_spins * 4


def test_pairs_graph_couples_like_the_dimers_kernel():
    """A pairs graph is the dimer ensemble: the compiled switching engine (and the Python path)
    gives the nested relay kernel's switches (a dimer's two spins flip as one avalanche: one
    switch, two flips)."""
    ens = SpinDimerEnsemble.random(200, width=1.0, spread=1.0, spin_coupling=1.0, seed=5)
    pairs = np.arange(ens.n_spins).reshape(-1, 2)
    model = RandomFieldIsing(ens.fields.reshape(-1), pairs, 1.0)
    runs = []
    for op, method in ((model, "auto"), (model, "generic"), (ens, "auto")):
        eng = ForcedOscillator(op, 2.9, ZETA, OMEGA).engine(start(), method=method)
        eng.advance(np.array([10 * T]), record=True)
        runs.append((eng, eng.records()["switches"]))
    b_eng, b = runs[-1]
    assert b_eng.method == "nested" and b.size >= 500
    for a_eng, a in runs[:2]:
        assert a.size == b.size
        for name in ("time", "q", "v"):
            np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-9)
        np.testing.assert_allclose(a["jump"], b["jump"], rtol=0, atol=1e-14)
        assert a_eng.state().q == pytest.approx(b_eng.state().q, abs=1e-9)
    flips = round(float(np.abs(b["jump"]).sum()) * ens.n_spins / 2)
    assert runs[0][0].n_events == flips


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
    assert system.engine_class is SwitchingKernelEngine
    assert system.engine().method == "compiled"
    assert isinstance(system.engine(method="generic"), RelayReferenceEngine)
    for method in ("nested", "heap"):
        with pytest.raises(ValueError, match="needs a relay table; RandomFieldIsing has none"):
            system.engine(method=method)
    with pytest.raises(AttributeError, match="relay_outputs"):
        system.engine().relay_outputs()  # no relay table: the engine's state() holds the spins
    # a lattice plus a relay (weights >= 0) is piecewise constant without a table or spins:
    # the reference path
    mixed = 0.8 * model + 0.2 * Relay(0.5, -0.5)
    assert isinstance(mixed, SwitchingSum) and not mixed.has_relay_table
    assert mixed.n_units == model.n_spins + 1 and mixed.compiled_switching() is None
    eng = ForcedOscillator(mixed, 2.9).engine(start())
    assert isinstance(eng, RelayReferenceEngine)
    eng.advance(np.array([4 * T]), record=True)
    assert eng.n_events > 50
    with pytest.raises(ValueError, match="periodic orbits of SwitchingSum are not computed"):
        StateCoordinates(ForcedOscillator(mixed, 2.9), ForcedOscillator(mixed, 2.9).initial_state())


# -- periodic orbits and basins --------------------------------------------------------------------
def test_periodic_orbit_of_a_lattice():
    """C = 2.9: a period-5 orbit, the spins carried as the template's memory (as a relay
    configuration). Checked independently: the reference path from the orbit's start returns
    to it after 5T (same spins), and det of the monodromy matrix is exp(−2ζ·5T) (saltations
    have det 1)."""
    model = lattice()
    system = ForcedOscillator(model, 2.9, ZETA, OMEGA)
    orbit = find_periodic_orbit(
        system, system.initial_state(-1.0, 0.1), transient=200, max_period=8
    )
    assert orbit.period == 5 and orbit.stable
    start_state = orbit.states[0]
    eng = system.engine(start_state, method="generic")
    eng.advance(np.array([5 * T]))
    end = eng.state()
    assert abs(end.q - start_state.q) < 1e-8 and abs(end.v - start_state.v) < 1e-8
    np.testing.assert_array_equal(
        model.spins(end.operator_state), model.spins(start_state.operator_state)
    )
    det = float(np.prod(orbit.multipliers).real)
    assert det == pytest.approx(math.exp(-2 * ZETA * 5 * T), rel=1e-8)
    coords = StateCoordinates(system, start_state)
    assert coords.kind == "spins" and coords.configuration(start_state)[0][0] == "spins"


def test_basins_of_a_lattice():
    """A 3×3 grid of starts: every start is classified (no undecided ones), the attractors are
    periodic — the period-5 orbit above, and a period-19 orbit from (q0, v0) = (2, −1)."""
    system = ForcedOscillator(lattice(), 2.9, ZETA, OMEGA)
    result = basins(
        system, BasinGrid((-2.0, 2.0), (-1.0, 1.0), 3), transient=200, periods=64, max_period=32
    )
    kinds = {a["kind"] for a in result.attractors}
    assert kinds <= {"periodic"} and np.all(np.asarray(result.labels) >= 0)
    assert {a["period"] for a in result.attractors} == {5, 19}
