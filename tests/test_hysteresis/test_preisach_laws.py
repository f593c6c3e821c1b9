"""Preisach laws (Mayergoyz) checked with hypothesis on discrete and continuous models.

wiping-out, return-point memory, congruency of minor loops, rate independence, bounded output,
determinism. The expected values come from the laws themselves (an independent wiping-out
reduction written here), never from the implementation.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hysteresis.preisach import PreisachModel

LOWER, UPPER = -2.0, 2.0


def _everett(a, b):
    # a smooth non-uniform Everett function: density mu = c * exp(alpha + beta) on the triangle
    # E(a, b) = c * int_b^a int_beta^a e^(x+y) dx dy = c * (e^a - e^b)^2 / 2
    c = 2.0 / (np.exp(UPPER) - np.exp(LOWER)) ** 2
    return c * (np.exp(a) - np.exp(b)) ** 2 / 2


def _models():
    rng = np.random.default_rng(7)
    n = 300
    s, r = rng.normal(0, 0.8, n), rng.uniform(0, 1, n)
    a, b = s + r, s - r
    ties = rng.random(n) < 0.2  # some zero-width relays and shared thresholds
    b[ties] = a[ties]
    a[:20] = np.round(a[:20], 1)
    b[:20] = np.minimum(np.round(b[:20], 1), a[:20])
    weights = rng.uniform(0.1, 1.0, n)
    return {
        "discrete": PreisachModel.from_relays(a, b, weights / weights.sum()),
        "continuous": PreisachModel.from_everett(_everett, LOWER, UPPER),
    }


MODELS = _models()
ATOL = {"discrete": 1e-12, "continuous": 1e-12}

values = st.floats(-2.5, 2.5, allow_nan=False) | st.sampled_from([-1.0, -0.5, 0.0, 0.5, 1.0])
sequences = st.lists(values, min_size=1, max_size=30)
SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def reduce_history(inputs):
    """Independent wiping-out: the dominant alternating extrema after rising from -inf."""
    stack = []  # alternating: maxima at even positions, minima at odd positions
    for v in inputs:
        if not stack:
            stack.append(v)
            continue
        last = stack[-1]
        last_is_max = len(stack) % 2 == 1
        if v == last:
            continue
        if (v > last) == last_is_max:
            stack[-1] = v  # continue the current monotone run
        else:
            stack.append(v)
        # wipe out every older extremum of the same kind that the new value dominates
        while len(stack) >= 3:
            cur, prev = stack[-1], stack[-3]
            is_max = len(stack) % 2 == 1
            if (is_max and cur >= prev) or (not is_max and cur <= prev):
                del stack[-3:-1]
            else:
                break
    return stack


@pytest.mark.parametrize("kind", list(MODELS))
@SETTINGS
@given(sequences)
def test_wiping_out(kind, inputs):
    model = MODELS[kind]
    out, state = model.apply(inputs)
    reduced = reduce_history(inputs)
    out_r, state_r = model.apply(reduced)
    assert out_r[-1] == pytest.approx(out[-1], abs=ATOL[kind])
    if kind == "discrete":
        assert np.array_equal(model.relay_states(state), model.relay_states(state_r))
    else:
        np.testing.assert_array_equal(state.extrema, reduced)


@pytest.mark.parametrize("kind", list(MODELS))
@SETTINGS
@given(sequences, values, values, st.lists(st.floats(0, 1), min_size=1, max_size=20))
def test_return_point_memory(kind, history, x, y, fractions):
    model = MODELS[kind]
    low, high = min(x, y), max(x, y)
    if low == high:
        return
    # go to low, then to high; then wander inside [low, high] and come back to high
    _, state = model.apply(list(history) + [low, high])
    excursion = [low + f * (high - low) for f in fractions] + [high]
    out, back = model.apply(excursion, state)
    assert out[-1] == pytest.approx(state.output, abs=ATOL[kind])
    if kind == "discrete":
        assert np.array_equal(model.relay_states(back), model.relay_states(state))


@pytest.mark.parametrize("kind", list(MODELS))
@SETTINGS
@given(sequences, sequences, values, values, st.lists(st.floats(0, 1), min_size=1, max_size=20))
def test_congruency_of_minor_loops(kind, history1, history2, x, y, fractions):
    model = MODELS[kind]
    low, high = min(x, y), max(x, y)
    if low == high:
        return
    cycle = [low + f * (high - low) for f in fractions]
    loops = []
    for history, top in ((history1, 2.6), (history2, high)):
        # two different histories, both end by falling to `low` from an input >= high
        _, state = model.apply(list(history) + [top, low])
        out, _ = model.apply(cycle, state)
        loops.append(out - state.output)
    np.testing.assert_allclose(loops[0], loops[1], atol=1e-11)


@pytest.mark.parametrize("kind", list(MODELS))
@SETTINGS
@given(sequences, st.lists(st.integers(0, 4), min_size=30, max_size=30), st.randoms())
def test_rate_independence(kind, inputs, inserts, rnd):
    model = MODELS[kind]
    dense, keep = [], []
    for k, v in enumerate(inputs):
        if k:
            prev = inputs[k - 1]
            for _ in range(inserts[k]):
                dense.append(prev + rnd.random() * (v - prev))  # samples on the segment
        keep.append(len(dense))
        dense.append(v)
    out, _ = model.apply(inputs)
    out_dense, _ = model.apply(dense)
    np.testing.assert_allclose(out_dense[keep], out, atol=ATOL[kind])


@pytest.mark.parametrize("kind", list(MODELS))
@SETTINGS
@given(sequences)
def test_bounded_and_deterministic(kind, inputs):
    model = MODELS[kind]
    out1, s1 = model.apply(inputs)
    out2, s2 = model.apply(inputs)
    assert np.all(np.abs(out1) <= 1.0 + 1e-12)
    np.testing.assert_array_equal(out1, out2)
    assert s1 == s2
    # applying from an explicit state is pure: the state is not changed by being used
    snapshot = s1.extrema.copy()
    model.apply([0.3, -0.2], s1)
    np.testing.assert_array_equal(s1.extrema, snapshot)
