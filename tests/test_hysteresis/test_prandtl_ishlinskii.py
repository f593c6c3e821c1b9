"""Prandtl–Ishlinskii: superposition of plays, exact inverse, branches and linearization."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hysteresis import PlayOperator, PrandtlIshlinskii

finite = st.floats(min_value=-20, max_value=20, allow_nan=False, allow_infinity=False)
sequences = st.lists(finite, min_size=1, max_size=80)


@st.composite
def invertible_operators(draw):
    """Width 0 with a positive weight, distinct widths, every partial weight sum > 0."""
    n = draw(st.integers(min_value=0, max_value=5))
    steps = draw(st.lists(st.floats(0.05, 3.0), min_size=n, max_size=n))
    widths = np.concatenate([[0.0], np.cumsum(steps)])
    partial = draw(st.lists(st.floats(0.1, 5.0), min_size=n + 1, max_size=n + 1))
    weights = np.diff(np.concatenate([[0.0], partial]))  # any signs, positive partial sums
    return PrandtlIshlinskii(widths, weights)


def test_output_is_weighted_sum_of_independent_plays():
    widths, weights = [3.0, 0.0, 1.0], [0.25, 1.0, -0.5]
    pi = PrandtlIshlinskii(widths, weights)
    u = np.cumsum(np.random.default_rng(0).normal(size=500))
    expected = sum(a * PlayOperator(p).apply(u)[0] for p, a in zip(widths, weights, strict=True))
    out, state = pi.apply(u)
    np.testing.assert_allclose(out, expected, rtol=1e-13, atol=1e-12)
    assert pi.output(state) == pytest.approx(out[-1])
    np.testing.assert_array_equal(pi.widths, [0.0, 1.0, 3.0])  # sorted, weights follow
    np.testing.assert_array_equal(pi.weights, [1.0, -0.5, 0.25])


def test_inverse_closed_form_two_plays():
    # y = u + play_2(u): slope 1 then 2 beyond r = 1 -> inverse slope 1 then 1/2, threshold
    # r' = phi(1) = 1: widths (0, 2), weights (1, -1/2)
    inv = PrandtlIshlinskii([0.0, 2.0], [1.0, 1.0]).inverse()
    np.testing.assert_allclose(inv.widths, [0.0, 2.0])
    np.testing.assert_allclose(inv.weights, [1.0, -0.5])
    np.testing.assert_allclose(inv.loading_curve([0.5, 1.0, 3.0]), [0.5, 1.0, 2.0])


@settings(max_examples=150, deadline=None)
@given(invertible_operators(), sequences)
def test_inverse_after_forward_is_identity(pi, inputs):
    y, _ = pi.apply(inputs)
    u, _ = pi.inverse().apply(y)
    np.testing.assert_allclose(u, inputs, atol=1e-9 * (1 + np.max(np.abs(inputs))))


@settings(max_examples=150, deadline=None)
@given(invertible_operators(), sequences)
def test_forward_after_inverse_is_identity(pi, targets):
    u, _ = pi.inverse().apply(targets)
    y, _ = pi.apply(u)
    np.testing.assert_allclose(y, targets, atol=1e-9 * (1 + np.max(np.abs(targets))))


@settings(max_examples=100, deadline=None)
@given(invertible_operators(), sequences, sequences)
def test_inverse_from_a_mid_history_state(pi, history, inputs):
    """Start both operators from a non-trivial memory: the inverse's state is built by
    ``inverse_state`` from the forward state."""
    _, state = pi.apply(history)
    inv_state = pi.inverse_state(state)
    assert inv_state.input == pytest.approx(pi.output(state))
    y, _ = pi.apply(inputs, state)
    u, _ = pi.inverse().apply(y, inv_state)
    np.testing.assert_allclose(u, inputs, atol=1e-9 * (1 + np.max(np.abs(history + inputs))))


@settings(max_examples=50, deadline=None)
@given(invertible_operators())
def test_inverse_of_inverse_and_initial_states(pi):
    back = pi.inverse().inverse()
    np.testing.assert_allclose(back.widths, pi.widths, atol=1e-9)
    np.testing.assert_allclose(back.weights, pi.weights, rtol=1e-9, atol=1e-12)
    s = pi.initial_state(0.7)
    np.testing.assert_allclose(
        pi.inverse_state(s).positions,
        pi.inverse().initial_state(pi.output(s)).positions,
        atol=1e-12,
    )


def _fd_check(pi, state, direction, h=1e-7):
    lin = pi.linearize(state, direction)
    br = pi.branch(state, direction)
    out, _ = pi.apply([state.input + direction * h], state)
    fd = (out[0] - pi.output(state)) / (direction * h)
    total = lin.d_output_d_input + float(lin.d_output_d_memory @ lin.slaved)
    assert fd == pytest.approx(total, rel=1e-5, abs=1e-6)
    assert br.slope == pytest.approx(total)
    for i in range(pi.widths.size):
        if pi.widths[i] == 0.0:
            continue  # the width-0 play has no freedom at a fixed input
        pos = np.array(state.positions)
        pos[i] += h if state.input >= pos[i] else -h
        dy = pi.output(pi.state(pos, state.input)) - pi.output(state)
        assert dy / (pos[i] - state.positions[i]) == pytest.approx(lin.d_output_d_memory[i])
    return lin, br


def test_branches_and_linearization():
    pi = PrandtlIshlinskii([0.0, 1.0, 3.0], [1.0, 0.5, 0.25])
    _, state = pi.apply([0.0, 4.0, 3.0])  # rose to 4, fell back by 1: width-1 play on left wall
    np.testing.assert_allclose(state.positions, [3.0, 3.5, 2.5])
    lin, br = _fd_check(pi, state, -1)
    assert lin.slaved.tolist() == [True, True, False] and br.slope == 1.5
    assert br.breakpoint == pytest.approx(1.0)  # width-3 play's left wall: 2.5 - 1.5
    assert lin.reset_on_leave.tolist() == [2]
    lin, br = _fd_check(pi, state, +1)
    assert lin.slaved.tolist() == [True, False, False] and br.slope == 1.0
    assert br.breakpoint == pytest.approx(4.0) and lin.reset_on_leave.tolist() == [1, 2]
    # initial state rising: everything dragged, no breakpoint
    lin, br = _fd_check(pi, pi.initial_state(0.0), +1)
    assert br.breakpoint == np.inf and lin.reset_on_leave.size == 0 and br.slope == 1.75
    # the breakpoint is where the slope changes
    y0, _ = pi.apply([1.0 + 1e-9], state)
    y1, _ = pi.apply([1.0 - 1e-3], state)
    assert (pi.output(state) - y0[0]) / (3.0 - 1.0 - 1e-9) == pytest.approx(1.5)
    assert (pi.output(state) - y1[0]) / (2.0 + 1e-3) > 1.5


@pytest.mark.parametrize(
    "widths,weights,name",
    [
        ([0.0, 1.0], [1.0], "weights"),
        ([0.0, -1.0], [1.0, 1.0], "widths"),
        ([0.0, 1.0, 1.0], [1.0, 1.0, 1.0], "widths must be distinct"),
        ([0.0, np.nan], [1.0, 1.0], "widths"),
        ([0.0, 1.0], [1.0, np.inf], "weights"),
        ([], [], "widths"),
    ],
)
def test_bad_parameters(widths, weights, name):
    with pytest.raises(ValueError, match=name):
        PrandtlIshlinskii(widths, weights)


def test_non_invertible_and_bad_states():
    with pytest.raises(ValueError, match="weights"):
        PrandtlIshlinskii([1.0, 2.0], [1.0, 1.0]).inverse()  # no linear term
    with pytest.raises(ValueError, match="weights"):
        PrandtlIshlinskii([0.0, 1.0], [1.0, -1.0]).inverse()  # partial sum 0
    with pytest.raises(ValueError, match="weights"):
        PrandtlIshlinskii([0.0, 1.0], [-1.0, 3.0]).inverse()
    pi = PrandtlIshlinskii([0.0, 2.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="positions"):
        pi.state([0.0, 1.5], 0.0)
    with pytest.raises(ValueError, match="inputs"):
        pi.apply([np.nan])
