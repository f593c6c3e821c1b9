"""Play and generalized play: closed forms, rate independence, return-point memory, bounds,
envelopes, branches and linearization against finite differences."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import erf

from hysteresis import GeneralizedPlay, PlayOperator, PlayState

finite = st.floats(min_value=-10, max_value=10, allow_nan=False, allow_infinity=False)
sequences = st.lists(finite, min_size=1, max_size=60)
widths = st.floats(min_value=0.0, max_value=8.0, allow_nan=False)


def reference_play(width, inputs, w0):
    w, out = w0, []
    for u in inputs:
        w = max(u - width / 2, min(u + width / 2, w))
        out.append(w)
    return np.array(out)


def test_closed_form_rise_reversal_fall():
    play = PlayOperator(2.0)
    up = np.linspace(-3.0, 1.0, 9)
    down = np.linspace(1.0, -3.0, 9)
    out, state = play.apply(np.concatenate([up, down]))
    np.testing.assert_allclose(out[:9], up - 1.0)  # dragged by the right wall
    # after the reversal at u = 1 the wagon rests at w = 0 until u = w - p/2 = -1
    expected_down = np.where(down >= -1.0, 0.0, down + 1.0)
    np.testing.assert_allclose(out[9:], expected_down)
    assert state == PlayState(-2.0, -3.0)


def test_initial_state_and_zero_width_identity():
    assert PlayOperator(3.0).initial_state(1.0) == PlayState(-0.5, 1.0)
    u = np.array([0.3, -2.0, 5.0, 5.0, 1e-9])
    out, _ = PlayOperator(0.0).apply(u)
    np.testing.assert_array_equal(out, u)


@settings(max_examples=200, deadline=None)
@given(sequences, widths, st.floats(min_value=-0.5, max_value=0.5))
def test_matches_reference_and_bounds(inputs, width, offset):
    play = PlayOperator(width)
    state = play.state(inputs[0] + offset * width, inputs[0])
    out, final = play.apply(inputs, state)
    np.testing.assert_array_equal(out, reference_play(width, inputs, state.position))
    # the finger never leaves the wagon
    assert np.all(np.abs(np.asarray(inputs) - out) <= width / 2 + 1e-12)
    assert final == PlayState(out[-1], inputs[-1])


@settings(max_examples=150, deadline=None)
@given(sequences, widths, st.integers(min_value=1, max_value=7))
def test_rate_independence(inputs, width, n_between):
    """Inserting samples on the straight segments between inputs changes nothing at the
    original inputs (the play only sees the visited values, not their timing)."""
    u = np.asarray(inputs)
    play = PlayOperator(width)
    out, final = play.apply(u)
    t = np.linspace(0.0, 1.0, n_between + 2)[1:-1]
    dense = [u[0]]
    for a, b in zip(u[:-1], u[1:], strict=True):
        dense.extend(a + (b - a) * t)
        dense.append(b)
    out_dense, final_dense = play.apply(dense)
    np.testing.assert_allclose(out_dense[:: n_between + 1], out, atol=1e-12)
    assert final_dense.position == pytest.approx(final.position, abs=1e-12)


@settings(max_examples=150, deadline=None)
@given(
    sequences,
    widths,
    st.floats(min_value=-10, max_value=0),
    st.floats(min_value=0.01, max_value=10),
    st.lists(st.floats(min_value=0, max_value=1), min_size=1, max_size=20),
)
def test_return_point_memory(history, width, low, span, fractions):
    """After a monotone rise from ``low`` to ``high``, any excursion inside [low, high] that comes
    back to ``high`` restores the state reached at ``high`` the first time (wiping out)."""
    high = low + span
    play = PlayOperator(width)
    _, s_hist = play.apply(history)
    _, s_low = play.apply([low], s_hist)
    _, s_high = play.apply([high], s_low)
    excursion = [low + f * span for f in fractions] + [high]
    _, s_back = play.apply(excursion, s_high)
    assert s_back.position == pytest.approx(s_high.position, abs=1e-12)


def test_explicit_state_validation():
    play = PlayOperator(2.0)
    assert play.state(0.0, 1.0) == PlayState(0.0, 1.0)
    with pytest.raises(ValueError, match="position"):
        play.state(0.0, 1.5)
    with pytest.raises(ValueError, match="input"):
        play.state(0.0, np.nan)


def test_branch_inside_and_on_the_wall():
    play = PlayOperator(2.0)
    wall = play.initial_state(0.5)  # w = -0.5, finger on the right wall
    b = play.branch(wall, +1)
    assert (b.value, b.slope, b.breakpoint) == (-0.5, 1.0, np.inf)
    b = play.branch(wall, -1)  # moving back: inside, next wall is the left one
    assert (b.value, b.slope, b.breakpoint) == (-0.5, 0.0, -1.5)
    inside = play.state(0.0, 0.2)
    assert play.branch(inside, +1).breakpoint == 1.0
    assert play.branch(inside, -1).breakpoint == -1.0
    # zero width: always dragged
    z = PlayOperator(0.0).initial_state(0.3)
    assert PlayOperator(0.0).branch(z, -1).slope == 1.0


def _finite_difference_check(op, state, direction, h=1e-6):
    """Compare the linearization with finite differences of ``apply``/``output``."""
    lin = op.linearize(state, direction)
    br = op.branch(state, direction)
    y0 = op.output(state)
    out, _ = op.apply([state.input + direction * h], state)
    total = lin.d_output_d_input + float(lin.d_output_d_memory @ lin.slaved)
    assert (out[0] - y0) / (direction * h) == pytest.approx(total, rel=1e-4, abs=1e-9)
    assert br.slope == pytest.approx(total, rel=1e-12, abs=1e-15)
    # memory: move the wagon by a small amount towards the finger (stays admissible)
    dw = h if state.input >= state.position else -h
    moved = op.state(state.position + dw, state.input)
    dy = op.output(moved) - y0
    assert dy / dw == pytest.approx(lin.d_output_d_memory[0], rel=1e-4)
    return lin


@pytest.mark.parametrize("make", [lambda: PlayOperator(2.0), lambda: GeneralizedPlay.erf(2.0, 0.7)])
def test_linearization_matches_finite_differences(make):
    op = make()
    wall = op.initial_state(0.4)
    lin = _finite_difference_check(op, wall, +1)
    assert lin.slaved.tolist() == [True] and lin.reset_on_leave.size == 0
    lin = _finite_difference_check(op, wall, -1)
    assert lin.slaved.tolist() == [False] and lin.reset_on_leave.tolist() == [0]
    inside = op.state(0.1, 0.3)
    for d in (+1, -1):
        lin = _finite_difference_check(op, inside, d)
        assert lin.slaved.tolist() == [False] and lin.d_output_d_input == 0.0
    # the breakpoint really is where the branch ends
    bp = op.branch(inside, +1).breakpoint
    y_before, _ = op.apply([bp - 1e-9], inside)
    y_after, _ = op.apply([bp + 1e-3], inside)
    assert y_before[0] == op.output(inside) and y_after[0] > op.output(inside)
    # on the left wall moving down: slaved
    left = op.state(1.0, 0.0)
    assert op.linearize(left, -1).slaved.tolist() == [True]
    _finite_difference_check(op, left, -1)


@settings(max_examples=100, deadline=None)
@given(sequences, st.floats(min_value=0.0, max_value=6.0), st.floats(min_value=0.1, max_value=4))
def test_generalized_erf_play(inputs, width, spread):
    gp = GeneralizedPlay.erf(width, spread)
    w, _ = PlayOperator(width).apply(inputs)
    out, state = gp.apply(inputs)
    np.testing.assert_allclose(out, erf(w / (math.sqrt(2.0) * spread)), rtol=1e-14, atol=1e-15)
    u = np.asarray(inputs)
    # between the envelopes: rising branch f(u - p/2) below, falling branch f(u + p/2) above
    assert np.all(gp.ascending(u) <= out + 1e-15) and np.all(out <= gp.descending(u) + 1e-15)
    np.testing.assert_allclose(gp.ascending(u), erf((u - width / 2) / (math.sqrt(2) * spread)))
    assert state.position == w[-1] and np.all(np.abs(out) <= 1.0)


def test_generalized_custom_shape_and_attributes():
    gp = GeneralizedPlay(1.0, np.tanh, lambda w: 1.0 / np.cosh(w) ** 2, name="tanh")
    assert gp.shape_kind == "custom" and gp.spread is None
    u = np.array([0.0, 2.0, 1.0, -3.0])
    np.testing.assert_allclose(gp.apply(u)[0], np.tanh(PlayOperator(1.0).apply(u)[0]))
    assert gp.output_range == (-1.0, 1.0)
    e = GeneralizedPlay.erf(2.0, 1.5)
    assert e.shape_kind == "erf" and e.spread == 1.5 and e.width == 2.0
    # read-only: the play-limit integrator dispatches on shape_kind / spread
    for attr, value in (("shape_kind", "custom"), ("spread", 3.0), ("name", "x")):
        with pytest.raises(AttributeError):
            setattr(e, attr, value)
    assert e.shape_kind == "erf" and e.spread == 1.5 and gp.name == "tanh"
    # derivative of erf(w/(sqrt2 R)) at 0 is sqrt(2/pi)/R
    assert e.shape_derivative(0.0) == pytest.approx(math.sqrt(2 / math.pi) / 1.5)
    _finite_difference_check(gp, gp.initial_state(0.2), +1)


@pytest.mark.parametrize(
    "factory,name",
    [
        (lambda: PlayOperator(-1.0), "width"),
        (lambda: PlayOperator(np.nan), "width"),
        (lambda: GeneralizedPlay.erf(1.0, 0.0), "spread"),
        (lambda: GeneralizedPlay.erf(1.0, -2.0), "spread"),
        (lambda: GeneralizedPlay.erf(np.inf, 1.0), "width"),
        (lambda: GeneralizedPlay(1.0, 3.0, np.cos), "shape"),
        (lambda: PlayOperator(1.0).apply([]), "inputs"),
        (lambda: PlayOperator(1.0).apply([0.0, np.inf]), "inputs"),
        (lambda: PlayOperator(1.0).branch(PlayState(0.0, 0.0), 0), "direction"),
    ],
)
def test_bad_input(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()
