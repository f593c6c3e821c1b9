"""RelayTable, the nested plan and the relay contract of the piecewise-constant operators.

Independent truths: single relays driven by hand (the relay rule written here), the Preisach
model's own staircase reading ``relay_states`` (O(N·depth), a different algorithm from
``relay_outputs``), and the brute-force spin-flip dynamics of the dimers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hysteresis import PreisachModel, Relay, SpinDimerEnsemble
from hysteresis.relay_table import NestedPlan, RelayTable


def relays_by_hand(alpha, beta, inputs, y0):
    """Every relay driven through ``inputs`` from outputs ``y0`` with the relay rule."""
    y = np.array(y0, dtype=float)
    for u in inputs:
        y[u >= alpha] = 1.0
        y[u < beta] = -1.0
    return y


def random_model(rng, n, zero_width=0.0, zero_weight=0.0, grid=None):
    c = rng.normal(size=n)
    r = rng.uniform(0.0, 1.5, size=n)
    if grid:
        c, r = np.round(c / grid) * grid, np.round(r / grid) * grid
    r[rng.random(n) < zero_width] = 0.0
    w = rng.random(n) + 0.1
    w[rng.random(n) < zero_weight] = 0.0
    if w.sum() == 0.0:
        w[0] = 1.0
    w = w / w.sum()
    w[np.argmax(w)] += 1.0 - w.sum()
    return PreisachModel.from_relays(c + r, c - r, w)


# -- RelayTable ---------------------------------------------------------------------------------
def test_table_validation():
    with pytest.raises(ValueError, match="same length"):
        RelayTable([1.0, 2.0], [0.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="alpha must be >= beta"):
        RelayTable([0.0], [1.0], [1.0])
    with pytest.raises(ValueError, match="weights must be >= 0"):
        RelayTable([1.0], [0.0], [-1.0])
    with pytest.raises(ValueError, match="alpha"):
        RelayTable([np.nan], [0.0], [1.0])
    with pytest.raises(ValueError, match="alpha"):
        RelayTable([], [], [])


def test_table_is_immutable():
    t = RelayTable([1.0, 2.0], [0.0, 1.0], [0.5, 0.5])
    for arr in (t.alpha, t.beta, t.weights):
        with pytest.raises(ValueError):
            arr[0] = 3.0
    with pytest.raises(AttributeError):
        t.foo = 1
    assert t.n_relays == len(t) == 2


def test_check_outputs():
    t = RelayTable([1.0, 2.0], [0.0, 1.5], [0.5, 0.5])
    assert np.array_equal(t.check_outputs([1, -1], 1.2), [1.0, -1.0])
    with pytest.raises(ValueError, match="length"):
        t.check_outputs([1.0], 0.5)
    with pytest.raises(ValueError, match=r"\+1 or -1"):
        t.check_outputs([1.0, 0.0], 0.5)
    with pytest.raises(ValueError, match="not reachable"):
        t.check_outputs([-1.0, -1.0], 1.2)  # alpha_0 = 1 <= 1.2 must be up
    with pytest.raises(ValueError, match="not reachable"):
        t.check_outputs([1.0, 1.0], 1.2)  # beta_1 = 1.5 > 1.2 must be down
    assert t.output([1.0, -1.0]) == 0.0


def test_nested_plan_equal_widths_matches_prefix_outputs():
    rng = np.random.default_rng(3)
    c = rng.normal(size=40)
    w = rng.random(40)
    w /= w.sum()
    t = RelayTable(c + 0.7, c - 0.7, w)
    plan = t.nested_plan()
    assert isinstance(plan, NestedPlan)
    assert plan is t.nested_plan()  # cached
    assert np.all(np.diff(plan.up) > 0) and np.all(np.diff(plan.down) > 0)
    for k in range(plan.n_groups + 1):
        y = plan.outputs(k, t.n_relays)
        # independent: the first k relays by centre up
        expect = np.where(np.argsort(np.argsort(c)) < k, 1.0, -1.0)
        assert np.array_equal(y, expect)
        assert plan.mval[k] == pytest.approx(math.fsum(w * expect), abs=1e-14)
        assert plan.index_of(y) == k
    y = plan.outputs(3, t.n_relays)
    y[plan.order[5]] = 1.0  # not a prefix any more
    assert plan.index_of(y) is None


def test_nested_plan_groups_ties_and_equal_weights_are_exact():
    # two relays at identical thresholds form one group; dimers: M_k = 4k/N - 1 exactly
    t = RelayTable([1.0, 1.0, 2.0, 3.0], [0.0, 0.0, 1.0, 2.0], [0.25] * 4)
    plan = t.nested_plan()
    assert plan.n_groups == 3
    assert list(plan.mval) == [-1.0, 0.0, 0.5, 1.0]
    assert plan.index_at(1.0) == 1 and plan.index_at(0.999) == 0


def test_nested_plan_none_for_random_widths():
    rng = np.random.default_rng(0)
    c = rng.normal(size=30)
    r = rng.uniform(0.5, 1.5, size=30)
    assert RelayTable(c + r, c - r, np.full(30, 1 / 30)).nested_plan() is None


# -- Relay ---------------------------------------------------------------------------------------
def test_relay_contract_round_trip():
    relay = Relay(1.0, -0.5)
    table = relay.relay_table()
    assert (table.alpha[0], table.beta[0], table.weights[0]) == (1.0, -0.5, 1.0)
    _, s = relay.apply([0.0, 1.2, 0.3])
    y = relay.relay_outputs(s)
    assert list(y) == [1.0]
    s2 = relay.state_from_relay_outputs(y, 0.3)
    path = np.array([0.5, -0.4, -0.6, 0.9, 1.0, -0.7])
    assert np.array_equal(relay.apply(path, s)[0], relay.apply(path, s2)[0])
    with pytest.raises(ValueError):
        relay.state_from_relay_outputs([1.0], -1.0)  # +1 below beta cannot be reached
    with pytest.raises(ValueError, match="length 1"):
        relay.state_from_relay_outputs([1.0, 1.0], 0.0)


# -- discrete Preisach -----------------------------------------------------------------------
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 25),
    steps=st.integers(1, 40),
    ties=st.booleans(),
    zero_width=st.sampled_from([0.0, 0.3]),
    zero_weight=st.sampled_from([0.0, 0.3]),
)
def test_preisach_relay_outputs_and_round_trip(seed, n, steps, ties, zero_width, zero_weight):
    rng = np.random.default_rng(seed)
    grid = 0.25 if ties else None
    model = random_model(rng, n, zero_width, zero_weight, grid)
    path = np.cumsum(rng.normal(size=steps))
    if ties:
        path = np.round(path / 0.25) * 0.25  # inputs exactly on thresholds
    _, state = model.apply(path)
    y = model.relay_outputs(state)
    # independent: each relay by hand from negative saturation (rising to path[0] first)
    by_hand = relays_by_hand(model.alpha, model.beta, path, -np.ones(n))
    assert np.array_equal(y, by_hand)
    assert np.array_equal(y > 0, model.relay_states(state))
    assert math.fsum(model.weights * y) == pytest.approx(model.output(state), abs=1e-12)

    rebuilt = model.state_from_relay_outputs(y, state.input)
    active = model.weights > 0
    assert np.array_equal(model.relay_outputs(rebuilt)[active], y[active])
    assert rebuilt.input == state.input
    future = state.input + np.cumsum(rng.normal(size=30))
    if ties:
        future = np.round(future / 0.25) * 0.25
    out_a, _ = model.apply(future, state)
    out_b, _ = model.apply(future, rebuilt)
    np.testing.assert_allclose(out_b, out_a, rtol=0, atol=1e-12)


def test_preisach_unreachable_configuration_raises():
    model = PreisachModel.from_relays([1.0, 2.0], [0.0, 0.5], [0.5, 0.5])
    # relay 1 (α=2, β=0.5) up forces relay 0 (α=1 <= 2, β=0 <= 0.5) up as well
    with pytest.raises(ValueError, match="not a reachable"):
        model.state_from_relay_outputs([-1.0, 1.0], 0.7)
    with pytest.raises(ValueError, match="not reachable"):
        model.state_from_relay_outputs([-1.0, -1.0], 1.5)  # α_0 = 1 <= 1.5 must be up
    with pytest.raises(ValueError, match="length"):
        model.state_from_relay_outputs([1.0], 0.0)


def test_preisach_relay_table_order_and_cache():
    model = PreisachModel.from_relays([1.0, 0.5, 2.0], [0.0, -1.0, 1.5], [0.2, 0.3, 0.5])
    t = model.relay_table()
    assert t is model.relay_table()
    assert np.array_equal(t.alpha, model.alpha) and np.array_equal(t.weights, model.weights)


# -- spin dimers -------------------------------------------------------------------------------
@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 30))
def test_dimer_relay_outputs_match_spin_dynamics(seed, steps):
    rng = np.random.default_rng(seed)
    n_dimers = 12
    fields = rng.normal(0.0, 1.5, size=(n_dimers, 2))
    ens = SpinDimerEnsemble(fields, spin_coupling=0.8)  # mixes hysteretic and non-hysteretic dimers
    path = np.cumsum(rng.normal(size=steps))
    _, state = ens.apply(path)
    _, spins = ens.simulate(path)  # brute force, starts all down relaxed at path[0]
    spins = spins.reshape(-1, 2)
    th = ens.thresholds()
    expect = np.concatenate(
        [
            np.where(spins[th.paired, 0] > 0, 1.0, -1.0),  # a pair flips together
            spins[~th.paired, 0].astype(float),  # first spin: zero-width relay at J - b1
            spins[~th.paired, 1].astype(float),  # second spin: at -J - b2
        ]
    )
    assert np.array_equal(ens.relay_outputs(state), expect)
    table = ens.relay_table()
    n = ens.n_spins
    assert math.fsum(table.weights * expect) == pytest.approx(spins.sum() / n, abs=1e-12)
    rebuilt = ens.state_from_relay_outputs(expect, state.input)
    future = state.input + np.cumsum(rng.normal(size=20))
    out_a, out_b = ens.apply(future, state)[0], ens.apply(future, rebuilt)[0]
    np.testing.assert_allclose(out_b, out_a, rtol=0, atol=1e-12)  # running sums: round-off


def test_dimer_relay_table_weights():
    ens = SpinDimerEnsemble(np.array([[0.1, -0.1], [3.0, -3.0]]), spin_coupling=1.0)
    t = ens.relay_table()
    # dimer 0 hysteretic: one relay 2/N; dimer 1 (b1 - b2 = 6 > 2J): two zero-width relays 1/N
    assert list(t.weights) == [0.5, 0.25, 0.25]
    assert np.array_equal(t.alpha[1:], t.beta[1:])
