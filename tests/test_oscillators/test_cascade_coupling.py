"""Cascades coupled to the forced oscillator, against independent truths.

The oscillator knows a cascade only through its contract (``branch_flow``): the generic
continuous engine integrates it, tangent flow included.

* ``Cascade(StaticMap(identity), op)`` runs the orbit of ``op`` itself;
* a trajectory of ``Cascade(StaticMap(f), play)`` against an event-driven ``solve_ivp``
  integrator written here (the play's three modes: dragged up, dragged down, inside);
* the Jacobian of the flow map (``system.jacobian``) against central differences of the map
  itself (state-only runs, no tangent code), for cascades that exercise every piece of the
  tangent bookkeeping: driven outer wagons (``StaticMap`` → Prandtl–Ishlinskii, PI → play),
  relay thresholds reached through the inner memory (``breakpoint_gradient``) and an outer
  Preisach model pushing the inner output at reversals (``pushed_gradient``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import gauss_everett_model
from scipy.integrate import solve_ivp

from hysteresis import GeneralizedPlay, PlayOperator, PrandtlIshlinskii, PreisachModel
from hysteresis.cascade import Cascade, CascadeState
from hysteresis.play import ErfShape, ErfShapeDerivative
from hysteresis.static_map import StaticMap
from oscillators.engines import ContinuousEngine, PlayEngine
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA = 0.05
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
#: central differences of a flow map integrated to rtol 1e-12 with step 1e-6: the integration
#: error enters as rtol/h ~ 1e-6 relative at worst (it is smooth in the start, so far less)
FD_STEP = 1e-6
FD_TOLERANCE = 1e-6


def f_in(u):
    """An increasing input nonlinearity (f' in [0.3, 1.5])."""
    return 1.2 * np.tanh(u) + 0.3 * np.asarray(u)


def f_in_derivative(u):
    return 1.2 / np.cosh(u) ** 2 + 0.3


F = StaticMap(f_in, f_in_derivative)
PI = PrandtlIshlinskii([0.0, 0.6, 1.5, 2.4], [0.2, 0.3, 0.3, 0.2])


def test_identity_in_front_is_the_operator_itself():
    op = Cascade(StaticMap(np.positive), PI)
    options = {"method": "generic", **TIGHT}
    ref = ForcedOscillator(PI, 0.8, ZETA, 1.0).trajectory(40.0, engine_options=options)
    system = ForcedOscillator(op, 0.8, ZETA, 1.0)
    assert system.engine_class is ContinuousEngine
    got = system.trajectory(40.0, engine_options=TIGHT)
    # the same branches and breakpoints (x = u exactly): the same orbit up to rounding
    np.testing.assert_allclose(got.q, ref.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.M, ref.M, rtol=0, atol=1e-12)
    assert len(got.events) == len(ref.events) > 20


def test_relays_then_identity_is_the_relay_system():
    """Flat branches ending in jumps at the relay thresholds, integrated by the generic
    engine, against the relay engine's closed-form flights; the tangent through the
    saltations C·ΔM/v* against the relay engine's."""
    relays = PreisachModel.from_relays([0.35, 0.1, -0.05], [-0.25, -0.5, -0.15], [0.3, 0.3, 0.4])
    op = Cascade(relays, StaticMap(np.positive))
    ref_system = ForcedOscillator(relays, 0.8, ZETA, 1.0)
    system = ForcedOscillator(op, 0.8, ZETA, 1.0)
    assert system.engine_class is ContinuousEngine
    ref = ref_system.trajectory(30.0, sample_dt=0.05)
    got = system.trajectory(30.0, sample_dt=0.05, engine_options=TIGHT)
    assert len(ref.switches) >= 10
    # switch times located to round-off by both; 1e-9 leaves the flow's expansion room
    np.testing.assert_allclose(got.q, ref.q, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got.M, ref.M)
    jac_ref, labels = ref_system.jacobian(12.0, ref_system.initial_state())
    jac, labels_got = system.jacobian(12.0, system.initial_state(), engine_options=TIGHT)
    assert labels == labels_got == ("q", "v", "phi")
    np.testing.assert_allclose(jac, jac_ref, rtol=0, atol=1e-8 * np.max(np.abs(jac_ref)))


def test_play_then_erf_is_the_compiled_erf_play():
    """A play followed by the map erf(w/√2) is the paper's erf play (GeneralizedPlay.erf), which
    runs on the compiled play kernel: an independent integrator."""
    erf_map = StaticMap(ErfShape(1.0), ErfShapeDerivative(1.0), output_range=(-1.0, 1.0))
    compiled = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0, ZETA, 1.0)
    cascade = ForcedOscillator(Cascade(PlayOperator(2.0), erf_map), 4.0, ZETA, 1.0)
    assert compiled.engine_class is PlayEngine and cascade.engine_class is ContinuousEngine
    ref = compiled.poincare_section(25)
    sec = cascade.poincare_section(25, engine_options=TIGHT)
    # the kernel's closed-form flights and the generic engine (rtol 1e-12) agree to 1e-6 on
    # this chaotic attractor over 25 periods (test_continuous_engine, same system)
    for got, want in ((sec.q, ref.q), (sec.v, ref.v), (sec.M, ref.M)):
        np.testing.assert_allclose(got, want, atol=1e-6, rtol=0)
    assert sec.n_switches > 40


def reference_play_of_f(width, coupling, q0, v0, t_end, times):
    """q(t), M(t) of q'' + 2ζq' + q = cos t + C·w with w the play of f(q), by hand."""
    r = 0.5 * width
    q, v, t = q0, v0, 0.0
    w = float(f_in(q0)) - r  # rising from negative saturation: on the right wall
    mode = 1 if v0 > 0 else 0  # +1 dragged up, -1 dragged down, 0 inside
    qs, ms = np.full(times.size, np.nan), np.full(times.size, np.nan)
    while t < t_end:

        def force(y, w=w, mode=mode):
            return float(f_in(y[0])) - mode * r if mode else w

        def rhs(s, y, force=force):
            return [y[1], -2 * ZETA * y[1] - y[0] + math.cos(s) + coupling * force(y)]

        if mode:  # dragged until the input turns (v = 0)

            def turn(s, y):
                return y[1]

            turn.direction = -mode
            stops = [turn]
        else:  # inside until f(q) reaches a wall

            def right(s, y, w=w):
                return f_in(y[0]) - w - r

            def left(s, y, w=w):
                return f_in(y[0]) - w + r

            right.direction, left.direction = 1, -1
            stops = [right, left]
        for stop in stops:
            stop.terminal = True
        sol = solve_ivp(
            rhs, (t, t_end), [q, v], method="DOP853", events=stops, dense_output=True,
            rtol=1e-12, atol=1e-12,
        )  # fmt: skip
        assert sol.t[-1] > t or sol.status == 0, "no progress"
        t1 = sol.t[-1]
        inside = (times >= t) & (times <= t1)
        if np.any(inside):
            y = sol.sol(times[inside])
            qs[inside] = y[0]
            ms[inside] = [force(col) for col in y.T]
        q, v = sol.y[0, -1], sol.y[1, -1]
        if sol.status == 1:
            if mode:
                w, mode = float(f_in(q)) - mode * r, 0
            else:
                mode = 1 if f_in(q) - w > 0 else -1
        t = t1
    return qs, ms


def test_trajectory_against_a_hand_written_event_integrator():
    width, coupling, t_end = 1.0, 0.9, 30.0
    system = ForcedOscillator(Cascade(F, PlayOperator(width)), coupling, ZETA, 1.0)
    got = system.trajectory(t_end, q0=-1.0, v0=0.1, sample_dt=0.05, engine_options=TIGHT)
    q, m = reference_play_of_f(width, coupling, -1.0, 0.1, t_end, got.t)
    kinds = got.events["kind"]
    assert np.sum(kinds == -1) >= 8 and np.sum(kinds == 1) >= 8  # reversals and wall hits
    # both integrate to 1e-12 and locate their events to round-off (measured 2e-12); 1e-10
    # leaves the flow's expansion over 30 time units a factor 50
    np.testing.assert_allclose(got.q, q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(got.M, m, rtol=0, atol=1e-10)


# ------------------------------------------------------------------------------------------
# the Jacobian of the flow map against central differences of the map
# ------------------------------------------------------------------------------------------
def _fd_jacobian(flow_map, x0):
    cols = []
    for j in range(x0.size):
        xp, xm = x0.copy(), x0.copy()
        xp[j] += FD_STEP
        xm[j] -= FD_STEP
        cols.append((flow_map(xp) - flow_map(xm)) / (2 * FD_STEP))
    return np.array(cols).T


def _check_jacobian(op, coupling, build, read, pre_time=30.0, reversal=2, not_free=()):
    """The Jacobian of the stroboscopic map (``system.jacobian`` over one period T), started
    0.3 after a reversal (frozen memory strictly inside), against central differences of
    ``system.stroboscopic_map`` in the coordinates ``(q, v, φ, *memory labels)``;
    ``build(x, start, labels)`` makes a state from coordinates, ``read(state, labels)`` the
    coordinates of a state. Returns the engine of the tangent run, the Jacobian and the start's
    labels."""
    system = ForcedOscillator(op, coupling, ZETA, 1.0)
    pre = system.engine(system.initial_state(), **TIGHT)
    pre.advance(np.array([pre_time]), record=True)
    events = pre.records()["events"]
    t_rev = events["time"][events["kind"] == -1][reversal]
    warm = system.engine(system.initial_state(), **TIGHT)
    warm.advance(np.array([t_rev + 0.3]))
    start = warm.state()
    eng = system.engine(start, **TIGHT)
    eng.start_tangent(include_phase=True)
    labels0 = eng.tangent_space
    eng.advance(np.array([system.period]), record=True)
    jac, labels1 = eng.deviations(), eng.tangent_space
    jac_api, labels_api = system.jacobian(system.period, start, engine_options=TIGHT)
    np.testing.assert_array_equal(jac_api, jac)
    assert labels_api == labels1

    def flow_map(x):
        return read(
            system.stroboscopic_map(build(x, start, labels0), engine_options=TIGHT), labels1
        )

    fd = _fd_jacobian(flow_map, read(start, labels0))
    # δw0 alone is no state (w0 ≡ q), nor is an extremum pushed at the start (≡ x): the
    # engine sets their rows from the others, so their columns vanish
    fd[:, [j for j, lab in enumerate(labels0) if lab in ("in:w0", *not_free)]] = 0.0
    np.testing.assert_allclose(jac, fd, rtol=0, atol=FD_TOLERANCE * np.max(np.abs(fd)))
    return eng, jac, labels0


def _pi_positions(labels, x, template, prefix):
    """Wagon positions: the labelled ones from ``x``, the others from ``template``."""
    pos = np.array(template, dtype=float)
    for k, lab in enumerate(labels[3:]):
        if lab.startswith(prefix):
            pos[int(lab[len(prefix) :])] = x[3 + k]
    return pos


def test_jacobian_of_a_static_map_in_front_of_prandtl_ishlinskii():
    """Outer wagons dragged by f(q) are driven (δw = f'(q) δq): they leave the tangent space
    on a wall hit and come back at a reversal initialised from that gradient."""
    op = Cascade(F, PI)

    def read(state, labels):
        pos = state.operator_state.outer.positions
        return np.array([state.q, state.v, state.phi, *(pos[int(lab[5:])] for lab in labels[3:])])

    def build(x, start, labels):
        q = float(x[0])
        outer = start.operator_state.outer
        pos = _pi_positions(labels, x, outer.positions, "out:w")
        for i in range(pos.size):
            if f"out:w{i}" not in labels:  # driven at the start: on its wall, follows f(q)
                pos[i] += float(f_in(q)) - outer.input
        state = CascadeState(F.initial_state(q), PI.state(pos, float(f_in(q))))
        return OscillatorState(q, x[1], x[2], state)

    eng, jac, _ = _check_jacobian(op, 0.8, build, read)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 1 and np.sum(kinds == 1) >= 6
    # every wagon was dragged at some point: only (q, v, φ) directions survive
    assert eng.rank_bound() == 3 == np.linalg.matrix_rank(jac, tol=1e-8)


@pytest.mark.parametrize("reversal", [2, 3])
def test_jacobian_of_prandtl_ishlinskii_in_front_of_a_play(reversal):
    """The outer wagon dragged by x = Σ a_i w_i is driven, δw = a_0 δq + Σ a_i δw_i; at a
    reversal of x it becomes a coordinate again with that gradient."""
    play = PlayOperator(0.8)
    # weights summing to 1.2 (with every wagon dragged δx = 1.2 δq: a slaved outer wagon, δq,
    # would be wrong) and a wide wagon that stays frozen when the outer one is released (the
    # gradient's ∂x/∂w_3 = a_3 term)
    pi = PrandtlIshlinskii([0.0, 0.6, 1.5, 6.0], [0.3, 0.4, 0.3, 0.2])
    op = Cascade(pi, play)

    def read(state, labels):
        s = state.operator_state
        vals = [
            s.inner.positions[int(lab[4:])] if lab.startswith("in:") else s.outer.position
            for lab in labels[3:]
        ]
        return np.array([state.q, state.v, state.phi, *vals])

    def build(x, start, labels):
        q = float(x[0])
        s0 = start.operator_state
        pos = _pi_positions(labels, x, s0.inner.positions, "in:w")
        pos[0] = q
        inner = pi.state(pos, q)
        xin = pi.output(inner)
        w_out = x[labels.index("out:w")] if "out:w" in labels else s0.outer.position
        if "out:w" not in labels:
            w_out += xin - s0.outer.input
        return OscillatorState(q, x[1], x[2], CascadeState(inner, play.state(w_out, xin)))

    eng, _, _ = _check_jacobian(op, 0.8, build, read, reversal=reversal)
    kinds = eng.records()["events"]["kind"]
    assert np.sum(kinds == -1) >= 2 and np.sum(kinds == 1) >= 5


def test_jacobian_of_relays_behind_prandtl_ishlinskii():
    """A relay switches where x(q; w) reaches its threshold: the switch moves with the frozen
    wagons, δu* = −(∂x/∂w) δw / (dx/dq), and the saltation carries that term."""
    pi = PrandtlIshlinskii([0.0, 1.5, 5.0], [0.5, 0.3, 0.2])  # wide wagons: frozen at switches
    relays = PreisachModel.from_relays([0.35, 0.1, -0.05], [-0.25, -0.5, -0.15], [0.3, 0.3, 0.4])
    op = Cascade(pi, relays)

    def read(state, labels):
        pos = state.operator_state.inner.positions
        return np.array([state.q, state.v, state.phi, *(pos[int(lab[4:])] for lab in labels[3:])])

    def build(x, start, labels):
        q = float(x[0])
        s0 = start.operator_state
        pos = _pi_positions(labels, x, s0.inner.positions, "in:w")
        pos[0] = q
        inner = pi.state(pos, q)
        outer = relays.state_from_relay_outputs(relays.relay_outputs(s0.outer), pi.output(inner))
        return OscillatorState(q, x[1], x[2], CascadeState(inner, outer))

    eng, jac, _ = _check_jacobian(op, 0.8, build, read)
    assert eng.n_events >= 4
    assert np.max(np.abs(jac[:, 4:])) > 0.05  # the frozen wagons move the switches


def test_jacobian_of_a_preisach_model_behind_prandtl_ishlinskii():
    """At a reversal the outer Preisach model remembers x = Σ a_i w_i, so the new extremum's
    perturbation is a_0 δq + Σ a_i δw_i (pushed_gradient), not δq."""
    preisach = gauss_everett_model(1.3, -6.0, 6.0)
    pi = PrandtlIshlinskii([0.0, 1.0, 2.5], [0.5, 0.3, 0.2])
    op = Cascade(pi, preisach)

    def read(state, labels):
        s = state.operator_state
        extrema = np.asarray(s.outer.extrema)
        n_out = sum(lab.startswith("out:") for lab in labels)
        assert extrema.size == n_out + 1  # the same staircase structure
        inner = [s.inner.positions[int(lab[4:])] for lab in labels[3:] if lab.startswith("in:")]
        return np.array([state.q, state.v, state.phi, *inner, *extrema[:-1]])

    def build(x, start, labels):
        q = float(x[0])
        pos = _pi_positions(labels, x, start.operator_state.inner.positions, "in:w")
        pos[0] = q
        inner = pi.state(pos, q)
        extrema = [x[3 + k] for k, lab in enumerate(labels[3:]) if lab.startswith("out:")]
        outer = preisach.state_from_extrema([*extrema, pi.output(inner)])
        return OscillatorState(q, x[1], x[2], CascadeState(inner, outer))

    eng, _, _ = _check_jacobian(op, 3.0, build, read, pre_time=60.0)
    kinds = eng.records()["events"]["kind"]
    # two reversals push x, between them a wipe-out removes the first pushed pair again
    assert np.sum(kinds == -1) >= 2 and np.sum(kinds == 1) >= 2


def test_jacobian_started_where_the_outer_preisach_model_has_just_turned():
    """0.3 after a reversal the inner play is inside (x = w constant) and the outer Preisach
    model, fed a constant input, has not stored its turning point yet: the branch pushes it
    virtually at the start, with δM := δx = δw (pushed_gradient in start_tangent)."""
    preisach = gauss_everett_model(1.3, -6.0, 6.0)
    play = PlayOperator(2.0)
    op = Cascade(play, preisach)

    def read(state, labels):
        s = state.operator_state
        extrema = np.asarray(s.outer.extrema)
        n_out = sum(lab.startswith("out:") for lab in labels)
        assert n_out in (extrema.size - 1, extrema.size)  # pushed virtually: the input too
        return np.array([state.q, state.v, state.phi, s.inner.position, *extrema[:n_out]])

    def build(x, start, labels):
        q, w = float(x[0]), float(x[3])
        n_real = np.asarray(start.operator_state.outer.extrema).size - 1
        outer = preisach.state_from_extrema([*x[4 : 4 + n_real], w])
        return OscillatorState(q, x[1], x[2], CascadeState(play.state(w, q), outer))

    eng, jac, labels0 = _check_jacobian(op, 3.0, build, read, pre_time=60.0, not_free=("out:M1",))
    assert labels0 == ("q", "v", "phi", "in:w", "out:M1")  # M1 pushed at the start
    assert np.sum(eng.records()["events"]["kind"] == 1) >= 1  # the inner wall hit
