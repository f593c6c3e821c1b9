"""The compiled continuous engine (oscillators.engines.compiled_continuous) against independent
truths.

* the generic engine (``solve_ivp`` DOP853 on ``branch_flow``, an independent implementation)
  run tight (rtol = atol = 1e-13): Poincaré sections, memory, event records and tangent maps;
* central finite differences of the compiled engine's own flow map (state-only runs) for its
  tangent flow across reversals, wall hits and wipe-outs, perturbing q, v, φ and every memory
  variable;
* closed forms: C = 0 decouples the oscillator (exponents −ζ, −ζ); a width-0 play alone is a
  linear spring (exponents −ζ, −ζ for any C with C·a < 1 − ζ²).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import ContinuousPreisachModel, GeneralizedPlay, PrandtlIshlinskii
from oscillators.engines import (
    CompiledContinuousEngine,
    ContinuousEngine,
    DivergenceError,
)
from oscillators.engines import compiled_continuous as cc
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA = 0.05
T = 2.0 * math.pi
#: the reference: the generic engine with its tightest tolerances. At rtol = 1e-11 (its default)
#: it differs from this by ~1e-8 over 10 periods of the chaotic C = 4 Preisach orbit, the
#: compiled engine (RK8, h = 0.05) by ~3e-10, so 1e-8 below bounds the reference's error
#: amplified by the orbit (λ ≈ 0.1 over 63 time units: ×500) with a margin.
REFERENCE = {"method": "generic", "rtol": 1e-13, "atol": 1e-13, "max_step": 0.1}
#: a tabulated (C¹) Everett function: its cell lines are kinks the adaptive solver's error
#: estimate does not see, so it needs short steps (measured: max_step 0.1 errs by 4e-9 over 10
#: periods, 0.01 by 1e-11; the compiled engine lands its steps on the lines: 3e-13)
REFERENCE_TABLE = {**REFERENCE, "max_step": 0.01}


def _pi5():
    return PrandtlIshlinskii(np.linspace(0.4, 2.0, 5), np.full(5, 0.2))


def _gaussian():
    return ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2)


#: half-side of the support of the linear density below
_L = 3.0


def _linear_density(a, b):
    """μ(α, β) = 6 (α − β)/(2L)³ on the triangle of [−L, L] (mass ∫_0^{2L} r (2L − r) dr =
    (2L)³/6): wide hysterons weigh more, no Gaussian anywhere."""
    return 6.0 * (np.asarray(a) - np.asarray(b)) / (2.0 * _L) ** 3


def _from_density():
    return ContinuousPreisachModel.from_density(_linear_density, -_L, _L, resolution=128)


class _GenericPlay(GeneralizedPlay):
    """A user shape without any compiled description (the generic engine's operator)."""

    def compiled_play(self):
        return None


def _generic_tanh():
    return _GenericPlay(2.0, np.tanh, lambda w: 1.0 / np.cosh(w) ** 2)


CASES = {"pi5": (_pi5, 0.8), "gaussian": (_gaussian, 4.0), "from_density": (_from_density, 2.0)}


def _system(name):
    make, coupling = CASES[name]
    return ForcedOscillator(make(), coupling, ZETA, 1.0)


def _memory(state):
    """Wagon positions (PI) or remembered extrema (Preisach) of a state."""
    op_state = state.operator_state
    if hasattr(op_state, "positions"):
        return np.asarray(op_state.positions)
    return np.asarray(op_state.extrema)


def _run(system, start, times, options, tangent=False):
    eng = system.engine(start, **options)
    if tangent:
        eng.start_tangent(False)
    out = np.empty((times.size, 3))
    eng.advance(times, out, record=True)
    return eng, out


# ------------------------------------------------------------------------------------------
# the contract picks the engine; the generic one stays reachable
# ------------------------------------------------------------------------------------------
def test_the_contract_selects_the_compiled_engine_and_generic_stays_reachable():
    from relay_test_support import gauss_everett_model

    for name in CASES:
        system = _system(name)
        assert system.engine_class is CompiledContinuousEngine
        assert isinstance(system.engine(), CompiledContinuousEngine)
        assert type(system.engine(method="generic")) is ContinuousEngine
    # a user Everett function runs on the compiled engine through its table
    model = gauss_everett_model(1.3, -6.0, 6.0)
    assert model.compiled_flow().kind == "preisach"
    assert ForcedOscillator(model, 1.0).engine_class is CompiledContinuousEngine
    # no compiled description at all: the generic engine
    tanh = _generic_tanh()
    assert tanh.compiled_flow() is None
    assert ForcedOscillator(tanh, 1.0).engine_class is ContinuousEngine


# ------------------------------------------------------------------------------------------
# compiled vs generic
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(CASES))
def test_sections_memory_and_events_agree_with_the_generic_engine(name):
    system = _system(name)
    start = system.initial_state(-1.0, 0.1)
    times = T * np.arange(1, 11)
    fast, out = _run(system, start, times, {})
    ref, out_ref = _run(
        system, start, times, REFERENCE_TABLE if name == "from_density" else REFERENCE
    )
    np.testing.assert_allclose(out, out_ref, atol=1e-8, rtol=0)
    a, b = fast.state(), ref.state()
    assert _memory(a).shape == _memory(b).shape
    np.testing.assert_allclose(_memory(a), _memory(b), atol=1e-8, rtol=0)
    assert a.t == pytest.approx(b.t, abs=1e-12)
    ev, ev_ref = fast.records()["events"], ref.records()["events"]
    assert ev.size == ev_ref.size > 10
    np.testing.assert_array_equal(ev["kind"], ev_ref["kind"])
    assert set(ev["kind"]) == {-1, 1}  # reversals and breakpoints (wall hits / wipe-outs)
    # event times: located to full accuracy on both sides (Newton on the RK8 map; the solver's
    # dense output at rtol 1e-13); they differ by the orbits' difference (<= 1e-8 above, ~3e-10
    # measured) over the crossing speed (|v| >= 0.2 at these breakpoints, v' = O(1) at the
    # reversals): measured 4e-14 (PI), 4e-10 (Preisach)
    np.testing.assert_allclose(ev["time"], ev_ref["time"], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ev["q"], ev_ref["q"], atol=1e-8, rtol=0)
    np.testing.assert_allclose(ev["M"], ev_ref["M"], atol=1e-8, rtol=0)
    assert np.all(ev["v"][ev["kind"] == -1] == 0.0)  # v := 0 exactly at a reversal
    assert fast.n_events == ref.n_events == ev.size


def test_gaussian_table_and_its_former_quadrature_give_the_same_sections():
    from hysteresis.preisach.gaussian import gaussian_everett

    # the model's bi-quintic Everett table (kind 2) against the 48-node quadrature (kind 0) it
    # replaced, both integrated by the compiled engine: E differs by <= 1e-12 (bound tested in
    # test_gaussian_table), a force perturbation of 2C·1e-12; over 10 periods of this chaotic
    # orbit (amplification ~500, see REFERENCE) that stays far below 1e-8 (measured 8e-11)
    table = _gaussian()
    quadrature = _gaussian()
    quadrature._compiled_everett = gaussian_everett(2.0, 1.0, 0.2, 48).compiled()
    assert table.compiled_everett().kind == 2 and quadrature.compiled_everett().kind == 0
    times = T * np.arange(1, 11)
    outs = []
    for op in (table, quadrature):
        system = ForcedOscillator(op, 4.0, ZETA, 1.0)
        outs.append(_run(system, system.initial_state(-1.0, 0.1), times, {})[1])
    np.testing.assert_allclose(outs[0], outs[1], atol=1e-8, rtol=0)


@pytest.mark.parametrize("name", list(CASES))
def test_tangent_maps_agree_with_the_generic_engine(name):
    system = _system(name)
    start = system.initial_state(-1.0, 0.1)
    times = T * np.arange(1, 6)
    reference = REFERENCE_TABLE if name == "from_density" else REFERENCE
    fast, _ = _run(system, start, times, {}, tangent=True)
    ref, _ = _run(system, start, times, reference, tangent=True)
    assert fast.tangent_space == ref.tangent_space
    assert fast.rank_bound() == ref.rank_bound()
    jac, jac_ref = fast.deviations(), ref.deviations()
    # relative to the map's size: both integrate the same linear equations to ~1e-10
    np.testing.assert_allclose(jac, jac_ref, atol=1e-7 * np.max(np.abs(jac_ref)), rtol=0)


def test_a_wipe_out_overshot_within_a_solver_step_is_found_by_both_engines():
    # C = 0, at resonance the amplitude grows by ~1e-5 per period: each new maximum passes the
    # previous one by a little and turns back within one solver step (the generic engine once
    # saw only the reversal); both record every wipe-out
    system = ForcedOscillator(_gaussian(), 0.0, ZETA, 1.0)
    start = system.initial_state(-1.0, 0.1)
    times = np.array([230.0])
    fast, _ = _run(system, start, times, {})
    ref, _ = _run(system, start, times, {"method": "generic"})
    ev, ev_ref = fast.records()["events"], ref.records()["events"]
    np.testing.assert_array_equal(ev["kind"], ev_ref["kind"])
    late = ev["time"] > 200.0
    assert np.sum(late & (ev["kind"] == 1)) >= 3  # the late wipe-outs (one per period)
    np.testing.assert_allclose(ev["time"], ev_ref["time"], atol=1e-6, rtol=0)


# ------------------------------------------------------------------------------------------
# tangent flow against finite differences of the engine's own flow map
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
    system = ForcedOscillator(op, 0.8, ZETA, 1.0)
    pre = system.engine()
    pre.advance(30.0, record=True)
    ev = pre.records()["events"]
    # start 0.3 after a reversal: every wagon with width > 0 frozen strictly inside
    t_rev = ev["time"][ev["kind"] == -1][2]
    warm = system.engine()
    warm.advance(t_rev + 0.3)
    start = warm.state()
    duration = 9.0
    eng = system.engine(start)
    eng.start_tangent(include_phase=True)
    assert eng.tangent_space == ("q", "v", "phi", "w0", "w1", "w2", "w3")
    eng.advance(duration, record=True)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 2 and np.sum(kinds == 1) >= 4  # reversals and wall hits
    jac = eng.deviations()

    def flow_map(x):
        pos = x[3:].copy()
        pos[0] = x[0]  # the width-0 wagon is the input itself
        e = system.engine(OscillatorState(x[0], x[1], x[2], op.state(pos, x[0])))
        e.advance(duration)
        f = e.state()
        return np.concatenate([[f.q, f.v, f.phi], f.operator_state.positions])

    x0 = np.concatenate([[start.q, start.v, start.phi], start.operator_state.positions])
    fd = _fd_jacobian(flow_map, x0, 1e-6)
    fd[:, 3] = 0.0  # δw0 alone is no state (w0 ≡ q): the engine resets it, column zero
    # central differences: truncation h²/6·|f'''| ~ 1e-12·(map growth), round-off
    # ε·|x|/h ~ 1e-10·(map growth); the fixed-step RK8 map is smooth in x between events
    np.testing.assert_allclose(jac, fd, atol=1e-7 * np.max(np.abs(fd)), rtol=0)
    # every wagon was dragged at some point: only (q, v, φ) directions survive
    assert eng.rank_bound() == 3
    assert np.linalg.matrix_rank(jac, tol=1e-8) == 3


@pytest.mark.parametrize("name", ["gaussian", "from_density"])
def test_preisach_tangent_flow_matches_finite_differences_across_wipe_outs(name):
    # from_density: the orbit also leaves and re-enters the support of the table, where the
    # branch slope jumps (the step's side decides it)
    op = CASES[name][0]()
    system = ForcedOscillator(op, 3.0, ZETA, 1.0)
    warm = system.engine(system.initial_state(-1.0, 0.1))
    warm.advance(60.0)
    start = warm.state()
    extrema0 = np.array(start.operator_state.extrema)
    duration = 14.0
    eng = system.engine(start)
    eng.start_tangent(include_phase=True)
    labels0 = eng.tangent_space[3:]
    assert labels0 == tuple(op.extremum_label(i) for i in range(extrema0.size - 1))
    assert len(labels0) >= 2
    eng.advance(duration, record=True)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 3 and np.sum(kinds == 1) >= 1  # reversals and a wipe-out
    jac = eng.deviations()
    final = eng.state().operator_state.extrema
    assert eng.tangent_space[3:] == tuple(op.extremum_label(i) for i in range(final.size - 1))

    def flow_map(x):
        extrema = np.append(x[3:], x[0])
        e = system.engine(OscillatorState(x[0], x[1], x[2], op.state_from_extrema(extrema)))
        e.advance(duration)
        f = e.state()
        ext = f.operator_state.extrema
        assert ext.size == final.size  # same event sequence
        return np.concatenate([[f.q, f.v, f.phi], ext[:-1]])

    x0 = np.concatenate([[start.q, start.v, start.phi], extrema0[:-1]])
    fd = _fd_jacobian(flow_map, x0, 1e-6)
    # as for PI; the chaotic orbit (C = 3) amplifies both errors alike (relative tolerance)
    np.testing.assert_allclose(jac, fd, atol=1e-6 * np.max(np.abs(fd)), rtol=0)
    survived = [
        lab for i, lab in enumerate(labels0) if i < final.size - 1 and final[i] == extrema0[i]
    ]
    assert eng.rank_bound() == min(jac.shape[1], 3 + len(survived))
    if name == "gaussian":
        assert len(survived) < len(labels0)  # an initial extremum was wiped out
    else:
        # the orbit left the table's support in this window
        e = system.engine(start)
        out = np.empty((400, 3))
        e.advance(np.linspace(0.0, duration, 400), out)
        assert np.min(out[:, 0]) < op.lower or np.max(out[:, 0]) > op.upper


def test_preisach_start_at_a_reversal_pushes_the_input_as_memory():
    op = _gaussian()
    system = ForcedOscillator(op, 2.0, ZETA, 1.0)
    # the state last rose to q; starting with v < 0 reverses at once: q is pushed, δm := δq
    state = OscillatorState(0.5, -0.2, 0.0, op.initial_state(0.5))
    for options in ({}, {"method": "generic"}):
        eng = system.engine(state, **options)
        eng.start_tangent(False)
        assert eng.tangent_space == ("q", "v", "M1")
        np.testing.assert_array_equal(eng.deviations(), [[1, 0, 0], [0, 1, 0], [1, 0, 0]])
        assert eng.rank_bound() == 2


# ------------------------------------------------------------------------------------------
# spectra: closed forms
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(CASES))
def test_zero_coupling_oscillator_exponents_are_minus_zeta(name):
    make, _ = CASES[name]
    system = ForcedOscillator(make(), 0.0, ZETA, 1.0)
    res = lyapunov_spectrum(system, 300.0, transient=50.0, progress=False)
    assert res.extra["engine"] == CompiledContinuousEngine.name
    exps = res.exponents
    finite = exps[np.isfinite(exps)]
    # the decoupled linear oscillator: a complex pair, both -ζ; the finite-time QR estimate
    # splits them by O(log(cond V)/t) (eigenvector basis of the damped rotation). Their sum is
    # the trace -2ζ up to the volume the memory rows add to the first two vectors (a reset
    # copies δq into a memory row): a factor <= sqrt(1 + n_memory) per vector, so
    # |Σ + 2ζ| <= log(1 + n_memory)/t
    assert finite.size == 2, exps
    window = res.t_end - res.transient
    n_mem = len(res.tangent_space) - 2
    np.testing.assert_allclose(finite, -ZETA, atol=0.01)
    assert np.sum(finite) == pytest.approx(-2.0 * ZETA, abs=math.log(1 + n_mem) / window)
    # the orbit's amplitude (1/(2ζ) = 10 at resonance) drags every wagon / wipes every
    # extremum each period: the memory directions collapse (-inf)
    assert np.all(exps[2:] == -np.inf)


def test_a_width_zero_play_is_a_linear_spring_with_exponents_minus_zeta():
    # y = a·q: q'' + 2ζq' + (1 − C a) q = cos t, eigenvalues −ζ ± i·sqrt(1 − Ca − ζ²)
    system = ForcedOscillator(PrandtlIshlinskii([0.0], [0.5]), 0.8, ZETA, 1.0)
    res = lyapunov_spectrum(system, 300.0, transient=20.0, progress=False)
    assert res.tangent_space == ("q", "v", "w0")
    np.testing.assert_allclose(res.exponents[:2], -ZETA, atol=0.01)
    # as above, one memory row: |Σ + 2ζ| <= log 2 / t
    window = res.t_end - res.transient
    assert np.sum(res.exponents[:2]) == pytest.approx(-2.0 * ZETA, abs=math.log(2.0) / window)
    assert res.exponents[2] == -np.inf  # w0 ≡ q: no direction of its own


# ------------------------------------------------------------------------------------------
# engine contract
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(CASES))
def test_advance_in_pieces_equals_one_run_and_state_is_consistent(name):
    system = _system(name)
    op = system.operator
    one = system.engine()
    one.advance(37.5)
    two = system.engine()
    for t in (3.0, 11.25, 11.25, 30.0, 37.5):
        two.advance(t)
    a, b = one.state(), two.state()
    assert b.t == pytest.approx(37.5)
    assert a.q == pytest.approx(b.q, abs=1e-9) and a.v == pytest.approx(b.v, abs=1e-9)
    np.testing.assert_allclose(_memory(a), _memory(b), atol=1e-9)
    assert a.phi == pytest.approx(math.fmod(37.5, T))
    out = np.empty((1, 3))
    two.advance(37.5, out)
    # the operator state is the operator's: its output drives the oscillator
    assert out[0, 2] == pytest.approx(op.output(b.operator_state), abs=1e-12)
    # and continuing from the reported state continues the orbit
    three = system.engine(b)
    three.advance(10.0)
    one.advance(47.5)
    assert three.state().q == pytest.approx(one.state().q, abs=1e-9)


def test_staircase_capacity_grows_without_changing_the_orbit(monkeypatch):
    system = _system("gaussian")
    ref = system.engine()
    ref.start_tangent(False)
    ref.advance(120.0)
    monkeypatch.setattr(cc, "_MIN_CAPACITY", 4)
    small = system.engine()
    assert small._stack.size < 8
    small.start_tangent(False)
    small.advance(120.0)
    assert small._stack.size > 8  # grown on the way
    assert small.state().q == ref.state().q and small.state().v == ref.state().v
    np.testing.assert_array_equal(small.deviations(), ref.deviations())


def test_bad_input_and_divergence_raise():
    system = _system("pi5")
    with pytest.raises(ValueError, match="method"):
        system.engine(method="bogus")
    with pytest.raises(ValueError, match="step"):
        system.engine(step=0.0)
    with pytest.raises(ValueError, match="step"):
        system.engine(step=0.5)
    with pytest.raises(TypeError):
        system.engine(rtol=1e-10)  # a generic-engine option without method="generic"
    tanh = ForcedOscillator(_generic_tanh(), 1.0)
    with pytest.raises(TypeError, match="compiled_flow"):
        CompiledContinuousEngine(tanh, tanh.initial_state())
    with pytest.raises(ValueError, match="method"):
        tanh.engine(method="compiled")
    eng = system.engine()
    with pytest.raises(ValueError, match="times"):
        eng.advance(np.array([2.0, 1.0]))
    # negative stiffness 1 − C·slope < 0 on the steepest branch: runaway, never a number
    with pytest.warns(RuntimeWarning, match="unbounded"):
        unstable = ForcedOscillator(PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5]), 2.0, ZETA, 1.0)
    with pytest.raises(DivergenceError):
        unstable.engine().advance(200.0)


@pytest.mark.parametrize(
    ("name", "zeta", "omega", "coupling"),
    [
        ("pi3", 2.0, 3.0, 0.5),  # overdamped, fast forcing
        ("pi3", ZETA, 1.0, -400.0),  # stiff: 1 − C·slope ≈ 400
        ("gaussian", 30.0, 0.3, 4.0),  # strongly overdamped
        ("gaussian", ZETA, 8.0, 4.0),  # fast forcing
    ],
)
def test_parameter_corners_agree_with_the_generic_engine(name, zeta, omega, coupling):
    # the RK8 step scales with ρ = max(1, Ω, 2ζ, √(|C|·slope)): its local error (ρh)^9 stays
    # put, so the agreement is the same (relative to the motion's size) as at Table II values
    op = PrandtlIshlinskii([0.0, 1.0, 2.0], [0.3, 0.3, 0.4]) if name == "pi3" else _gaussian()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # C < 0: no positive feedback
        system = ForcedOscillator(op, coupling, zeta, omega)
    start = system.initial_state(-1.0, 0.1)
    times = np.array([2.5, 5.0, 10.0])
    reference = {**REFERENCE, "max_step": 0.05}
    _, out = _run(system, start, times, {})
    _, out_ref = _run(system, start, times, reference)
    np.testing.assert_allclose(out, out_ref, atol=1e-10 * max(1.0, np.max(np.abs(out_ref))))
