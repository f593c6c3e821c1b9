"""PreisachModel: brute-force relay cross-checks, switching, play limits, continuous model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.special import erf

from hysteresis.preisach import PreisachModel, PreisachState

# ------------------------------------------------------------------------------------------
# independent references (plain loops over all relays)
# ------------------------------------------------------------------------------------------


def brute_force(alpha, beta, weights, inputs, up=None):
    """Relay by relay: +1 once u >= alpha, -1 once u < beta; start: rise from -inf to u[0]."""
    n = len(alpha)
    if up is None:
        up = [inputs[0] >= alpha[i] for i in range(n)]
    up = list(up)
    outputs = []
    for u in inputs:
        for i in range(n):
            if u >= alpha[i]:
                up[i] = True
            elif u < beta[i]:
                up[i] = False
        outputs.append(sum(weights[i] if up[i] else -weights[i] for i in range(n)))
    return np.array(outputs), np.array(up)


def brute_switching(alpha, beta, weights, inputs):
    """Next switching inputs by trying every threshold in turn after the history ``inputs``."""
    ref, _ = brute_force(alpha, beta, weights, inputs)
    u = inputs[-1]
    upper, jump_up = math.inf, 0.0
    for c in sorted(set(a for a in alpha if a > u)):
        out, _ = brute_force(alpha, beta, weights, list(inputs) + [c])
        if abs(out[-1] - ref[-1]) > 1e-12:
            upper, jump_up = c, out[-1] - ref[-1]
            break
    lower, jump_down = -math.inf, 0.0
    for c in sorted(set(b for b in beta if b <= u), reverse=True):
        out, _ = brute_force(alpha, beta, weights, list(inputs) + [np.nextafter(c, -np.inf)])
        if abs(out[-1] - ref[-1]) > 1e-12:
            lower, jump_down = c, out[-1] - ref[-1]
            break
    return lower, upper, jump_down, jump_up


# thresholds and inputs on a coarse grid so that ties (input == threshold, equal thresholds,
# zero-width relays) are frequent
grid_value = st.integers(-8, 8).map(lambda k: k / 4)


@st.composite
def relay_systems(draw, max_relays=12):
    n = draw(st.integers(1, max_relays))
    pairs = [draw(st.tuples(grid_value, grid_value)) for _ in range(n)]
    zero_width = draw(st.lists(st.booleans(), min_size=n, max_size=n))
    alpha = np.array([max(p) for p in pairs])
    beta = np.array([a if z else min(p) for p, a, z in zip(pairs, alpha, zero_width, strict=True)])
    raw = np.array(draw(st.lists(st.integers(0, 5), min_size=n, max_size=n)), dtype=float)
    weights = raw / raw.sum() if raw.sum() > 0 else np.full(n, 1.0 / n)
    return alpha, beta, weights


input_sequences = st.lists(grid_value | st.floats(-2.5, 2.5), min_size=1, max_size=40)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(relay_systems(), input_sequences)
def test_apply_equals_brute_force(system, inputs):
    alpha, beta, weights = system
    model = PreisachModel.from_relays(alpha, beta, weights)
    ref, up = brute_force(alpha, beta, model.weights, inputs)
    out, state = model.apply(inputs)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    assert np.array_equal(model.relay_states(state), up)
    assert state.output == pytest.approx(ref[-1], abs=1e-12)
    # splitting the input sequence anywhere gives the same outputs
    k = len(inputs) // 2
    if k:
        o1, s1 = model.apply(inputs[:k])
        o2, _ = model.apply(inputs[k:], s1)
        np.testing.assert_allclose(np.concatenate([o1, o2]), ref, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000))
def test_apply_equals_brute_force_many_relays(seed):
    # more relays than the short-range scan size, so the range-extremum recursion is exercised
    rng = np.random.default_rng(seed)
    n = int(rng.integers(100, 500))  # ranges longer than the kernel's short-range scan (128)
    a = rng.integers(-40, 41, n) / 8
    b = rng.integers(-40, 41, n) / 8
    alpha, beta = np.maximum(a, b), np.minimum(a, b)
    zero_width = rng.random(n) < 0.2
    beta[zero_width] = alpha[zero_width]
    model = PreisachModel.from_relays(alpha, beta)
    walk = np.clip(np.cumsum(rng.integers(-24, 25, 150) / 8), -6, 6)
    ref, up = brute_force(alpha, beta, model.weights, walk)
    out, state = model.apply(walk)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    assert np.array_equal(model.relay_states(state), up)


def test_ties_with_staircase_extrema_in_long_ranges():
    # 200 identical relays (alpha=1, beta=0) and 200 (alpha=2, beta=0.5): index ranges longer
    # than the kernel's short-range scan (128) whose thresholds equal the last extremum exactly
    alpha = np.repeat([1.0, 2.0], 200)
    beta = np.repeat([0.0, 0.5], 200)
    model = PreisachModel.from_relays(alpha, beta)
    inputs = [-1.0, 2.0, 0.0, 1.5, 1.0, -0.5, 1.0, 0.5, 2.0, 0.5, 1.0, 0.0, 1.0, -1.0]
    ref, up = brute_force(alpha, beta, model.weights, inputs)
    out, state = model.apply(inputs)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    assert np.array_equal(model.relay_states(state), up)
    for k in range(1, len(inputs)):
        _, st_k = model.apply(inputs[: k + 1])
        lower, upper, jd, ju = brute_switching(alpha, beta, model.weights, inputs[: k + 1])
        sw = model.switching(st_k)
        assert (sw.lower, sw.upper) == (lower, upper)
        assert (sw.jump_down, sw.jump_up) == pytest.approx((jd, ju), abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_apply_equals_brute_force_coarse_ties(seed):
    # few distinct threshold values and many relays: long index ranges full of exact ties with
    # the inputs and the staircase extrema
    rng = np.random.default_rng(100 + seed)
    n = 1500
    a = rng.integers(-10, 11, n) / 2
    b = rng.integers(-10, 11, n) / 2
    alpha, beta = np.maximum(a, b), np.minimum(a, b)
    model = PreisachModel.from_relays(alpha, beta)
    walk = np.clip(np.cumsum(rng.integers(-8, 9, 120) / 2), -6, 6)
    ref, up = brute_force(alpha, beta, model.weights, walk)
    out, state = model.apply(walk)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    assert np.array_equal(model.relay_states(state), up)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(relay_systems(max_relays=8), st.lists(grid_value, min_size=1, max_size=15))
def test_switching_equals_brute_force(system, inputs):
    alpha, beta, weights = system
    model = PreisachModel.from_relays(alpha, beta, weights)
    _, state = model.apply(inputs)
    sw = model.switching(state)
    lower, upper, jump_down, jump_up = brute_switching(alpha, beta, model.weights, inputs)
    assert sw.upper == upper and sw.lower == lower
    assert sw.jump_up == pytest.approx(jump_up, abs=1e-12)
    assert sw.jump_down == pytest.approx(jump_down, abs=1e-12)
    # the state is unchanged strictly inside (lower, upper)
    for u in (sw.lower, sw.upper):
        if math.isfinite(u):
            inside = np.nextafter(u, state.input) if u != state.input else u
            out, _ = model.apply([inside], state)
            assert out[0] == pytest.approx(state.output, abs=1e-12)


def test_switching_many_relays_matches_brute_force():
    rng = np.random.default_rng(3)
    n = 300
    s, r = rng.normal(0, 1, n), rng.uniform(0, 1, n)
    model = PreisachModel.from_relays(s + r, s - r)
    walk = np.cumsum(rng.normal(0, 0.3, 60))
    state = model.initial_state(walk[0])
    for k in range(1, walk.size):
        _, state = model.apply(walk[k : k + 1], state)
        sw = model.switching(state)
        lower, upper, jd, ju = brute_switching(
            model.alpha, model.beta, model.weights, walk[: k + 1]
        )
        assert (sw.lower, sw.upper) == (lower, upper)
        assert sw.jump_up == pytest.approx(ju, abs=1e-12)
        assert sw.jump_down == pytest.approx(jd, abs=1e-12)


@pytest.mark.parametrize("order", ["increasing", "decreasing", "random"])
def test_large_jumps_switch_everything(order):
    # one step switches all 50 000 relays; the range recursion must report each exactly once
    # whatever the beta order inside the alpha order (worst cases for the recursion depth)
    n = 50_000
    rng = np.random.default_rng(9)
    alpha = np.sort(rng.uniform(-1, 1, n))
    gap = {"increasing": np.linspace(0, 1, n), "decreasing": np.linspace(1, 0, n)}.get(
        order, rng.uniform(0, 1, n)
    )
    beta = alpha - gap
    model = PreisachModel.from_relays(alpha, beta)
    out, state = model.apply([-5.0, 5.0, -5.0, 0.0, 5.0, 0.3, -0.2])
    # vectorised relay-by-relay reference
    up = np.zeros(n, dtype=bool)
    expected = []
    for u in [-5.0, 5.0, -5.0, 0.0, 5.0, 0.3, -0.2]:
        up = (u >= alpha) | (up & (u >= beta))
        expected.append(np.mean(np.where(up, 1.0, -1.0)))
    np.testing.assert_allclose(out, expected, atol=1e-11)
    assert np.array_equal(model.relay_states(state), up)


def test_initial_state_and_saturation():
    model = PreisachModel.from_relays([1.0, 2.0, 3.0], [0.0, -1.0, 3.0])
    assert model.initial_state(-10).output == pytest.approx(-1.0)
    assert model.initial_state(10).output == pytest.approx(1.0)
    # threshold reached exactly: relay switches up (u >= alpha)
    assert model.initial_state(2.0).output == pytest.approx(1 / 3)
    # falling exactly to beta does not switch down; falling below does
    state = model.initial_state(10)
    out, _ = model.apply([0.0, np.nextafter(0.0, -1)], state)
    np.testing.assert_allclose(out, [1.0 - 2 / 3, 1.0 - 4 / 3])
    positive = model.state_from_extrema([0.5], saturation="positive")
    assert np.array_equal(model.relay_states(positive), [True, True, False])


def test_state_from_extrema_and_read_only():
    model = PreisachModel.from_relays([1.0, 2.0, 0.5], [0.0, -1.0, 0.5])
    state = model.state_from_extrema([3.0, -0.5, 1.5, 0.2])
    assert isinstance(state, PreisachState)
    ref, up = brute_force(model.alpha, model.beta, model.weights, [3.0, -0.5, 1.5, 0.2])
    assert state.output == pytest.approx(ref[-1])
    assert np.array_equal(model.relay_states(state), up)
    assert state.input == 0.2
    for arr in (model.alpha, model.beta, model.weights, state.extrema):
        with pytest.raises(ValueError):
            arr[0] = 7.0
    with pytest.raises(AttributeError):
        state.output = 0.0  # type: ignore[misc]


def test_staircase_is_bounded_by_relays():
    # a damped oscillation never wipes out anything: without pruning the staircase would grow
    # with every turn; with 3 relays it must stay small
    model = PreisachModel.from_relays([1.0, 0.5, 0.25], [-1.0, -0.5, -0.25])
    k = np.arange(1, 2000)
    inputs = (-1.0) ** k * (2.0 / k)
    out, state = model.apply(inputs)
    assert state.extrema.size <= 2 * model.n_relays + 6
    ref, _ = brute_force(model.alpha, model.beta, model.weights, inputs)
    np.testing.assert_allclose(out, ref, atol=1e-12)


def test_model_attributes():
    model = PreisachModel.from_relays([3.0, 1.0, 2.0], [1.0, -1.0, 0.0])
    assert model.n_relays == 3
    assert model.equal_widths
    np.testing.assert_allclose(model.sorted_centres, [0.0, 1.0, 2.0])
    np.testing.assert_array_equal(model.order_by_centre, [1, 2, 0])
    np.testing.assert_allclose(model.weights, [1 / 3] * 3)
    assert not PreisachModel.from_relays([3.0, 1.0], [1.0, 0.0]).equal_widths
    assert model.piecewise_constant


# ------------------------------------------------------------------------------------------
# play operator limits
# ------------------------------------------------------------------------------------------


def _play_positions(inputs, width):
    # independent play: w = max(u - p/2, min(u + p/2, w_prev)), w0 = u0 - p/2
    w = inputs[0] - width / 2
    out = []
    for u in inputs:
        w = max(u - width / 2, min(u + width / 2, w))
        out.append(w)
    return np.array(out)


def test_uniform_centres_give_affine_play():
    a, b, p, n = -2.0, 2.0, 1.0, 2000
    centres = a + (np.arange(n) + 0.5) * (b - a) / n
    model = PreisachModel.from_relays(centres + p / 2, centres - p / 2)
    rng = np.random.default_rng(5)
    inputs = np.clip(np.cumsum(rng.normal(0, 0.2, 3000)), a + p / 2, b - p / 2)
    w = _play_positions(inputs, p)
    out, _ = model.apply(inputs)
    np.testing.assert_allclose(out, (2 * w - a - b) / (b - a), atol=2.0 / n)
    # and the play from hysteresis.play agrees with the independent one
    from hysteresis.play import PlayOperator

    play_out, _ = PlayOperator(width=p).apply(inputs)
    np.testing.assert_allclose(play_out, w, atol=1e-14)


@pytest.mark.parametrize("seed", [0, 1])
def test_gaussian_equal_width_is_play_plus_empirical_cdf(seed):
    rng = np.random.default_rng(seed)
    n, p = 5000, 2.0
    centres = rng.normal(0, 1, n)
    model = PreisachModel.from_relays(centres + p / 2, centres - p / 2)
    inputs = 3 * np.sin(np.linspace(0, 30, 4000)) * np.linspace(1, 0.2, 4000)
    inputs += rng.normal(0, 0.05, inputs.size)
    w = _play_positions(inputs, p)
    sorted_c = np.sort(centres)
    expected = 2 * np.searchsorted(sorted_c, w, side="right") / n - 1
    out, _ = model.apply(inputs)
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_gaussian_equal_width_approaches_erf_play():
    from hysteresis.play import GeneralizedPlay

    p, spread = 2.0, 1.0
    t = np.linspace(0, 40, 6000)
    inputs = 3.5 * np.sin(t) * np.exp(-t / 30) + 0.3 * np.sin(3.1 * t)
    limit, _ = GeneralizedPlay.erf(p, spread).apply(inputs)
    # the paper's closed form, independently of hysteresis.play
    np.testing.assert_allclose(
        limit, erf(_play_positions(inputs, p) / (math.sqrt(2) * spread)), atol=1e-12
    )
    errors = {}
    for n in (1_000, 100_000):
        centres = np.random.default_rng(42).normal(0, spread, n)
        out, _ = PreisachModel.from_relays(centres + p / 2, centres - p / 2).apply(inputs)
        errors[n] = float(np.max(np.abs(out - limit)))
        # Kolmogorov–Smirnov: sup|F_N - Φ| ≈ 1.63/sqrt(N) at the 1% level; M = 2F - 1
        assert errors[n] < 2 * 1.63 / math.sqrt(n)
    assert errors[100_000] < errors[1_000] / 3  # shrinks like 1/sqrt(N) (ratio 10 expected)


# ------------------------------------------------------------------------------------------
# continuous model
# ------------------------------------------------------------------------------------------

LOWER, UPPER = -2.0, 2.0


def uniform_density(alpha, beta):
    alpha, beta = np.broadcast_arrays(alpha, beta)
    return np.full(alpha.shape, 2.0 / (UPPER - LOWER) ** 2)


def uniform_everett(a, b):
    # mass of {b < beta <= alpha <= a} for the uniform density on the triangle
    return (2.0 / (UPPER - LOWER) ** 2) * np.maximum(a - b, 0.0) ** 2 / 2


def smooth_density(alpha, beta):
    # a smooth bump in (r, s), normalised numerically below
    s, r = (alpha + beta) / 2, (alpha - beta) / 2
    return np.exp(-((s - 0.2) ** 2) / 0.5) * r * np.exp(-r / 0.4)


def _normalised_smooth():
    x = np.linspace(LOWER, UPPER, 1601)
    h = x[1] - x[0]
    mid = x[:-1] + h / 2
    A, B = np.meshgrid(mid, mid, indexing="ij")
    mass = np.sum(np.where(A >= B, smooth_density(A, B), 0.0)) * h * h
    return lambda a, b: smooth_density(a, b) / mass


def _discretised(density, n):
    # brute-force discretisation: one relay per cell centre with the cell's (midpoint) mass
    h = (UPPER - LOWER) / n
    x = LOWER + (np.arange(n) + 0.5) * h
    A, B = np.meshgrid(x, x, indexing="ij")
    keep = A > B
    w = density(A[keep], B[keep]) * h * h
    return PreisachModel.from_relays(A[keep], B[keep], w / w.sum())


def test_everett_sign_and_factor_two():
    model = PreisachModel.from_everett(uniform_everett, LOWER, UPPER)
    c = 2.0 / (UPPER - LOWER) ** 2
    # mu = -d2E/(da db) > 0 (sign), equal to the uniform density
    pts_a, pts_b = np.array([1.0, 0.5, 1.5]), np.array([-1.0, 0.0, -0.5])
    np.testing.assert_allclose(model.density(pts_a, pts_b), c, rtol=1e-5)
    # E(alpha, beta) = (f_alpha - f_alpha_beta)/2: rise from saturation to alpha, fall to beta
    for a, b in [(1.0, -1.0), (0.3, 0.1), (2.0, -2.0)]:
        out, _ = model.apply([LOWER - 1, a, b])
        assert (out[1] - out[2]) / 2 == pytest.approx(float(uniform_everett(a, b)), rel=1e-12)
    # rotated coordinates: mu_rs = 2 mu and it integrates to 1 over r in [0, L/2], s in the domain
    assert model.density_rs(0.3, 0.1) == pytest.approx(2 * c, rel=1e-5)
    r = np.linspace(0, (UPPER - LOWER) / 2, 401)
    s = np.linspace(LOWER, UPPER, 401)
    R, S = np.meshgrid((r[1:] + r[:-1]) / 2, (s[1:] + s[:-1]) / 2, indexing="ij")
    inside = (S + R <= UPPER) & (S - R >= LOWER)
    mass_rs = np.sum(np.where(inside, 2 * c, 0.0)) * (r[1] - r[0]) * (s[1] - s[0])
    assert mass_rs == pytest.approx(1.0, abs=1e-2)
    # the same model from its density: tabulated Everett function agrees with the closed form
    tab = PreisachModel.from_density(uniform_density, LOWER, UPPER, resolution=200)
    a = np.array([1.0, 0.37, 2.0, -1.3])
    b = np.array([-1.0, 0.11, -2.0, -1.9])
    np.testing.assert_allclose(tab.everett(a, b), uniform_everett(a, b), atol=2e-4)


def test_continuous_matches_discretisation():
    density = _normalised_smooth()
    model = PreisachModel.from_density(density, LOWER, UPPER, resolution=256)
    rng = np.random.default_rng(11)
    inputs = np.clip(np.cumsum(rng.normal(0, 0.4, 400)), -2.5, 2.5)
    out, _ = model.apply(inputs)
    assert np.all(np.abs(out) <= 1 + 1e-12)
    errors = []
    for n in (50, 200):
        ref, _ = _discretised(density, n).apply(inputs)
        errors.append(float(np.max(np.abs(out - ref))))
    # the discretisation error shrinks with the relay grid (~1/n)
    assert errors[1] < 0.02
    assert errors[1] < errors[0] / 2


def test_continuous_split_apply_and_branch_slope():
    density = _normalised_smooth()
    model = PreisachModel.from_density(density, LOWER, UPPER, resolution=256)
    inputs = [0.0, 1.5, -1.0, 1.0, -0.5, 0.4]
    out, state = model.apply(inputs)
    o1, s1 = model.apply(inputs[:3])
    o2, s2 = model.apply(inputs[3:], s1)
    np.testing.assert_allclose(np.concatenate([o1, o2]), out, atol=1e-13)
    assert s2 == state
    np.testing.assert_allclose(state.extrema, [1.5, -1.0, 1.0, -0.5, 0.4])
    # branch slopes against finite differences of the output (rising, then falling)
    h = 1e-3
    br = model.branch(state, +1)
    up_out, _ = model.apply([0.4 + h], state)
    assert br.slope == pytest.approx((up_out[0] - state.output) / h, rel=2e-2)
    assert br.breakpoint == 1.0
    _, s_fall = model.apply([0.7, 0.1], state)  # falling from the maximum 0.7
    br_down = model.branch(s_fall, -1)
    down_out, _ = model.apply([0.1 - h], s_fall)
    assert br_down.slope == pytest.approx((s_fall.output - down_out[0]) / h, rel=2e-2)
    assert br_down.breakpoint == -0.5
    # right after a reversal the branch starts flat (E(u, m) ~ mu (u - m)^2 / 2)
    assert model.branch(s_fall, +1).slope == 0.0
    lin = model.linearize(state, +1)
    assert lin.d_output_d_input == pytest.approx(br.slope, rel=1e-12)
    assert lin.d_output_d_memory.shape == (4,)


def test_continuous_initial_state():
    model = PreisachModel.from_everett(uniform_everett, LOWER, UPPER)
    assert model.initial_state(-5).output == pytest.approx(-1.0)
    assert model.initial_state(5).output == pytest.approx(1.0)
    assert model.initial_state(0.0).output == pytest.approx(-1 + 2 * uniform_everett(0.0, LOWER))


# ------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(alpha=[0.0, 1.0], beta=[0.5, 0.0]), "alpha"),
        (dict(alpha=[np.nan], beta=[0.0]), "alpha"),
        (dict(alpha=[1.0], beta=[np.inf]), "beta"),
        (dict(alpha=[1.0, 2.0], beta=[0.0]), "length"),
        (dict(alpha=[], beta=[]), "alpha"),
        (dict(alpha=[1.0, 2.0], beta=[0.0, 0.0], weights=[0.5, 0.6]), "weights"),
        (dict(alpha=[1.0, 2.0], beta=[0.0, 0.0], weights=[1.5, -0.5]), "weights"),
        (dict(alpha=[1.0, 2.0], beta=[0.0, 0.0], weights=[1.0]), "weights"),
        (dict(alpha=[1.0, 2.0], beta=[0.0, 0.0], weights=[np.nan, 1.0]), "weights"),
    ],
)
def test_bad_relays_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PreisachModel.from_relays(**kwargs)


def test_bad_inputs_raise():
    model = PreisachModel.from_relays([1.0], [0.0])
    with pytest.raises(ValueError, match="inputs"):
        model.apply([])
    with pytest.raises(ValueError, match="inputs"):
        model.apply([0.0, np.nan])
    with pytest.raises(ValueError, match="u0"):
        model.initial_state(np.nan)
    with pytest.raises(ValueError, match="state"):
        model.apply([0.0], state="nope")
    with pytest.raises(ValueError, match="saturation"):
        model.state_from_extrema([1.0], saturation="sideways")
    cont = PreisachModel.from_everett(uniform_everett, LOWER, UPPER)
    with pytest.raises(ValueError, match="direction"):
        cont.branch(cont.initial_state(0.0), 0)
    with pytest.raises(ValueError, match="state"):
        model.apply([0.0], cont.initial_state(0.0))


def test_bad_continuous_raise():
    with pytest.raises(ValueError, match="density"):
        PreisachModel.from_density(lambda a, b: 2 * uniform_density(a, b), LOWER, UPPER)
    with pytest.raises(ValueError, match="density"):
        PreisachModel.from_density(lambda a, b: -uniform_density(a, b), LOWER, UPPER)
    with pytest.raises(ValueError, match="upper"):
        PreisachModel.from_density(uniform_density, 1.0, 1.0)
    with pytest.raises(ValueError, match="resolution"):
        PreisachModel.from_density(uniform_density, LOWER, UPPER, resolution=0)
    with pytest.raises(ValueError, match="everett"):
        PreisachModel.from_everett(lambda a, b: 0.5 * uniform_everett(a, b), LOWER, UPPER)
    with pytest.raises(ValueError, match="lower"):
        PreisachModel.from_everett(uniform_everett, np.nan, UPPER)
