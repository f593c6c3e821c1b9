"""Cascade (hysteresis.cascade) against independent truths.

* ``apply`` against the composition written out by hand (the play and Prandtl–Ishlinskii
  recursions ``w = max(x − r, min(x + r, w))`` on the mapped input) and against
  ``GeneralizedPlay`` (a play followed by a static map *is* the generalized play);
* the composite branch flow against central differences of the cascade's own ``apply``:
  output, slope, memory partials, the driven variables' values and gradients, the pushed
  gradient, the breakpoint's motion with the memory; the breakpoint against the first input at
  which ``apply`` changes the memory structure or jumps;
* the refusals and the bookkeeping (initial state, ranges, slopes, pickling).
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from relay_test_support import gauss_everett_model

from hysteresis import (
    GeneralizedPlay,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    Relay,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.cascade import Cascade, CascadeState
from hysteresis.static_map import StaticMap

EPS = np.finfo(np.float64).eps
H = 1e-6


def f_in(u):
    """An increasing input nonlinearity (f' in [0.3, 1.5])."""
    return 1.2 * np.tanh(u) + 0.3 * np.asarray(u)


def f_in_derivative(u):
    return 1.2 / np.cosh(u) ** 2 + 0.3


def g_out(x):
    """An increasing output map."""
    return np.asarray(x) + 0.2 * np.asarray(x) ** 3


def g_out_derivative(x):
    return 1.0 + 0.6 * np.asarray(x) ** 2


F = StaticMap(f_in, f_in_derivative)
G = StaticMap(g_out, g_out_derivative)
PI = PrandtlIshlinskii([0.0, 0.6, 1.5, 2.4], [0.2, 0.3, 0.3, 0.2])
PLAY = PlayOperator(0.8)
RELAYS = PreisachModel.from_relays([0.35, 0.1, -0.05], [-0.25, -0.5, -0.15], [0.3, 0.3, 0.4])
U = np.concatenate(
    [np.linspace(-3, 2, 60), np.linspace(2, -1.2, 50), np.linspace(-1.2, 1.1, 40), [0.7, 0.9]]
)


def hand_plays(x, half_widths, weights, positions):
    """Prandtl–Ishlinskii written out: every wagon follows ``w = max(x−r, min(x+r, w))``."""
    w = np.array(positions, dtype=float)
    out = []
    for xk in x:
        w = np.maximum(xk - half_widths, np.minimum(xk + half_widths, w))
        out.append(float(np.dot(weights, w)))
    return np.array(out)


# ------------------------------------------------------------------------------------------
# apply
# ------------------------------------------------------------------------------------------
def test_static_map_then_play_is_the_play_of_the_mapped_input():
    y, _ = Cascade(F, PLAY).apply(U)
    x = f_in(U)
    ref = hand_plays(x, np.array([0.4]), np.array([1.0]), [x[0] - 0.4])
    np.testing.assert_array_equal(y, ref)


def test_play_then_static_map_is_the_generalized_play():
    y, state = Cascade(PLAY, G).apply(U)
    ref, ref_state = GeneralizedPlay(0.8, g_out, g_out_derivative).apply(U)
    np.testing.assert_array_equal(y, ref)
    assert state.inner.position == ref_state.position


def test_pi_then_static_map_is_the_generalized_prandtl_ishlinskii_model():
    y, _ = Cascade(PI, G).apply(U)
    r = 0.5 * PI.widths
    x = hand_plays(U, r, PI.weights, U[0] - r)
    np.testing.assert_allclose(y, g_out(x), rtol=4 * EPS, atol=4 * EPS)


@pytest.mark.parametrize(
    "op",
    [
        Cascade(F, PLAY),
        Cascade(PI, PLAY),
        Cascade(PI, RELAYS),
        Cascade(Relay(0.3, -0.2), G),
        Cascade(RELAYS, Relay(0.5, -0.5)),
        Cascade(Cascade(F, PI), PLAY),
        Cascade(PI, gauss_everett_model()),
    ],
)
def test_continuing_from_a_returned_state_equals_one_long_call(op):
    y, final = op.apply(U)
    y1, s1 = op.apply(U[:37])
    y2, s2 = op.apply(U[37:101], s1)
    y3, s3 = op.apply(U[101:], s2)
    np.testing.assert_array_equal(np.concatenate([y1, y2, y3]), y)
    assert op.output(s3) == op.output(final) == y[-1]
    assert s3.input == U[-1]


def test_initial_state_rises_part_by_part():
    state = Cascade(F, PLAY).initial_state(0.5)
    assert state.inner.input == 0.5
    x0 = float(f_in(0.5))
    assert state.outer.input == x0 and state.outer.position == x0 - 0.4
    # a decreasing inner: the outer's own rising state at the inner output (module docstring)
    state = Cascade(StaticMap(np.negative), PLAY).initial_state(0.5)
    assert state.outer.input == -0.5 and state.outer.position == -0.9


# ------------------------------------------------------------------------------------------
# branch flow against differences of apply
# ------------------------------------------------------------------------------------------
def perturb_pi_play(op, state, label, h):
    """Cascade(PI, play): move wagon ``label`` by ``h`` (the outer's input follows x)."""
    pos = np.array(state.inner.positions, dtype=float)
    w_out = state.outer.position
    if label.startswith("in:"):
        pos[int(label[4:])] += h
    else:
        w_out += h
    inner = PI.state(pos, state.inner.input)
    x = float(PI.apply([inner.input], inner)[0][0])
    return CascadeState(inner, PLAY.state(w_out, x))


def perturb_f_pi(op, state, label, h):
    """Cascade(F, PI): move outer wagon ``label`` by ``h``."""
    pos = np.array(state.outer.positions, dtype=float)
    pos[int(label[5:])] += h
    return CascadeState(state.inner, PI.state(pos, state.outer.input))


def perturb_nested(op, state, label, h):
    """Cascade(Cascade(F, PI), play): labels ``in:out:w{i}`` and ``out:w``."""
    inner = state.inner
    pos = np.array(inner.outer.positions, dtype=float)
    w_out = state.outer.position
    if label.startswith("in:out:w"):
        pos[int(label[8:])] += h
    else:
        w_out += h
    inner = CascadeState(inner.inner, PI.state(pos, inner.outer.input))
    return CascadeState(inner, PLAY.state(w_out, float(np.dot(PI.weights, pos))))


def driven_value(state, label):
    """The memory variable ``label`` read from a cascade state (any of the three above)."""
    parts = label.split(":")
    for part in parts[:-1]:
        state = state.inner if part == "in" else state.outer
    if hasattr(state, "positions"):
        return float(state.positions[int(parts[-1][1:])])
    return float(state.position)


def memory_difference(reading, perturbed):
    """d(reading)/dm by central differences, or the second-order one-sided difference
    ``(−3r(0) + 4r(h) − r(2h))/2h`` towards the admissible side when the variable sits on a
    wall (a perturbation past it is no state: ``ValueError``); error O(h²) either way. None
    in a corner of the state space (inner and outer wagons both on their walls, where the
    variable cannot move alone)."""
    try:
        return (reading(perturbed(H)) - reading(perturbed(-H))) / (2 * H)
    except ValueError:
        pass
    for h in (H, -H):
        try:
            r1, r2 = reading(perturbed(h)), reading(perturbed(2 * h))
        except ValueError:
            continue
        return (-3 * reading(perturbed(0.0)) + 4 * r1 - r2) / (2 * h)
    return None


CASES = [
    (Cascade(PI, PLAY), perturb_pi_play),
    (Cascade(F, PI), perturb_f_pi),
    (Cascade(Cascade(F, PI), PLAY), perturb_nested),
]


@pytest.mark.parametrize(("op", "perturb"), CASES)
@pytest.mark.parametrize("cut", [100, 110, 135, U.size])
@pytest.mark.parametrize("d", [1, -1])
def test_branch_flow_against_differences_of_apply(op, perturb, cut, d):
    _, state = op.apply(U[:cut])
    flow = op.branch_flow(state, d)
    u0, bp = flow.input, flow.breakpoint
    span = min(0.5, 0.5 * abs(bp - u0)) if math.isfinite(bp) else 0.5
    checked = 0
    for u in (u0 + 0.3 * d * span, u0 + d * span):

        def along(uu, st=state):
            return op.apply([uu], st)

        y, moved = along(u)
        # output on the branch: apply moving monotonically to u (rounding only)
        assert abs(float(flow.output(u)) - y[0]) <= 1e-13 * max(1.0, abs(y[0]))
        # slope: central difference along the branch (error h²·|y'''| + ε/h)
        fd = (along(u + H)[0][0] - along(u - H)[0][0]) / (2 * H)
        assert abs(float(flow.slope(u)) - fd) <= 1e-8
        _, d_m = flow.partials(u)
        if flow.driven_labels:
            values, d_du, d_dm = flow.driven(u)
            for k, lab in enumerate(flow.driven_labels):
                assert abs(values[k] - driven_value(moved, lab)) <= 1e-13
                total = d_du[k] + np.sum(d_dm[k][flow.slaved])
                fd_total = (
                    driven_value(along(u + H)[1], lab) - driven_value(along(u - H)[1], lab)
                ) / (2 * H)
                assert abs(total - fd_total) <= 1e-8
        for i, lab in enumerate(flow.labels):
            if flow.slaved[i]:
                continue

            def reading(st, u=u):
                y, moved = op.apply([u], st)
                return np.array([y[0], *(driven_value(moved, dl) for dl in flow.driven_labels)])

            fd = memory_difference(reading, lambda h, lab=lab: perturb(op, state, lab, h))
            if fd is None:
                continue
            checked += 1
            assert abs(d_m[i] - fd[0]) <= 1e-8, (lab, d_m[i], fd[0])
            if flow.driven_labels:
                np.testing.assert_allclose(flow.driven(u)[2][:, i], fd[1:], rtol=0, atol=1e-8)
    # continuing the last motion, every frozen variable is strictly inside and checked
    if d * (U[cut - 1] - U[cut - 2]) > 0:
        assert checked == 2 * int(np.sum(~flow.slaved))


@pytest.mark.parametrize(("op", "perturb"), CASES)
@pytest.mark.parametrize("cut", [60, 110, 135])
@pytest.mark.parametrize("d", [1, -1])
def test_breakpoint_is_the_first_input_where_the_memory_structure_changes(op, perturb, cut, d):
    _, state = op.apply(U[:cut])
    flow = op.branch_flow(state, d)
    bp = flow.breakpoint
    if not math.isfinite(bp):
        return

    def structure(u):
        f = op.branch_flow(op.apply([u], state)[1], d)
        return f.labels, tuple(f.slaved), f.driven_labels

    # a wall within 8 ulps counts as touched (hysteresis.play), so "before" is 1e-12 earlier
    before = bp - d * 1e-12 * max(1.0, abs(bp))
    assert (flow.input - before) * d < 0
    assert structure(before) == (flow.labels, tuple(flow.slaved), flow.driven_labels)
    assert structure(bp) != structure(before)
    # the labels that leave (driven from now on) or are reset are the ones announced
    after = op.branch_flow(op.apply([bp], state)[1], d)
    gone = set(flow.labels) - set(after.labels)
    assert gone == set(flow.breakpoint_removes)
    for lab in flow.breakpoint_resets:
        assert after.slaved[after.labels.index(lab)]


def test_relays_after_pi_jump_where_apply_switches_and_the_jump_moves_with_the_memory():
    pi = PrandtlIshlinskii([0.0, 1.5, 5.0], [0.5, 0.3, 0.2])  # wide wagons: frozen at switches
    op = Cascade(pi, RELAYS)
    checked = moving = 0
    for cut in range(10, U.size, 9):
        _, state = op.apply(U[:cut])
        for d in (1, -1):
            flow = op.branch_flow(state, d)
            if flow.breakpoint_jump == 0.0:
                continue
            checked += 1
            bp = flow.breakpoint
            before = math.nextafter(bp, flow.input)
            y_bp = op.apply([bp], state)[0][0]
            y_before = op.apply([before], state)[0][0]
            assert y_before == float(flow.output(before))  # not switched yet
            assert y_bp - float(flow.output(bp)) == pytest.approx(flow.breakpoint_jump, abs=1e-15)
            # ∂u*/∂w_i: the breakpoint of the perturbed state (u* is affine in w on a PI
            # branch: the difference is exact up to the rounding of u*, ε/h relative)
            for i, lab in enumerate(flow.labels):
                if flow.slaved[i]:
                    continue

                def perturbed(h, lab=lab, state=state):
                    pos = np.array(state.inner.positions)
                    pos[int(lab[4:])] += h
                    inner = pi.state(pos, state.inner.input)
                    x = float(pi.apply([inner.input], inner)[0][0])
                    outputs = RELAYS.relay_outputs(state.outer)
                    return CascadeState(inner, RELAYS.state_from_relay_outputs(outputs, x))

                fd = memory_difference(
                    lambda st, d=d: np.array([op.branch_flow(st, d).breakpoint]), perturbed
                )
                assert flow.breakpoint_gradient[i] == pytest.approx(fd[0], rel=1e-7, abs=1e-8)
                moving += flow.breakpoint_gradient[i] != 0.0
    assert checked >= 6 and moving >= 6


def test_relay_then_static_map_jumps_at_the_thresholds():
    op = Cascade(Relay(0.3, -0.2), G)
    state = op.initial_state(0.0)  # relay down
    up = op.branch_flow(state, 1)
    assert up.breakpoint == 0.3 and up.labels == ()
    assert up.breakpoint_jump == float(g_out(1.0) - g_out(-1.0))
    assert float(up.output(0.1)) == float(g_out(-1.0))
    state = op.apply([0.5, 0.0], state)[1]  # relay up
    down = op.branch_flow(state, -1)
    assert down.breakpoint == math.nextafter(-0.2, -math.inf)
    assert down.breakpoint_jump == float(g_out(-1.0) - g_out(1.0))
    assert op.apply([down.breakpoint], state)[0][0] == float(g_out(-1.0))
    assert op.apply([-0.2], state)[0][0] == float(g_out(1.0))


def test_an_outer_preisach_model_pushes_the_inner_output_with_its_gradient():
    preisach = gauss_everett_model()
    op = Cascade(PI, preisach)
    _, state = op.apply(U[:60])  # the input last rose
    flow = op.branch_flow(state, -1)  # reversing: the outer pushes x(u0)
    pushed = np.flatnonzero(flow.pushed)
    assert [flow.labels[i] for i in pushed] == ["out:M1"]
    d_du, d_dm = flow.pushed_gradient(flow.input)
    # the pushed value is x = Σ a_i w_i: ∂x/∂u = 0, ∂x/∂w_i = a_i (w0 slaved: counts as δu)
    assert d_du[0] == 0.0
    np.testing.assert_array_equal(d_dm[0, :4], PI.weights)
    assert np.all(d_dm[0, 4:] == 0.0)


# ------------------------------------------------------------------------------------------
# refusals and bookkeeping
# ------------------------------------------------------------------------------------------
class Opaque(ContinuousHysteron):
    """A continuous operator the cascade knows nothing about (not a Cascade, no declared
    monotonicity), wrapping another one."""

    def __init__(self, op):
        self.op = op

    def initial_state(self, u0):
        return self.op.initial_state(u0)

    def apply(self, inputs, state=None):
        return self.op.apply(inputs, state)

    def branch_flow(self, state, direction):
        return self.op.branch_flow(state, direction)


def test_refused_cascades_say_why_in_one_sentence():
    for inner in (Relay(0.3, -0.2), RELAYS, Cascade(Relay(0.3, -0.2), G)):
        for outer in (PLAY, PI, gauss_everett_model()):
            with pytest.raises(ValueError, match="has an output that jumps, and outer") as err:
                Cascade(inner, outer)
            assert "\n" not in str(err.value)
    for outer in (PLAY, RELAYS):
        with pytest.raises(ValueError, match="is not monotone, and outer"):
            Cascade(StaticMap(np.square), outer)
    Cascade(StaticMap(np.square), G)  # no memory behind it: fine
    with pytest.raises(TypeError, match="^outer must be a hysteresis operator"):
        Cascade(PLAY, np.tanh)
    # an inner that jumps without saying so: refused when the jump is reached
    op = Cascade(Opaque(Cascade(Relay(0.3, -0.2), StaticMap(np.positive))), PLAY)
    state = op.initial_state(0.0)
    with pytest.raises(ValueError, match="jumps at input 0.3, and outer"):
        op.branch_flow(state, 1)


def test_a_state_of_another_cascade_is_refused():
    op = Cascade(PI, PLAY)
    other = Cascade(PI, PlayOperator(3.0)).apply(U)[1]
    bad = CascadeState(op.initial_state(0.0).inner, PLAY.state(5.0, 5.0))
    with pytest.raises(ValueError, match="^state: the outer's input 5.0 is not the inner's"):
        op.apply([0.0], bad)
    with pytest.raises(ValueError):
        op.apply([0.0], other)
    with pytest.raises(TypeError, match="^state must be a CascadeState"):
        op.apply([0.0], PI.initial_state(0.0))


def test_output_range_and_max_slope_follow_from_the_parts():
    erf_play = GeneralizedPlay.erf(1.0, 0.5)
    assert Cascade(erf_play, G).output_range == (float(g_out(-1.0)), float(g_out(1.0)))
    assert Cascade(PI, G).output_range == (-math.inf, math.inf)
    assert Cascade(F, erf_play).output_range == (-1.0, 1.0)
    slope_f = StaticMap(f_in, f_in_derivative, max_slope=1.5)
    assert Cascade(slope_f, PI).max_slope == 1.5 * 1.0
    assert Cascade(F, PI).max_slope is None
    assert Cascade(StaticMap(np.negative, max_slope=0.0), PI).max_slope == 0.0
    assert Cascade(PI, RELAYS).max_slope == 0.0
    assert Cascade(PI, PLAY).max_slope == 1.0


def test_pickles_and_keeps_accepting_its_states():
    op = Cascade(StaticMap(np.tanh), PI)
    y, state = op.apply(U[:80])
    copy = pickle.loads(pickle.dumps(op))
    np.testing.assert_array_equal(copy.apply(U[80:], state)[0], op.apply(U[80:], state)[0])
    state_copy = pickle.loads(pickle.dumps(state))
    np.testing.assert_array_equal(op.apply(U[80:], state_copy)[0], op.apply(U[80:], state)[0])
    assert repr(copy) == f"Cascade(StaticMap({np.tanh!r}), {PI!r})"
