"""The generic continuous engine (oscillators.engines.continuous) against independent truths.

* the compiled play-limit kernel (``PlayEngine``, an independent implementation) through the
  public API (``ForcedOscillator`` picks the engine, ``lyapunov_spectrum``): a user-supplied erf
  shape and a one-play Prandtl–Ishlinskii operator give its sections and its tangent flow;
* central finite differences of the engine's own flow map (state-only runs, no tangent code)
  for the tangent flow across reversals, wall hits and wipe-outs, perturbing q, v, φ and every
  memory variable;
* C = 0: the oscillator decouples, its exponents are exactly −ζ (closed form).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import gauss_everett_model
from scipy.special import erf

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import GeneralizedPlay, PlayOperator, PrandtlIshlinskii
from oscillators.engines import (
    CompiledContinuousEngine,
    ContinuousEngine,
    DivergenceError,
    PlayEngine,
)
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA = 0.05
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
#: the generic engine also for operators that have the compiled one (this file tests the former)
GENERIC = {"method": "generic"}


class _GenericPlay(GeneralizedPlay):
    """A user shape without its compiled description: a custom shape would otherwise run on
    the compiled play kernel as a table (hysteresis.shape_table); these tests are about the
    generic engine."""

    def compiled_play(self):
        return None


def _erf_play_custom(width=2.0, spread=1.0):
    scale = math.sqrt(2.0) * spread
    norm = math.sqrt(2.0 / math.pi) / spread
    return _GenericPlay(
        width,
        lambda w: erf(np.asarray(w) / scale),
        lambda w: norm * np.exp(-0.5 * (np.asarray(w) / spread) ** 2),
    )


def _tanh_play(width=2.0):
    return _GenericPlay(
        width, lambda w: np.tanh(np.asarray(w)), lambda w: 1.0 / np.cosh(np.asarray(w)) ** 2
    )


def _pi5():
    return PrandtlIshlinskii([0.0, 0.5, 1.0, 2.0, 3.0], [0.15, 0.2, 0.25, 0.2, 0.2])


def _preisach_analytic(scale=1.3, lower=-6.0, upper=6.0):
    """Product density ∝ φ(α)φ(β) with closed-form Everett and gradient (relay_test_support)."""
    return gauss_everett_model(scale, lower, upper)


def _start(op, q0=-1.0, v0=0.1, phi0=0.0, operator_state=None):
    if operator_state is None:
        operator_state = op.initial_state(q0)
    return OscillatorState(q0, v0, phi0, operator_state)


def _engine(op, coupling, state=None, **options):
    options.setdefault("rtol", 1e-12)
    options.setdefault("atol", 1e-12)
    system = ForcedOscillator(op, coupling, ZETA, 1.0)
    return ContinuousEngine(system, _start(op) if state is None else state, **options)


def _section(engine, n_periods):
    times = np.arange(n_periods) * 2.0 * math.pi
    out = np.empty((n_periods, len(engine.sample_columns)))
    engine.advance(times, out)
    return out


# ------------------------------------------------------------------------------------------
# agreement with the compiled play kernel
# ------------------------------------------------------------------------------------------
def test_custom_erf_shape_gives_the_compiled_erf_section():
    compiled = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0, ZETA, 1.0)
    custom = ForcedOscillator(_erf_play_custom(), 4.0, ZETA, 1.0)
    assert compiled.engine_class is PlayEngine and custom.engine_class is ContinuousEngine
    ref = compiled.poincare_section(25)
    sec = custom.poincare_section(25, engine_options=TIGHT)
    np.testing.assert_allclose(sec.q, ref.q, atol=1e-6, rtol=0)
    np.testing.assert_allclose(sec.v, ref.v, atol=1e-6, rtol=0)
    np.testing.assert_allclose(sec.w, ref.w, atol=1e-6, rtol=0)
    np.testing.assert_allclose(sec.M, ref.M, atol=1e-6, rtol=0)
    assert sec.n_switches > 40
    # the erf play itself through the generic engine (forced by building it directly)
    engine = ContinuousEngine(compiled, compiled.initial_state(), **TIGHT)
    out = _section(engine, 25)
    np.testing.assert_allclose(out[:, 0], ref.q, atol=1e-6, rtol=0)
    np.testing.assert_allclose(out[:, 1], ref.v, atol=1e-6, rtol=0)


@pytest.mark.parametrize("coupling", [0.6, -0.8])
def test_single_play_prandtl_ishlinskii_gives_the_play_section(coupling):
    play = ForcedOscillator(PlayOperator(2.0), coupling, ZETA, 1.0)
    pi = ForcedOscillator(PrandtlIshlinskii([2.0], [1.0]), coupling, ZETA, 1.0)
    assert play.engine_class is PlayEngine and pi.engine_class is CompiledContinuousEngine
    ref = play.poincare_section(25)
    sec = pi.poincare_section(25, engine_options={**GENERIC, **TIGHT})
    np.testing.assert_allclose(sec.q, ref.q, atol=1e-6, rtol=0)
    np.testing.assert_allclose(sec.v, ref.v, atol=1e-6, rtol=0)
    np.testing.assert_allclose(sec.M, ref.M, atol=1e-6, rtol=0)
    # and the plain play itself through the generic engine
    out_play = _section(ContinuousEngine(play, play.initial_state(), **TIGHT), 25)
    np.testing.assert_allclose(out_play[:, 0], ref.q, atol=1e-6, rtol=0)


def test_erf_play_tangent_flow_and_dky_agree_with_compiled_kernel():
    t_end = 150.0  # both runs stay on one trajectory (λ_max·t_end ≈ 8 against ~1e-11 errors)
    compiled = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0, ZETA, 1.0)
    custom = ForcedOscillator(_erf_play_custom(), 4.0, ZETA, 1.0)
    ref = lyapunov_spectrum(compiled, t_end)
    res = lyapunov_spectrum(custom, t_end, engine_options={"rtol": 1e-11, "atol": 1e-11})
    assert (
        res.extra["engine"] == ContinuousEngine.name and ref.extra["engine"] != res.extra["engine"]
    )
    assert res.tangent_space == ref.tangent_space == ("q", "v", "w")
    assert res.exponents[2] == -np.inf and ref.exponents[2] == -np.inf
    np.testing.assert_allclose(res.exponents[:2], ref.exponents[:2], rtol=1e-4, atol=1e-6)
    assert res.kaplan_yorke == pytest.approx(ref.kaplan_yorke, abs=1e-3)
    assert res.kaplan_yorke > 1.0  # chaotic at C = 4 (paper)


@pytest.mark.slow
def test_erf_play_dky_from_a_moderate_run_agrees_with_compiled_kernel():
    # the paper's D_KY at C = 4 (fig:mboa: [1.42, 1.48] from long runs) from a moderate run on
    # both engines: the orbits separate after ~300 time units, so this compares two estimates
    # of one attractor's exponents (statistical, not round-off, agreement)
    moderate = {"t_end": 3000.0, "transient": 100.0}
    compiled = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0, ZETA, 1.0)
    custom = ForcedOscillator(_erf_play_custom(), 4.0, ZETA, 1.0)
    d_ref = lyapunov_spectrum(compiled, **moderate).kaplan_yorke
    d_gen = lyapunov_spectrum(custom, **moderate, engine_options={"rtol": 1e-10, "atol": 1e-10})
    assert d_gen.kaplan_yorke == pytest.approx(d_ref, abs=0.06)
    assert 1.3 < d_gen.kaplan_yorke < 1.6


# ------------------------------------------------------------------------------------------
# tangent flow against finite differences of the flow map
# ------------------------------------------------------------------------------------------
def _fd_jacobian(flow_map, x0, h):
    cols = []
    for j in range(x0.size):
        xp = x0.copy()
        xp[j] += h
        xm = x0.copy()
        xm[j] -= h
        cols.append((flow_map(xp) - flow_map(xm)) / (2 * h))
    return np.array(cols).T


def test_pi_tangent_flow_matches_finite_differences():
    op = PrandtlIshlinskii([0.0, 0.6, 1.5, 2.4], [0.2, 0.3, 0.3, 0.2])
    coupling = 0.8
    pre = _engine(op, coupling)
    pre.advance(30.0, record=True)
    ev = pre.records()["events"]
    # start 0.3 after a reversal: every wagon with width > 0 frozen strictly inside
    t_rev = ev["time"][ev["kind"] == -1][2]
    warm = _engine(op, coupling)
    warm.advance(t_rev + 0.3)
    start = warm.state()
    duration = 9.0
    eng = _engine(op, coupling, start)
    eng.start_tangent(include_phase=True)
    assert eng.tangent_space == ("q", "v", "phi", "w0", "w1", "w2", "w3")
    eng.advance(duration, record=True)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 2 and np.sum(kinds == 1) >= 4  # reversals and wall hits
    jac = eng.deviations()
    system = ForcedOscillator(op, coupling, ZETA, 1.0)
    jac_api, labels = system.jacobian(duration, start, engine_options={**GENERIC, **TIGHT})
    assert labels == eng.tangent_space
    np.testing.assert_array_equal(jac_api, jac)

    def flow_map(x):
        pos = x[3:].copy()
        pos[0] = x[0]  # the width-0 wagon is the input itself
        state = OscillatorState(x[0], x[1], x[2], op.state(pos, x[0]))
        e = _engine(op, coupling, state)
        e.advance(duration)
        f = e.state()
        return np.concatenate([[f.q, f.v, f.phi], f.operator_state.positions])

    x0 = np.concatenate([[start.q, start.v, start.phi], start.operator_state.positions])
    fd = _fd_jacobian(flow_map, x0, 1e-6)
    fd[:, 3] = 0.0  # δw0 alone is no state (w0 ≡ q): the engine resets it, column zero
    np.testing.assert_allclose(jac, fd, atol=2e-7 * np.max(np.abs(fd)), rtol=0)
    # every wagon was dragged at some point: only (q, v, φ) directions survive
    assert eng.rank_bound() == 3
    assert np.linalg.matrix_rank(jac, tol=1e-8) == 3


def test_preisach_tangent_flow_matches_finite_differences():
    op = _preisach_analytic()
    coupling = 3.0
    warm = _engine(op, coupling)
    warm.advance(60.0)
    start = warm.state()
    extrema0 = np.array(start.operator_state.extrema)
    duration = 12.0
    eng = _engine(op, coupling, start)
    eng.start_tangent(include_phase=True)
    labels0 = eng.tangent_space[3:]
    assert labels0 == tuple(op.extremum_label(i) for i in range(extrema0.size - 1))
    eng.advance(duration, record=True)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 3 and np.sum(kinds == 1) >= 1  # reversals and a wipe-out
    jac = eng.deviations()
    final = eng.state().operator_state.extrema
    assert eng.tangent_space[3:] == tuple(op.extremum_label(i) for i in range(final.size - 1))

    def flow_map(x):
        extrema = np.append(x[3:], x[0])
        state = OscillatorState(x[0], x[1], x[2], op.state_from_extrema(extrema))
        e = _engine(op, coupling, state)
        e.advance(duration)
        f = e.state()
        ext = f.operator_state.extrema
        assert ext.size == final.size  # same event sequence
        return np.concatenate([[f.q, f.v, f.phi], ext[:-1]])

    x0 = np.concatenate([[start.q, start.v, start.phi], extrema0[:-1]])
    fd = _fd_jacobian(flow_map, x0, 1e-6)
    np.testing.assert_allclose(jac, fd, atol=1e-6 * np.max(np.abs(fd)), rtol=0)
    # structural rank: (q, v, φ) plus the initial extrema that survived (neither wiped out nor
    # replaced by a later extremum with the same label)
    survived = [
        lab for i, lab in enumerate(labels0) if i < final.size - 1 and final[i] == extrema0[i]
    ]
    assert eng.rank_bound() == min(jac.shape[1], 3 + len(survived))
    assert len(survived) < len(labels0)


# ------------------------------------------------------------------------------------------
# spectra
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "op",
    [_tanh_play(), _pi5(), _preisach_analytic()],
    ids=["tanh-play", "pi5", "preisach"],
)
def test_zero_coupling_oscillator_exponents_are_minus_zeta(op):
    system = ForcedOscillator(op, 0.0, ZETA, 1.0)
    options = {**GENERIC, "rtol": 1e-10, "atol": 1e-10}
    assert isinstance(system.engine(**options), ContinuousEngine)
    res = lyapunov_spectrum(system, 300.0, engine_options=options)
    exps = res.exponents
    # the decoupled oscillator contributes -ζ twice (complex pair); memory directions are
    # frozen (0) or reset (-inf)
    finite = exps[np.isfinite(exps)]
    osc = finite[np.abs(finite + ZETA) < 0.02]
    assert osc.size == 2, exps
    np.testing.assert_allclose(osc, -ZETA, atol=0.01)
    assert np.all((np.abs(finite) < 1e-9) | (np.abs(finite + ZETA) < 0.02))


@pytest.mark.parametrize(
    ("op", "coupling", "memory"),
    [(_tanh_play(), 4.0, ("w",)), (_pi5(), 0.8, ("w0", "w1", "w2", "w3", "w4"))],
    ids=["tanh-play", "pi5"],
)
def test_tanh_play_and_pi5_couple_with_finite_spectra(op, coupling, memory):
    system = ForcedOscillator(op, coupling, ZETA, 1.0)
    options = {**GENERIC, "rtol": 1e-10, "atol": 1e-10}
    res = lyapunov_spectrum(system, 200.0, engine_options=options)
    exps = res.exponents
    assert res.extra["engine"] == ContinuousEngine.name
    assert res.tangent_space == ("q", "v") + memory
    assert np.all(np.isfinite(exps[:2])), exps
    assert exps[0] < 1.0 and exps[1] < 0.0
    # every memory direction is reset by a wall hit: exactly -inf (paper's λ_4 = -∞)
    assert np.all(exps[2:] == -np.inf)
    assert res.n_switches > 50
    assert np.isfinite(res.kaplan_yorke)


# ------------------------------------------------------------------------------------------
# engine contract
# ------------------------------------------------------------------------------------------
def test_advance_in_pieces_equals_one_run_and_state_is_consistent():
    op = _pi5()
    one = _engine(op, 0.8)
    one.advance(37.5)
    two = _engine(op, 0.8)
    for t in (3.0, 11.25, 11.25, 30.0, 37.5):
        two.advance(t)
    a, b = one.state(), two.state()
    assert b.t == pytest.approx(37.5)
    assert a.q == pytest.approx(b.q, abs=1e-9) and a.v == pytest.approx(b.v, abs=1e-9)
    np.testing.assert_allclose(a.operator_state.positions, b.operator_state.positions, atol=1e-9)
    assert a.phi == pytest.approx(math.fmod(37.5, 2 * math.pi))
    # the operator state is the operator's: its output drives the oscillator
    out = np.empty((1, 3))
    two.advance(37.5, out)
    assert out[0, 2] == pytest.approx(op.output(b.operator_state), abs=1e-12)


def test_tangent_space_and_rank_bound_at_start():
    op = PlayOperator(2.0)
    # inside the play: w is a free direction
    inside = _engine(op, 0.5, _start(op, operator_state=op.state(-1.5, -1.0)))
    inside.start_tangent(include_phase=True)
    assert inside.tangent_space == ("q", "v", "phi", "w")
    np.testing.assert_array_equal(inside.deviations(), np.eye(4))
    assert inside.rank_bound() == 4
    # on the wall moving outward: δw := δq at t = 0 (one-sided derivative), rank 2 + phase
    wall = _engine(op, 0.5, _start(op, v0=-0.1, operator_state=op.state(0.0, -1.0)))
    wall.start_tangent()
    dev = wall.deviations()
    np.testing.assert_array_equal(dev[2], dev[0])
    assert wall.rank_bound() == 2
    with pytest.raises(ValueError, match="shape"):
        wall.set_deviations(np.eye(4))


def test_preisach_start_at_a_reversal_pushes_the_input_as_memory():
    op = _preisach_analytic()
    # rising from saturation to q0 = 0.5, then moving down: the reversal at t = 0 makes q0 an
    # extremum whose perturbation is δq (one-sided derivative, as a play wall at t = 0)
    eng = _engine(op, 2.0, _start(op, q0=0.5, v0=-0.3))
    eng.start_tangent()
    assert eng.tangent_space == ("q", "v", "M1")
    dev = eng.deviations()
    np.testing.assert_array_equal(dev[2], dev[0])
    assert eng.rank_bound() == 2
    eng.advance(3.0)
    assert eng.tangent_space[:3] == ("q", "v", "M1")
    assert eng.state().operator_state.extrema[0] == 0.5


def test_bad_input_raises():
    op = _pi5()
    with pytest.raises(ValueError, match="rtol"):
        _engine(op, 0.5, rtol=0.5)
    with pytest.raises(ValueError, match="max_step"):
        _engine(op, 0.5, max_step=0.0)
    with pytest.raises(ValueError, match="input"):
        _engine(op, 0.5, OscillatorState(1.0, 0.0, 0.0, op.initial_state(0.0)))
    engine = _engine(op, 0.5)
    engine.advance(2.0)
    with pytest.raises(ValueError, match="times"):
        engine.advance(1.0)
    with pytest.raises(RuntimeError, match="start_tangent"):
        engine.deviations()
    with pytest.raises(TypeError, match="branch_flow"):
        from hysteresis import Relay

        ContinuousEngine(ForcedOscillator(Relay(1.0, -1.0), 1.0), _start(Relay(1.0, -1.0)))


def test_negative_stiffness_diverges():
    # PI with total weight 1 and C = 2: on the walls q'' = ... + (C − 1) q grows without bound
    with pytest.warns(RuntimeWarning, match="unbounded"):
        engine = _engine(PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5]), 2.0)
    with pytest.raises(DivergenceError):
        engine.advance(200.0)


# ------------------------------------------------------------------------------------------
# width disorder: the Gaussian-ridge Preisach model tends to the erf play as σ_r -> 0
# ------------------------------------------------------------------------------------------
def test_gaussian_preisach_approaches_the_erf_play_as_width_spread_shrinks():
    from hysteresis import ContinuousPreisachModel

    coupling = 4.0
    play_system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), coupling, ZETA, 1.0)
    ref = play_system.poincare_section(12)
    # λ_max over a horizon on which the orbits still shadow each other (finite-time exponent
    # along nearly one trajectory): differences then measure the model difference
    t_end = 40.0
    ref_max = lyapunov_spectrum(play_system, t_end).max_exponent
    options = {**GENERIC, "rtol": 1e-10, "atol": 1e-10}
    distances, gaps = [], []
    for width_spread in (0.1, 0.05, 0.025):
        model = ContinuousPreisachModel.gaussian(2.0, 1.0, width_spread)
        system = ForcedOscillator(model, coupling, ZETA, 1.0)
        sec = system.poincare_section(12, engine_options=options)
        distances.append(np.max(np.hypot(sec.q - ref.q, sec.v - ref.v)))
        res = lyapunov_spectrum(system, t_end, engine_options=options)
        gaps.append(abs(res.max_exponent - ref_max))
    assert distances[0] > distances[1] > distances[2]
    assert gaps[0] > gaps[1] > gaps[2]
    assert distances[2] < 0.1 * distances[0] and distances[2] < 0.1
    assert gaps[2] < 2e-3
