"""The operator algebra (hysteresis/algebra.py): sums are operators of the contract.

Independent truths: the parts' own ``apply`` (a sum's outputs are their weighted sum, exactly),
the relay-by-relay reference of the contract (``PiecewiseConstantHysteron.apply``, O(N) per
input), finite differences of ``apply`` for the assembled branch partials, and the identified
Preisach density (a sum's FORC masses are the weighted sum of the parts' masses).
"""

from __future__ import annotations

import math
import pickle
import warnings

import numpy as np
import pytest

from analysis.identification import identify_preisach
from hysteresis import (
    BranchSum,
    GeneralizedPlay,
    PiecewiseConstantHysteron,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    Relay,
    RelaySum,
    SpinDimerEnsemble,
    SumState,
    WeightedSum,
    weighted_sum,
)
from oscillators import ForcedOscillator, OscillatorState
from oscillators.engines import (
    CompiledContinuousEngine,
    ContinuousEngine,
    GenericEngineWarning,
    RelayEngine,
)


def _walk(seed: int, n: int = 400, scale: float = 3.0) -> np.ndarray:
    """A random input history with many reversals (minor loops inside major ones)."""
    rng = np.random.default_rng(seed)
    return scale * np.tanh(np.cumsum(rng.normal(0.0, 0.35, n)))


def _relays(seed: int, n: int = 30) -> PreisachModel:
    rng = np.random.default_rng(seed)
    beta = rng.uniform(-2.0, 1.5, n)
    alpha = beta + rng.uniform(0.0, 1.0, n)
    weights = rng.uniform(0.5, 1.5, n)
    return PreisachModel.from_relays(alpha, beta, weights / weights.sum())


PARTS = {
    "play": PlayOperator(0.8),
    "erf": GeneralizedPlay.erf(1.0, 0.7),
    "pi": PrandtlIshlinskii([0.0, 0.5, 1.5], [0.3, 0.4, 0.2]),
    "relay": Relay(0.4, -0.6),
    "relays": _relays(1),
    "dimers": SpinDimerEnsemble.random(40, width=0.6, spread=1.0, spin_coupling=0.5, seed=3),
}


@pytest.mark.parametrize(
    ("names", "weights"),
    [
        (("erf", "relays"), (0.6, 0.4)),
        (("pi", "erf"), (0.7, 0.3)),
        (("play", "relay", "dimers"), (1.0, -2.0, 0.5)),
        (("relays", "dimers", "relay"), (0.25, 0.5, 3.0)),
    ],
)
def test_sum_outputs_are_the_weighted_sum_of_the_parts(names, weights):
    ops = [PARTS[n] for n in names]
    total = weighted_sum(ops, weights)
    built = sum((w * op for w, op in zip(weights, ops, strict=True)), start=0)
    u = _walk(7)
    y, state = total.apply(u)
    expected = np.zeros(u.size)
    for w, op in zip(weights, ops, strict=True):
        expected = expected + w * op.apply(u)[0]  # the documented order of summation
    np.testing.assert_array_equal(y, expected)
    np.testing.assert_array_equal(built.apply(u)[0], expected)
    assert isinstance(state, SumState) and len(state) == len(ops)
    assert total.output(state) == pytest.approx(y[-1], abs=1e-14)
    # continuing from a returned state equals one long call
    y1, s1 = total.apply(u[:173])
    y2, s2 = total.apply(u[173:], s1)
    np.testing.assert_array_equal(np.concatenate([y1, y2]), y)
    assert total.output(s2) == total.output(state)


def test_family_follows_the_parts():
    relays, erf = PARTS["relays"], PARTS["erf"]
    assert isinstance(relays + 2 * PARTS["relay"], RelaySum)
    assert (relays + PARTS["relay"]).piecewise_constant
    assert isinstance(0.5 * erf + 0.5 * relays, BranchSum)
    # a negative weight has no relay table with weights >= 0: the branch-flow family
    assert isinstance(relays - PARTS["relay"], BranchSum)
    assert isinstance(-relays, BranchSum)


def test_nested_sums_flatten():
    a, b, c = PARTS["play"], PARTS["erf"], PARTS["relays"]
    s = (0.5 * a + 0.25 * b) + 2.0 * (3.0 * c)
    assert s.parts == (a, b, c)
    np.testing.assert_array_equal(s.weights, [0.5, 0.25, 6.0])
    d = a - (b - c)
    assert d.parts == (a, b, c)
    np.testing.assert_array_equal(d.weights, [1.0, -1.0, 1.0])


def test_relay_sum_matches_relay_by_relay_reference():
    s = 0.3 * PARTS["relays"] + 0.7 * PARTS["dimers"] + 2.0 * PARTS["relay"]
    table = s.relay_table()
    n = sum(p.relay_table().n_relays for p in s.parts)
    assert table.n_relays == n
    u = _walk(11)
    y, state = s.apply(u)
    y_ref, state_ref = PiecewiseConstantHysteron.apply(s, u)  # every relay driven one by one
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(s.relay_outputs(state), s.relay_outputs(state_ref))
    # the next switches read from the parts agree with the ones read from the table
    for k in range(0, u.size, 37):
        _, st = s.apply(u[: k + 1])
        fast, ref = s.switching(st), PiecewiseConstantHysteron.switching(s, st)
        assert (fast.lower, fast.upper) == (ref.lower, ref.upper)
        assert fast.jump_up == pytest.approx(ref.jump_up, abs=1e-14)
        assert fast.jump_down == pytest.approx(ref.jump_down, abs=1e-14)
    back = s.state_from_relay_outputs(s.relay_outputs(state), state.input)
    assert s.output(back) == pytest.approx(s.output(state), abs=1e-14)


def test_branch_partials_match_finite_differences():
    s = 0.6 * PARTS["erf"] + 0.3 * PARTS["pi"] + 0.1 * PARTS["relays"]
    u = _walk(5, n=60, scale=1.0)
    _, state = s.apply(u)
    for direction in (1, -1):
        flow = s.branch_flow(state, direction)
        u0 = flow.input
        assert flow.labels == ("0:w", "1:w0", "1:w1", "1:w2")
        # a step along the branch, short of its end: the output follows flow.output
        h = 1e-6 * direction
        assert (flow.breakpoint - u0) * direction > abs(h)
        y_step = s.apply([u0, u0 + h], state)[0][-1]
        assert y_step == pytest.approx(float(flow.output(u0 + h)), abs=1e-15)
        # the slope: central difference of the branch, error O(h² f''') + O(ε/h)
        fd = (float(flow.output(u0 + h)) - float(flow.output(u0 - h))) / (2 * h)
        assert float(flow.slope(u0)) == pytest.approx(fd, abs=1e-8)


def test_breakpoint_is_the_next_relay_switch_with_its_jump():
    relay = Relay(0.5, -0.5)
    s = PlayOperator(4.0) + 0.25 * relay  # the play stays inside: flat, no breakpoint of its own
    state = s.initial_state(0.0)  # relay down, play wagon at -2
    up = s.branch_flow(state, 1)
    assert up.breakpoint == 0.5 and up.breakpoint_jump == 0.5
    y, st = s.apply([0.2, 0.5])  # u >= α switches
    assert y[1] - y[0] == pytest.approx(0.5 + 0.3)  # the jump plus the play dragged by 0.3
    down = s.branch_flow(st, -1)
    assert down.breakpoint == math.nextafter(-0.5, -math.inf)
    assert down.breakpoint_jump == -0.5
    # the relay convention u < β: at β itself it has not switched, one float below it has
    assert s.apply([-0.5], st)[0][0] > s.apply([down.breakpoint], st)[0][0] + 0.49


def test_sum_of_forc_densities_is_the_weighted_sum():
    a, b = PARTS["relays"], _relays(9)
    step, sat = 0.25, 3.5
    ra = identify_preisach(a, step, sat)
    rb = identify_preisach(b, step, sat)
    rs = identify_preisach(0.3 * a + 0.7 * b, step, sat)
    # the masses are differences of outputs: linear in the operator up to round-off of O(1)
    np.testing.assert_allclose(
        rs.cell_mass, 0.3 * ra.cell_mass + 0.7 * rb.cell_mass, rtol=0, atol=1e-12
    )


def test_pickle_round_trip():
    s = 0.6 * PARTS["erf"] + 0.4 * PARTS["relays"]
    copy = pickle.loads(pickle.dumps(s))
    u = _walk(2)
    np.testing.assert_array_equal(copy.apply(u)[0], s.apply(u)[0])
    st = pickle.loads(pickle.dumps(s.apply(u)[1]))
    assert isinstance(st, SumState)
    r = pickle.loads(pickle.dumps(PARTS["relays"] + PARTS["relay"]))
    np.testing.assert_array_equal(r.apply(u)[0], (PARTS["relays"] + PARTS["relay"]).apply(u)[0])


def test_ranges_and_slopes_follow_the_parts():
    s = 0.5 * PARTS["erf"] - 2.0 * PARTS["relay"]
    assert s.output_range == (-2.5, 2.5)
    assert s.max_slope == 0.5 / (0.7 * math.sqrt(2.0 * math.pi))  # erf' at 0; relays flat
    custom = GeneralizedPlay(1.0, np.tanh, lambda w: 1.0 / np.cosh(w) ** 2)
    assert (custom + PARTS["relay"]).max_slope is None  # a user's shape: not known
    p = 2.0 * PlayOperator(1.0) - 0.5 * PrandtlIshlinskii([0.0, 1.0], [1.0, 1.0])
    assert p.max_slope == 2.0 - 0.5 * 1.0  # the PI rises at least with its linear weight 1
    assert p.output_range == (-math.inf, math.inf)


@pytest.mark.parametrize(
    ("weight", "error"),
    [(math.nan, ValueError), (math.inf, ValueError), (1j, TypeError), ("2", TypeError)],
)
def test_bad_weights_are_refused(weight, error):
    with pytest.raises(error, match="weight"):
        weighted_sum([PARTS["play"]], [weight])
    if isinstance(weight, float):
        with pytest.raises(error, match="weight"):
            weight * PARTS["play"]


def test_bad_operands_and_states_are_refused():
    play = PARTS["play"]
    with pytest.raises(TypeError, match="StaticMap"):
        play + 1.0
    with pytest.raises(TypeError, match="Cascade"):
        play * play
    s = play + PARTS["relay"]
    with pytest.raises(TypeError, match="SumState"):
        s.apply([0.0], play.initial_state(0.0))
    with pytest.raises(ValueError, match="one state per part"):
        s.apply([0.0], SumState([play.initial_state(0.0)]))
    with pytest.raises(ValueError, match="one input"):
        s.state(play.initial_state(0.0), PARTS["relay"].initial_state(1.0))
    assert 0 + play is play
    with pytest.raises(TypeError, match="weighted_sum"):
        WeightedSum([play], [1.0])


def test_coupling_picks_the_engine_from_the_family_and_says_so():
    relays = PARTS["relays"] + PARTS["relay"]
    assert ForcedOscillator(relays, coupling=1.0).engine_class is RelayEngine
    mixed = ForcedOscillator(0.5 * PARTS["erf"] + 0.5 * PARTS["relays"], coupling=1.0)
    assert mixed.engine_class is CompiledContinuousEngine
    assert mixed.engine_description == "compiled continuous engine"
    # a continuous Preisach model has its own compiled engine, not one shared with plays
    preisach = PreisachModel.from_everett(lambda a, b: ((a - b) / 4.0) ** 2, -2.0, 2.0)
    with pytest.warns(GenericEngineWarning, match="GeneralizedPlay, ContinuousPreisachModel"):
        system = ForcedOscillator(0.5 * PARTS["erf"] + 0.5 * preisach, coupling=1.0)
    assert system.engine_class is ContinuousEngine
    assert "Python path" in system.engine_description


def test_relay_sum_on_the_kernel_matches_the_reference_engine():
    """The concatenated table on the compiled relay kernel against the Python reference path
    (switching() of the sum, derived from its parts)."""
    s = 0.5 * PARTS["relays"] + 0.5 * PARTS["dimers"]
    system = ForcedOscillator(s, coupling=1.5, damping_ratio=0.1, frequency=1.2)
    fast = system.trajectory(30.0)
    ref = system.trajectory(30.0, engine_options={"method": "generic"})
    np.testing.assert_allclose(fast.q, ref.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.M, ref.M, rtol=0, atol=1e-12)


def test_mixed_sum_jacobian_matches_finite_differences_of_the_map():
    """A play plus relays: the tangent flow with the jump saltations against central
    differences of the stroboscopic map in (q, v) (h = 1e-6: truncation ~h²·|P'''| and
    round-off ~1e-11/h from the engine's rtol, both below 1e-5)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GenericEngineWarning)
        system = ForcedOscillator(
            0.6 * GeneralizedPlay.erf(1.0, 0.5) + 0.4 * Relay(0.5, -0.3),
            coupling=1.0,
            damping_ratio=0.1,
            frequency=1.0,
        )
    start = OscillatorState(q=0.3, v=0.5, phi=0.0, operator_state=None, t=0.0)
    jac, labels = system.jacobian(system.period, start, include_phase=False)
    assert labels == ("q", "v", "0:w")
    engine = system.engine(start)
    engine.advance(np.array([system.period]), None, True)
    events = engine.records()["events"]
    assert np.sum(events["kind"] == 2) >= 2  # the relay switched up and down on the way

    def mapped(q: float, v: float) -> np.ndarray:
        end = system.stroboscopic_map(OscillatorState(q=q, v=v, phi=0.0, operator_state=None))
        return np.array([end.q, end.v])

    h = 1e-6
    fd_q = (mapped(0.3 + h, 0.5) - mapped(0.3 - h, 0.5)) / (2 * h)
    fd_v = (mapped(0.3, 0.5 + h) - mapped(0.3, 0.5 - h)) / (2 * h)
    # the start is on the rising branch at the initial state: w = q − p/2 moves with q, so the
    # q column of the map is J[:, q] + J[:, w]
    np.testing.assert_allclose(jac[:2, 0] + jac[:2, 2], fd_q, rtol=0, atol=1e-5)
    np.testing.assert_allclose(jac[:2, 1], fd_v, rtol=0, atol=1e-5)


def test_sum_of_plays_runs_on_the_compiled_engine_as_on_the_generic_one():
    """PI + erf play + play is one set of shaped plays for the compiled continuous engine:
    trajectory and Jacobian against the generic engine over the assembled branch flow
    (DOP853 rtol 1e-11 there, RK8 h = 0.05/ρ here: both ~1e-10 over 15 periods of a stable
    response)."""
    s = 0.7 * PARTS["pi"] + 0.3 * PARTS["erf"] - 0.1 * PlayOperator(0.4)
    with warnings.catch_warnings():
        warnings.simplefilter("error", GenericEngineWarning)  # no Python path: no warning
        system = ForcedOscillator(s, coupling=1.0, damping_ratio=0.1, frequency=1.1)
    assert system.engine_class is CompiledContinuousEngine
    fast = system.trajectory(80.0)
    ref = system.trajectory(80.0, engine_options={"method": "generic"})
    np.testing.assert_allclose(fast.q, ref.q, rtol=0, atol=5e-9)
    np.testing.assert_allclose(fast.M, ref.M, rtol=0, atol=5e-9)
    start = OscillatorState(q=0.3, v=0.5, phi=0.0, operator_state=None)
    jac, labels = system.jacobian(3 * system.period, start)
    jac_ref, labels_ref = system.jacobian(
        3 * system.period, start, engine_options={"method": "generic"}
    )
    assert labels == labels_ref == ("q", "v", "phi", "0:w0", "0:w1", "0:w2", "1:w", "2:w")
    np.testing.assert_allclose(jac, jac_ref, rtol=0, atol=1e-8)
    # the final states are SumStates the parts accept
    end = system.stroboscopic_map(start)
    assert isinstance(end.operator_state, SumState)
    end_ref = system.stroboscopic_map(start, engine_options={"method": "generic"})
    assert s.output(end.operator_state) == pytest.approx(s.output(end_ref.operator_state), abs=1e-9)


@pytest.mark.parametrize("method", ["auto", "generic"])
def test_a_composite_trajectory_lists_its_relay_switches(method):
    """The relays of a play + relays switch on the continuous engines: the trajectory's
    ``switches`` lists them (events of kind 2), each jump the switched relays' weighted 2w,
    and the output samples jump by it there."""
    relay = Relay(0.5, -0.5)
    s = 0.6 * GeneralizedPlay.erf(1.0, 0.5) + 0.4 * relay
    system = ForcedOscillator(s, coupling=1.0, damping_ratio=0.1, frequency=1.0)
    traj = system.trajectory(30.0, engine_options={"method": method})
    sw = traj.switches
    assert sw.size >= 4
    np.testing.assert_allclose(np.abs(sw["jump"]), 0.8, rtol=0, atol=1e-15)
    assert np.all(np.diff(np.sign(sw["jump"])) != 0)  # up, down, up, ...
    up = sw["jump"] > 0
    np.testing.assert_allclose(sw["q"][up], 0.5, atol=1e-12)
    np.testing.assert_allclose(sw["q"][~up], -0.5, atol=1e-12)


def test_inverse_of_any_operator_and_of_a_sum():
    """``op.inverse()``: the closed form where one exists (PI), the numeric inverse of a sum
    with strictly increasing branches (its least slope: the weighted least slopes), and a
    one-line refusal for jumps and flat branches."""
    from hysteresis import InverseOperator

    pi = PARTS["pi"]
    assert isinstance(pi.inverse(), PrandtlIshlinskii)
    s = 0.5 * pi + 0.5 * PARTS["erf"]
    assert s.min_slope == 0.5 * pi.min_slope  # the erf play is flat inside: 0
    inverse = s.inverse()
    assert isinstance(inverse, InverseOperator)
    y = s.apply(_walk(3, n=200, scale=2.0))[0]
    u = inverse.apply(y)[0]
    np.testing.assert_allclose(s.apply(u)[0], y, rtol=0, atol=1e-10 * np.max(np.abs(y)))
    for op, why in ((PARTS["play"], "flat"), (PARTS["relays"], "jumps")):
        with pytest.raises(ValueError, match=why) as info:
            op.inverse()
        assert "\n" not in str(info.value)


def test_slope_bounds_of_a_sum_use_each_part_on_its_side():
    play = PlayOperator(1.0)  # slopes in [0, 1]
    assert (-1.0 * play).max_slope == 0.0  # -play never rises
    assert (-1.0 * play).min_slope == -1.0
    assert (2.0 * play - 0.5 * play).max_slope == 2.0


def _tanh_slope(u):
    return 1.0 / np.cosh(u) ** 2


def test_sum_of_a_cascade_and_an_inverse_carries_their_driven_memory():
    """Parts whose memory is driven (a cascade's outer wagons follow the inner output, an
    inverse's forward wagons follow u(y)): the sum composes their driven variables and pushed
    gradients, so its Jacobian matches central differences of the stroboscopic map in every
    coordinate the map has (q, v, φ and the memory rows frozen at the start)."""
    from hysteresis import Cascade, InverseOperator, StaticMap

    inner = PrandtlIshlinskii([0.0, 0.6], [0.5, 0.5])
    cascade = Cascade(inner, PlayOperator(0.8))
    inverse = InverseOperator(PrandtlIshlinskii([0.0, 1.0], [1.0, 0.5]))
    s = 0.5 * cascade + 0.3 * inverse + 0.2 * StaticMap(np.tanh, _tanh_slope)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GenericEngineWarning)
        system = ForcedOscillator(s, coupling=0.6, damping_ratio=0.1, frequency=1.0)
    start = system.stroboscopic_map(OscillatorState(q=0.4, v=-0.3, phi=0.0, operator_state=None))
    start = OscillatorState(q=start.q, v=start.v, phi=0.0, operator_state=start.operator_state)
    jac, labels = system.jacobian(system.period, start, include_phase=False)
    h = 1e-6  # truncation ~h² |P'''| and round-off ~1e-11/h (the engine's rtol): both < 1e-5

    def mapped(dq: float, dv: float) -> np.ndarray:
        shifted = OscillatorState(
            q=start.q + dq,
            v=start.v + dv,
            phi=0.0,
            operator_state=s.apply([start.q + dq], start.operator_state)[1],
        )
        end = system.stroboscopic_map(shifted)
        return np.array([end.q, end.v])

    # a shift of q at the start also moves the memory that is dragged there (its rows are
    # δq); the q column of the map is then J[:, q] + Σ_dragged J[:, m]
    fd_v = (mapped(0.0, h) - mapped(0.0, -h)) / (2 * h)
    np.testing.assert_allclose(jac[:2, 1], fd_v, rtol=0, atol=1e-5)
    assert labels[:2] == ("q", "v") and all(":" in lab for lab in labels[2:])
