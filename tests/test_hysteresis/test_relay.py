"""Relay (Preisach unit): the definition of paper eq. (preisachunit), boundaries, switching."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hysteresis import Relay, RelayState

finite = st.floats(min_value=-10, max_value=10, allow_nan=False, allow_infinity=False)
sequences = st.lists(finite, min_size=1, max_size=60)


def reference_relay(alpha, beta, inputs, y0):
    """Literal reading of the definition, one input at a time."""
    y, out = y0, []
    for u in inputs:
        if u >= alpha:
            y = 1.0
        elif u < beta:
            y = -1.0
        out.append(y)
    return np.array(out)


def test_parameters_and_rotated_coordinates():
    r = Relay(alpha=1.0, beta=-3.0)
    assert (r.alpha, r.beta) == (1.0, -3.0)
    assert r.centre == -1.0 and r.half_width == 2.0 and r.width == 4.0


def test_boundaries_of_the_definition():
    r = Relay(1.0, -1.0)
    # rising: exactly alpha switches up; falling: exactly beta keeps +1, just below switches
    out, state = r.apply([-2.0, 0.999, 1.0, 0.0, -1.0, np.nextafter(-1.0, -2.0), 0.5])
    np.testing.assert_array_equal(out, [-1, -1, 1, 1, 1, -1, -1])
    assert state == RelayState(-1.0, 0.5)


def test_zero_width_relay_is_a_reversible_switch():
    r = Relay(0.5, 0.5)
    u = np.array([-1.0, 0.5, 0.49, 0.5, 2.0, np.nextafter(0.5, 0.0)])
    out, _ = r.apply(u)
    np.testing.assert_array_equal(out, np.where(u >= 0.5, 1.0, -1.0))


def test_initial_state_is_rising_from_minus_infinity():
    r = Relay(1.0, -1.0)
    assert r.initial_state(0.0).output == -1.0  # inside the loop, reached from below
    assert r.initial_state(1.0).output == 1.0
    assert r.initial_state(-5.0).output == -1.0


@settings(max_examples=200, deadline=None)
@given(
    sequences,
    st.tuples(finite, finite).map(sorted),
    st.sampled_from([-1.0, 1.0]),
)
def test_matches_reference_from_any_valid_state(inputs, thresholds, y0):
    beta, alpha = thresholds
    r = Relay(alpha, beta)
    # a reachable state: +1 needs input >= beta, -1 needs input < alpha (apply checks it)
    state = RelayState(y0, alpha if y0 > 0 else float(np.nextafter(beta, -np.inf)))
    out, final = r.apply(inputs, state)
    expected = reference_relay(alpha, beta, inputs, y0)
    np.testing.assert_array_equal(out, expected)
    assert final.output == expected[-1] and final.input == inputs[-1]


@settings(max_examples=100, deadline=None)
@given(sequences, sequences)
def test_apply_composes(first, second):
    r = Relay(1.0, -2.0)
    out_all, s_all = r.apply(first + second)
    out1, s1 = r.apply(first)
    out2, s2 = r.apply(second, s1)
    np.testing.assert_array_equal(out_all, np.concatenate([out1, out2]))
    assert s_all == s2


def test_switching_reports_next_threshold_and_jump():
    r = Relay(2.0, -1.0)
    down = r.initial_state(0.0)
    sw = r.switching(down)
    assert (sw.lower, sw.upper, sw.jump_up, sw.jump_down) == (-np.inf, 2.0, 2.0, 0.0)
    up = r.initial_state(3.0)
    sw = r.switching(up)
    assert (sw.lower, sw.upper, sw.jump_up, sw.jump_down) == (-1.0, np.inf, 0.0, -2.0)


def test_explicit_state_must_be_reachable():
    r = Relay(1.0, -1.0)
    assert r.state(1.0, 0.0) == RelayState(1.0, 0.0)
    with pytest.raises(ValueError, match="input"):
        r.state(1.0, -1.5)
    with pytest.raises(ValueError, match="input"):
        r.state(-1.0, 1.0)
    with pytest.raises(ValueError, match="output"):
        r.state(0.0, 0.0)


def test_large_input_is_fast_and_correct():
    u = np.sin(np.linspace(0, 200 * np.pi, 1_000_000)) * 2.0
    out, _ = Relay(1.0, -1.0).apply(u)
    # after the first crossing of alpha the output follows the sign of the last excursion
    assert out[0] == -1.0 and out.max() == 1.0 and out.min() == -1.0
    assert np.all(out[u >= 1.0] == 1.0) and np.all(out[u < -1.0] == -1.0)
    # 100 periods: every maximum (2 > alpha) switches up, every minimum (-2 < beta) down
    assert np.count_nonzero(np.diff(out) == 2.0) == 100
    assert np.count_nonzero(np.diff(out) == -2.0) == 100


@pytest.mark.parametrize(
    "alpha,beta,name",
    [(0.0, 1.0, "alpha must be >= beta"), (np.nan, 0.0, "alpha"), (1.0, np.inf, "beta")],
)
def test_bad_parameters(alpha, beta, name):
    with pytest.raises(ValueError, match=name):
        Relay(alpha, beta)


@pytest.mark.parametrize("bad", [[], [0.0, np.nan], [np.inf]])
def test_bad_inputs(bad):
    with pytest.raises(ValueError, match="inputs"):
        Relay(1.0, 0.0).apply(bad)
