"""State and parameter checks refuse what is wrong and nothing that is right.

The bad-input corpus shows the refusals; here: valid states built by hand or by an equal model
are accepted and give the independent answer, valid custom shapes and Everett functions pass the
construction probes, and the probes catch what the issue reported.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erf

from hysteresis import (
    GeneralizedPlay,
    PIState,
    PlayOperator,
    PlayState,
    PrandtlIshlinskii,
    PreisachModel,
    PreisachState,
    Relay,
    RelayState,
    SpinDimerEnsemble,
)
from hysteresis._validation import ParameterTypeError


def brute_relays(alpha, beta, weights, history, inputs):
    """Independent truth: every relay updated on its own along the whole input history."""
    up = np.zeros(alpha.size, dtype=bool)  # negative saturation
    out = []
    for k, u in enumerate(np.concatenate([history, inputs])):
        up = np.where(u >= alpha, True, np.where(u < beta, False, up))
        if k >= len(history):
            out.append(float(np.sum(np.where(up, weights, -weights))))
    return np.array(out)


def test_hand_built_discrete_state_is_checked_then_accepted():
    rng = np.random.default_rng(1)
    beta = rng.normal(size=40)
    alpha = beta + rng.random(40)
    w = rng.dirichlet(np.ones(40))
    model = PreisachModel.from_relays(alpha, beta, w)
    history = np.array([2.5, -1.0, 1.2, -0.3, 0.4])
    made = model.state_from_extrema(history)
    # the same staircase without the fingerprint: full consistency check, then accepted
    bare = PreisachState(
        made.extrema, made.output, made.counts_alpha, made.counts_beta, made.prefix
    )
    inputs = np.array([0.1, 0.9, -0.8, 1.5, -2.0])
    out, _ = model.apply(inputs, bare)
    np.testing.assert_allclose(out, brute_relays(alpha, beta, w, history, inputs), atol=1e-12)
    # ... and the same staircase with a wrong output is refused
    wrong = PreisachState(
        made.extrema, made.output + 0.25, made.counts_alpha, made.counts_beta, None
    )
    with pytest.raises(ValueError, match="state.output"):
        model.apply(inputs, wrong)


def test_state_of_an_equal_model_is_accepted():
    # the fingerprint is the model's data, not its identity: a rebuilt ensemble interoperates
    a = SpinDimerEnsemble.random(40, 1.0, 1.0, 2.0, seed=5)
    b = SpinDimerEnsemble.random(40, 1.0, 1.0, 2.0, seed=5)
    _, state = a.apply([3.0, -0.5])
    out_b, _ = b.apply([0.7, -2.0], state)
    out_a, _ = a.apply([0.7, -2.0], state)
    np.testing.assert_array_equal(out_a, out_b)
    c = SpinDimerEnsemble.random(40, 1.0, 1.0, 2.0, seed=6)
    with pytest.raises(ValueError, match="state belongs to another"):
        c.apply([0.0], state)


def test_continuous_state_checks():
    everett = lambda a, b: ((a - b) / 2.0) ** 2  # noqa: E731 - uniform density on [-1, 1]
    model = PreisachModel.from_everett(everett, -1.0, 1.0)
    _, state = model.apply([0.8, -0.6, 0.3])
    bare = PreisachState(state.extrema, state.output, prefix=state.prefix)
    out, _ = model.apply([0.0], bare)
    # closed form after 0.8, -0.6, 0.3, then u = 0 (staircase M1, m1, M2, u):
    # M = -1 + 2 [E(M1, -1) - E(M1, m1) + E(M2, m1) - E(M2, u)]
    e = everett
    expected = -1 + 2 * (e(0.8, -1.0) - e(0.8, -0.6) + e(0.3, -0.6) - e(0.3, 0.0))
    assert out[0] == pytest.approx(expected, abs=1e-12)
    forged = PreisachState(state.extrema, state.output, prefix=state.prefix + 0.1)
    with pytest.raises(ValueError, match="state does not belong"):
        model.apply([0.0], forged)


@pytest.mark.parametrize(
    ("shape", "derivative"),
    [
        (np.tanh, lambda w: 1.0 / np.cosh(w) ** 2),
        (np.arctan, lambda w: 1.0 / (1.0 + w * w)),
        (lambda w: w**3 + w, lambda w: 3 * w**2 + 1),
        (
            lambda w: erf(w / 1e-2),
            lambda w: 2 / math.sqrt(math.pi) / 1e-2 * np.exp(-((w / 1e-2) ** 2)),
        ),
    ],
)
def test_valid_custom_shapes_pass_the_probe(shape, derivative):
    op = GeneralizedPlay(0.5, shape, derivative)
    u = np.array([0.0, 2.0, 1.9, -3.0])
    out, _ = op.apply(u)
    w = PlayOperator(0.5).apply(u)[0]
    np.testing.assert_allclose(out, shape(w))


def test_shape_probe_catches_the_reported_cases():
    with pytest.raises(ValueError, match="shape must be increasing"):
        GeneralizedPlay(1.0, lambda w: -w, lambda w: -np.ones_like(w))
    with pytest.raises(ValueError, match="shape must be finite"):
        GeneralizedPlay(1.0, lambda w: np.full_like(w, np.nan), np.ones_like)
    with pytest.raises(ValueError, match="one value per input"):
        GeneralizedPlay(1.0, lambda w: w[:-1], np.ones_like)
    with pytest.raises(ValueError, match="inconsistent with shape"):
        GeneralizedPlay(1.0, np.tanh, lambda w: 2.0 / np.cosh(w) ** 2)
    # a shape that is fine on the probes but not beyond: caught in apply, not returned
    op = GeneralizedPlay(
        1.0, lambda w: np.where(w > 5e3, np.nan, np.tanh(w)), lambda w: 1.0 / np.cosh(w) ** 2
    )
    with pytest.raises(ValueError, match="shape returned a non-finite value"):
        op.apply([0.0, 1e4])


def test_everett_probe_catches_negative_density_only():
    # a valid non-uniform density (mass 1 on [-1, 1]): E(a, b) = ((a-b)/2)^3 has mu = 6(a-b)/8
    PreisachModel.from_everett(lambda a, b: ((a - b) / 2.0) ** 3, -1.0, 1.0)
    with pytest.raises(ValueError, match="negative mass"):
        PreisachModel.from_everett(
            lambda a, b: ((a - b) / 2.0) ** 2 + 0.3 * np.sin(3 * (a - b)) * (a - b) * (2 - (a - b)),
            -1.0,
            1.0,
        )


def test_valid_states_of_simple_operators_are_accepted():
    relay = Relay(1.0, -1.0)
    assert relay.apply([0.0], RelayState(1.0, 0.0))[0][0] == 1.0
    assert relay.apply([0.0], RelayState(-1.0, 0.0))[0][0] == -1.0
    play = PlayOperator(2.0)
    assert play.apply([0.0], PlayState(1.0, 0.0))[0][0] == 1.0  # on the wall: allowed
    pi = PrandtlIshlinskii([0.0, 2.0], [1.0, 0.5])
    out, _ = pi.apply([0.0], PIState(np.array([0.0, -1.0]), 0.0))
    assert out[0] == -0.5


def test_type_errors_are_both_type_and_value_errors():
    with pytest.raises(TypeError, match="alpha"):
        Relay("1", "0")
    with pytest.raises(ValueError, match="alpha"):
        Relay("1", "0")
    assert issubclass(ParameterTypeError, TypeError) and issubclass(ParameterTypeError, ValueError)
    with pytest.raises(TypeError, match="state"):
        Relay(1.0, 0.0).apply([0.0], PlayState(0.0, 0.0))
