"""Sums of operators coupled to the forced oscillator, against independent truth.

``q'' + 2ζq' + q = cos(φ0 + Ωt) + C·M[q](t)`` with ``M = Σ a_k H_k`` (:mod:`hysteresis.algebra`).

* Trajectories against ``composite_reference`` (tests/composite_reference.py): ``solve_ivp``
  (DOP853, rtol = atol = 1e-12) with terminal events, the wagons and relay outputs moved by hand,
  nothing of the library used. The reference is first checked against the library's *single*
  operators (a play, an erf play, relays, a Prandtl–Ishlinskii operator), which proves it.
  Cases: a mixed sum (play + relays: jumps at the thresholds), a continuous sum (PI + erf
  play, on the compiled and the generic engine), relay sums (all weights >= 0: the relay
  engine on the concatenated table; a negative weight: jumps on the generic engine).
* Tangent flow: ``system.jacobian`` against central differences of ``system.stroboscopic_map``.
* Invariants: ``apply`` is the weighted sum of the parts' (bitwise where the products are
  exact), continuing from a returned state equals one long call, Σλ = −2ζ for relay-only sums
  (every saltation matrix has determinant 1), a pickled sum gives the same outputs and orbit.

Parameters: ζ = 0.2, Ω = 1.2 (|1 − Ω² + 2iζΩ| = 0.65): the responses below settle on stable
orbits of period 1 or 2 (checked: their stroboscopic points repeat), so integration errors are
not amplified along the run.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from composite_reference import RTOL, Model, PlayTerm, RelayTerm, near_switch, reference

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import (
    DiscretePreisachModel,
    GeneralizedPlay,
    PlayOperator,
    PrandtlIshlinskii,
    Relay,
    WeightedSum,
)
from hysteresis.play import PlayState
from hysteresis.prandtl_ishlinskii import PIState
from oscillators.engines import CompiledContinuousEngine
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

# a sum with a continuous part runs on the generic engine, which says so once per system
pytestmark = pytest.mark.filterwarnings("ignore:.*generic continuous engine")

ZETA, OMEGA = 0.2, 1.2
PERIOD = 2.0 * math.pi / OMEGA
T_END = 20.0 * PERIOD
SAMPLE_DT = 0.05
Q0, V0 = -1.0, 0.1
#: the generic continuous engine's default rtol; the compiled engines (closed-form relay
#: flights, fixed-step DOP853 at h = 0.05 with local error ~h⁹) are at least as accurate
ENGINE_RTOL = 1e-11

# -- the operators ------------------------------------------------------------------------------
ALPHA = (-0.6, -0.1, 0.3, 0.8)
BETA = (-1.0, -0.5, -0.2, 0.4)
RELAY_WEIGHTS = (0.1, 0.2, 0.3, 0.4)
PLAY_WIDTH, SPREAD = 1.0, 0.5
PI_WIDTHS, PI_WEIGHTS = (0.0, 0.6, 1.4), (0.3, 0.4, 0.3)


def preisach() -> DiscretePreisachModel:
    return DiscretePreisachModel(ALPHA, BETA, RELAY_WEIGHTS)


def erf_play() -> GeneralizedPlay:
    return GeneralizedPlay.erf(PLAY_WIDTH, SPREAD)


def pi() -> PrandtlIshlinskii:
    return PrandtlIshlinskii(PI_WIDTHS, PI_WEIGHTS)


def relay_terms(scale: float) -> tuple[RelayTerm, ...]:
    return tuple(
        RelayTerm(scale * w, a, b) for w, a, b in zip(RELAY_WEIGHTS, ALPHA, BETA, strict=True)
    )


def erf_term(scale: float) -> PlayTerm:
    return PlayTerm(scale, PLAY_WIDTH, SPREAD)


def pi_terms(scale: float) -> tuple[PlayTerm, ...]:
    return tuple(PlayTerm(scale * a, p) for p, a in zip(PI_WIDTHS, PI_WEIGHTS, strict=True))


def memory_of(op, state) -> tuple[np.ndarray, np.ndarray]:
    """Wagon positions and relay outputs of an operator state, in the order of the parts (a
    single operator is its own only part), as the reference's ``w`` and ``y``."""
    parts = zip(op.parts, state, strict=True) if isinstance(op, WeightedSum) else [(op, state)]
    w: list[float] = []
    y: list[float] = []
    for part, s in parts:
        if part.piecewise_constant:
            y.extend(part.relay_outputs(s))
        elif isinstance(s, PlayState):
            w.append(s.position)
        else:
            w.extend(s.positions)
    return np.array(w), np.array(y)


# -- trajectories against the reference ---------------------------------------------------------
def tolerance(ref, coupling: float, engine_rtol: float = ENGINE_RTOL) -> float:
    """Bound on |library − reference| over the run.

    Each integrator's error per segment between events is at most about its tolerance (|q|,
    |v| ≈ 1, so rtol ≈ atol); on a stable orbit the flow does not amplify it between events,
    and an event adds at most one segment's error times its saltation gain: a position error
    δq moves the switch by δt = δq/v*, which becomes a velocity error C·ΔM·δt. Summed over the
    events, with a factor 10 for the dense output and global-versus-local error:
    ``10·(rtol_ref + rtol_engine)·(1 + n_events)·max(1, max |C·ΔM/v*|)``. (Measured: 4e-12 to
    5e-12 for the single operators on the compiled engines, 4e-11 to 2e-10 for the sums on the
    generic engine, with 80–240 events; the bound is 9e-9 to 8e-8.)"""
    gains = [abs(coupling * jump / v) for _, _, _, v, jump, _ in ref.events if jump != 0.0]
    gain = max([1.0, *gains])
    return 10.0 * (RTOL + engine_rtol) * (1 + len(ref.events)) * gain


def assert_matches_reference(
    op, model: Model, coupling: float, engine_options: dict | None = None
) -> ForcedOscillator:
    """The library's trajectory of ``op`` against the reference integration of ``model``."""
    system = ForcedOscillator(op, coupling, ZETA, OMEGA)
    traj = system.trajectory(T_END, Q0, V0, sample_dt=SAMPLE_DT, engine_options=engine_options)
    ref = reference(model, coupling, ZETA, OMEGA, Q0, V0)
    # the samples and, merged in, the stroboscopic points of the last periods
    strobe = np.arange(14, 21) * PERIOD
    times = np.concatenate([traj.t, strobe])
    order = np.argsort(times, kind="stable")
    merged = np.empty((times.size, 3))
    merged[order] = ref.run(times[order])
    out, section = merged[: traj.t.size], merged[traj.t.size :]
    tol = tolerance(ref, coupling)
    np.testing.assert_allclose(traj.q, out[:, 0], rtol=0, atol=tol)
    np.testing.assert_allclose(traj.v, out[:, 1], rtol=0, atol=tol)
    # an event's time is uncertain by the state's error over the event function's speed
    window = 10.0 * tol / min(abs(e[5]) for e in ref.events)
    events = np.array([e[:2] for e in ref.events])
    if traj.events is not None:  # the continuous engines: every wall hit, switch, reversal
        np.testing.assert_array_equal(traj.events["kind"], events[:, 1])
        np.testing.assert_allclose(traj.events["time"], events[:, 0], rtol=0, atol=window)
    switches = ref.switches
    if traj.switches.size:  # the relay engine: every switch
        np.testing.assert_allclose(traj.switches["time"], switches, rtol=0, atol=window)
    # M jumps at a switch: a sample within the switch-time uncertainty may fall on either side
    away = ~near_switch(traj.t, switches, window)
    np.testing.assert_allclose(traj.M[away], out[away, 2], rtol=0, atol=tol)
    # the operator state handed back holds the reference's memory at the end
    w, y = memory_of(op, traj.final.operator_state)
    np.testing.assert_allclose(w, ref.w, rtol=0, atol=tol)
    np.testing.assert_array_equal(y, ref.y)
    # a non-trivial orbit: many events, the relays switched again and again
    assert len(ref.events) > 40
    if model.relays:
        assert switches.size >= 2 * len(model.relays) * 5
    # a stable periodic response (period 1 or 2): the last stroboscopic points repeat, so the
    # run does not amplify integration errors
    x = section[:, :2]
    assert min(np.max(np.abs(x[p:] - x[:-p])) for p in (1, 2)) < 1e-6, x
    return system


@pytest.mark.parametrize(
    ("make", "model", "coupling"),
    [
        (lambda: PlayOperator(PLAY_WIDTH), Model(plays=(PlayTerm(1.0, PLAY_WIDTH),)), 0.6),
        (erf_play, Model(plays=(erf_term(1.0),)), 0.6),
        (preisach, Model(relays=relay_terms(1.0)), 0.3),
        (preisach, Model(relays=relay_terms(1.0)), -0.5),
        (pi, Model(plays=pi_terms(1.0)), 0.6),
    ],
    ids=["play", "erf-play", "preisach-0.3", "preisach-neg", "pi"],
)
def test_reference_agrees_with_single_operators(make, model, coupling):
    """The reference against the library's own engines for one operator (play kernel, relay
    kernel, compiled PI engine): two independent integrators agree, which proves the
    reference for the sums below."""
    assert_matches_reference(make(), model, coupling)


@pytest.mark.parametrize("coupling", [0.3, 0.6, -0.5])
def test_mixed_sum_erf_play_plus_relays(coupling):
    """``0.5·erf play + 0.5·Preisach``: a hybrid orbit, continuous branches with jumps of the
    output at the relay thresholds."""
    op = 0.5 * erf_play() + 0.5 * preisach()
    assert_matches_reference(op, Model((erf_term(0.5),), relay_terms(0.5)), coupling)


def test_mixed_sum_plain_play_plus_relays():
    op = 0.5 * PlayOperator(PLAY_WIDTH) + 0.5 * preisach()
    model = Model((PlayTerm(0.5, PLAY_WIDTH),), relay_terms(0.5))
    assert_matches_reference(op, model, 1.0)


@pytest.mark.parametrize("method", ["auto", "generic"])
@pytest.mark.parametrize("coupling", [0.4, 0.8])
def test_continuous_sum_pi_plus_erf_play(coupling, method):
    """``0.7·PI + 0.3·erf play``: the compiled continuous engine (a PI kernel with shaped
    plays) and the generic engine over the assembled branch flow."""
    op = 0.7 * pi() + 0.3 * erf_play()
    model = Model(pi_terms(0.7) + (erf_term(0.3),))
    system = assert_matches_reference(op, model, coupling, {"method": method})
    assert system.engine_class is CompiledContinuousEngine


def test_relay_sum_runs_on_the_concatenated_table():
    """Relay + Preisach, weights >= 0: one relay table (the relay engine)."""
    op = 0.4 * Relay(0.5, -0.3) + 0.6 * preisach()
    assert op.piecewise_constant
    model = Model(relays=(RelayTerm(0.4, 0.5, -0.3),) + relay_terms(0.6))
    assert_matches_reference(op, model, 0.3)


def _negative_relays():
    return 1.5 * Relay(0.2, -0.7) - 0.5 * preisach()


def _negative_relays_model():
    return Model(relays=(RelayTerm(1.5, 0.2, -0.7),) + relay_terms(-0.5))


def _play_minus_relays():
    return erf_play() - 0.3 * preisach()


def _play_minus_relays_model():
    return Model((erf_term(1.0),), relay_terms(-0.3))


@pytest.mark.parametrize(
    ("make", "model", "coupling"),
    [
        (_negative_relays, _negative_relays_model, 0.2),
        (_negative_relays, _negative_relays_model, 0.4),
        (_play_minus_relays, _play_minus_relays_model, 0.4),
        (_play_minus_relays, _play_minus_relays_model, 1.0),
    ],
    ids=["relays-0.2", "relays-0.4", "erf-play-0.4", "erf-play-1.0"],
)
def test_sum_with_a_negative_weight(make, model, coupling):
    """A relay-type part of negative weight (no relay table holds it: jumps on the generic
    engine); they go against the input. At C = 0.4 the relay sum's orbit has period 2 and a
    switch at |v*| = 0.07 (saltation gain 3.9)."""
    assert_matches_reference(make(), model(), coupling)


# -- the tangent: Jacobian of the stroboscopic map against central differences ----------------
#: step of the central differences. Error estimate: truncation |F'''|·h²/6 (measured: about
#: 1.4·h² for the mixed orbit, 0.25·h² for the continuous one) plus the map's evaluation error
#: over 2h: the generic engine integrates at rtol 1e-11, and if its error were uncorrelated
#: between the ±h runs (adaptive steps) that is ε/h ≈ 1e-7 at h = 1e-4 (the compiled engine's
#: fixed steps make the map smooth: round-off only), plus the tangent flow's own error (same
#: rtol, ~1e-10). The optimum of h² + ε/h is h ≈ ε^(1/3) ≈ 2e-4.
FD_STEP = 1e-4
#: the bound of that estimate (1.4e-8 + 1e-7 + 1e-10) with a factor 8 (measured: 1.4e-8 for
#: the mixed sum, 2.5e-9 for the continuous one on either engine)
FD_TOL = 1e-6


def rebuilt(op, state, q: float, memory: dict[str, float]):
    """The sum's state with the input at ``q`` and the wagon positions ``memory`` (by the
    tangent-space labels ``"k:w"``, ``"k:w{i}"``), relays unchanged."""
    parts = []
    for k, (part, s) in enumerate(zip(op.parts, state, strict=True)):
        if part.piecewise_constant:
            parts.append(part.state_from_relay_outputs(part.relay_outputs(s), q))
        elif isinstance(s, PlayState):
            parts.append(part.state(memory[f"{k}:w"], q))
        else:
            positions = [memory[f"{k}:w{i}"] for i in range(len(s.positions))]
            parts.append(part.state(positions, q))
    return op.state(*parts)


def labelled_memory(op, state) -> dict[str, float]:
    """The wagon positions of a sum's state by tangent-space label."""
    out = {}
    for k, s in enumerate(state):
        if isinstance(s, PlayState):
            out[f"{k}:w"] = s.position
        elif isinstance(s, PIState):
            out.update({f"{k}:w{i}": float(x) for i, x in enumerate(s.positions)})
    return out


def slaved_at(op, state, direction: int) -> dict[str, bool]:
    """Which wagons the input drags at ``state`` (finger on the wall it pushes), by hand."""
    out = {}
    for k, (part, s) in enumerate(zip(op.parts, state, strict=True)):
        if part.piecewise_constant:
            continue
        positions = [s.position] if isinstance(s, PlayState) else list(s.positions)
        widths = [part.width] if isinstance(s, PlayState) else list(part.widths)
        names = ["w"] if isinstance(s, PlayState) else [f"w{i}" for i in range(len(widths))]
        for name, w, p in zip(names, positions, widths, strict=True):
            out[f"{k}:{name}"] = direction * (s.input - w) >= 0.5 * p - 1e-12
    return out


def start_after_reversal(system: ForcedOscillator, options: dict) -> OscillatorState:
    """A state on the settled orbit 0.3 after its first reversal past 10 periods: every wagon
    of positive width frozen inside (a reversal frees them all, and 0.3 later the input has
    moved ~0.05, less than any wall distance 2r >= 0.6)."""
    traj = system.trajectory(12.0 * PERIOD, Q0, V0, sample_dt=0.1, engine_options=options)
    events = traj.events
    t_rev = events["time"][(events["kind"] == -1) & (events["time"] > 10.0 * PERIOD)][0]
    return system.trajectory(t_rev + 0.3, Q0, V0, sample_dt=0.1, engine_options=options).final


@pytest.mark.parametrize(
    ("make", "coupling", "method"),
    [
        (lambda: 0.5 * erf_play() + 0.5 * preisach(), 0.6, "auto"),
        (lambda: 0.7 * pi() + 0.3 * erf_play(), 0.4, "auto"),
        (lambda: 0.7 * pi() + 0.3 * erf_play(), 0.4, "generic"),
    ],
    ids=["mixed", "continuous-compiled", "continuous-generic"],
)
def test_jacobian_matches_central_differences_of_the_stroboscopic_map(make, coupling, method):
    """``system.jacobian(T)`` (the engine's tangent flow: memory rows frozen / slaved / reset
    at walls, the saltation ``δv += C·Δy/v*·δq`` at relay jumps) against central differences
    of ``system.stroboscopic_map`` in ``(q, v, φ, wagons)``. A wagon dragged at the start is
    slaved (``δw = δq``, its column zero by the engine's one-sided convention): it moves with
    ``q`` in the ``q`` column."""
    op = make()
    system = ForcedOscillator(op, coupling, ZETA, OMEGA)
    options = {"method": method}
    base = start_after_reversal(system, options)
    jac, labels = system.jacobian(PERIOD, base, include_phase=True, engine_options=options)
    memory = labelled_memory(op, base.operator_state)
    assert labels == ("q", "v", "phi", *memory)
    slaved = slaved_at(op, base.operator_state, 1 if base.v > 0 else -1)
    assert sum(slaved.values()) == (1 if "0:w0" in memory else 0)  # only PI's width-0 play
    x0 = np.array([base.q, base.v, base.phi, *memory.values()])

    def strobe(x):
        memory_x = dict(zip(labels[3:], x[3:], strict=True))
        state = OscillatorState(x[0], x[1], x[2], rebuilt(op, base.operator_state, x[0], memory_x))
        end = system.stroboscopic_map(state, engine_options=options)
        return np.array([end.q, end.v, end.phi, *labelled_memory(op, end.operator_state).values()])

    fd = np.zeros_like(jac)
    for j, label in enumerate(labels):
        if slaved.get(label, False):
            np.testing.assert_array_equal(jac[:, j], 0.0)
            continue
        step = np.zeros(x0.size)
        step[j] = FD_STEP
        if label == "q":
            step[3:] = [FD_STEP if slaved[lab] else 0.0 for lab in labels[3:]]
        diff = strobe(x0 + step) - strobe(x0 - step)
        diff[2] = math.remainder(diff[2], 2.0 * math.pi)  # the phase is wrapped
        fd[:, j] = diff / (2.0 * FD_STEP)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=FD_TOL * max(1.0, np.max(np.abs(jac))))
    # the period crosses what the tangent must get right: relay jumps (the mixed sum) and wall
    # hits, none of them at a turning point (no grazing: the map is smooth at x0)
    traj = system.trajectory(
        PERIOD, base.q, base.v, base.operator_state, 0.01, base.phi, engine_options=options
    )
    events = traj.events
    assert np.count_nonzero(events["kind"] >= 1) >= 2
    turning = events["q"][events["kind"] == -1]
    for k, part in enumerate(op.parts):
        if part.piecewise_constant:
            thresholds = np.concatenate([ALPHA, BETA])
            assert np.min(np.abs(turning[:, None] - thresholds[None, :])) > 0.05
            y, _ = part.apply(traj.q, base.operator_state[k])
            assert np.count_nonzero(np.diff(y)) >= 2


# -- invariants --------------------------------------------------------------------------------
def _inputs(seed: int = 7, n: int = 400) -> np.ndarray:
    """A random walk over [-2.5, 2.5] with many reversals: it moves every wall and threshold."""
    rng = np.random.default_rng(seed)
    return np.clip(np.cumsum(rng.normal(0.0, 0.25, n)), -2.5, 2.5)


@pytest.mark.parametrize(
    ("first", "second"),
    [(erf_play, preisach), (pi, erf_play), (lambda: Relay(0.5, -0.3), preisach)],
    ids=["mixed", "continuous", "relays"],
)
def test_apply_is_the_weighted_sum_of_the_parts(first, second):
    """Weights 1 and 0.5: both products are exact, so the sum is one correctly rounded addition
    whatever the order: bitwise. Any weights, three parts (nested sums flatten): each product
    and addition rounds once, so within 3ε·Σ|a_k y_k| (n = 3)."""
    a, b = first(), second()
    u = _inputs()
    ya, _ = a.apply(u)
    yb, _ = b.apply(u)
    y, _ = (a + 0.5 * b).apply(u)
    np.testing.assert_array_equal(y, ya + 0.5 * yb)
    c = PlayOperator(0.8)
    yc, _ = c.apply(u)
    nested = (0.7 * a - 0.2 * b) + 0.1 * (3.0 * c)
    assert len(nested.parts) == 3
    y, _ = nested.apply(u)
    terms = np.stack([0.7 * ya, -0.2 * yb, 0.3 * yc])
    bound = 3.0 * np.finfo(float).eps * np.sum(np.abs(terms), axis=0)
    assert np.all(np.abs(y - terms.sum(axis=0)) <= bound)


@pytest.mark.parametrize(
    "make",
    [
        lambda: 0.5 * erf_play() + 0.5 * preisach(),
        lambda: 0.7 * pi() + 0.3 * erf_play(),
        lambda: 0.4 * Relay(0.5, -0.3) + 0.6 * preisach(),
        lambda: 1.5 * Relay(0.2, -0.7) - 0.5 * preisach(),
    ],
    ids=["mixed", "continuous", "relays", "negative"],
)
def test_continuing_from_a_returned_state_equals_one_long_call(make):
    op = make()
    u = _inputs()
    y, state = op.apply(u)
    y1, s1 = op.apply(u[:157])
    y2, s2 = op.apply(u[157:], s1)
    np.testing.assert_array_equal(np.concatenate([y1, y2]), y)
    # the two final states are the same memory: they answer any further input alike
    more = _inputs(seed=8)
    np.testing.assert_array_equal(op.apply(more, s2)[0], op.apply(more, state)[0])


@pytest.mark.parametrize(
    ("make", "coupling", "tol"),
    [
        # the relay engine: closed-form flights, det = 1 saltations; round-off only
        (lambda: 0.4 * Relay(0.5, -0.3) + 0.6 * preisach(), 0.3, 1e-14),
        # the generic engine (negative weight): variational equations at rtol 1e-11, about 30
        # steps per period T = 5.2: log-det error per period <= 30·1e-11, over T: 6e-11
        (lambda: 1.5 * Relay(0.2, -0.7) - 0.5 * preisach(), 0.4, 1e-9),
    ],
    ids=["relay-engine", "generic-engine"],
)
def test_relay_only_sum_contracts_phase_space_at_minus_two_zeta(make, coupling, tol):
    """Σλ = −2ζ in (q, v): the linear flow contracts areas at e^{−2ζt} and every saltation
    matrix ``[[1, 0], [C·ΔM/v*, 1]]`` has determinant 1."""
    system = ForcedOscillator(make(), coupling, ZETA, OMEGA)
    result = lyapunov_spectrum(system, 40.0 * PERIOD, 5.0 * PERIOD)
    assert result.tangent_space == ("q", "v")
    assert result.n_switches > 100
    assert abs(np.sum(result.exponents) + 2.0 * ZETA) <= tol


@pytest.mark.parametrize(
    "make",
    [
        lambda: 0.5 * erf_play() + 0.5 * preisach(),
        lambda: 0.7 * pi() + 0.3 * erf_play(),
        lambda: 0.4 * Relay(0.5, -0.3) + 0.6 * preisach(),
    ],
    ids=["mixed", "continuous", "relays"],
)
def test_pickled_sum_gives_the_same_outputs_and_orbit(make):
    op = make()
    if op.piecewise_constant:
        op.relay_table()  # a cached table must not travel (or be stale)
    copy = pickle.loads(pickle.dumps(op))
    assert type(copy) is type(op) and np.array_equal(copy.weights, op.weights)
    u = _inputs()
    y, state = op.apply(u)
    np.testing.assert_array_equal(copy.apply(u)[0], y)
    more = _inputs(seed=8)
    np.testing.assert_array_equal(copy.apply(more, state)[0], op.apply(more, state)[0])
    a = ForcedOscillator(op, 0.6, ZETA, OMEGA).trajectory(2.0 * PERIOD, Q0, V0)
    b = ForcedOscillator(copy, 0.6, ZETA, OMEGA).trajectory(2.0 * PERIOD, Q0, V0)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.M, b.M)
