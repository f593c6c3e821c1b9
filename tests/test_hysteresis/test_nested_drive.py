"""NestedPlan.drive: a nested relay table driven by an input sequence in O(log G) per input.

Independent truths: every relay driven by hand with the relay rule (up once ``u >= alpha``,
down once ``u < beta``), ``M = fsum(weights·y)``; the general discrete Preisach kernel
(``PreisachModel.apply``, a staircase and a running sum); the brute-force spin-flip dynamics of
the dimers (``SpinDimerEnsemble.simulate``).

Round-off bounds (u = eps/2, n relays, W = Σ weights, first order in n·u):

* ``mval`` vs the exact ``Σ w·y``: equal weights ``mval[k] = fl(fl((2c − n)/n)·fl(Σw))`` —
  the sum within γ_{n−1}·W (any summation order), two roundings more: ``(n + 2)·u·W``.
  Unequal weights ``2·cumsum − Σw``: two sums of at most n terms and one subtraction,
  ``(3n + 2)·u·W``. Rounding the truth with ``math.fsum``: ``u·W`` more.
* ``PreisachModel.apply`` keeps a running sum: its start ``−1 + 2·cumsum`` is within
  ``(2n + 1)·u`` (plus ``|1 − W|``: the model assumes ``W = 1``), and every input adds at most
  ``2·γ_n·W`` from its switched-weight sums plus one rounding per addition — at most two
  additions per input on average (one per pushed step, one per popped step) — so after t
  inputs it is within ``|1 − W| + (2n + 3)·(t + 1)·u·W``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hysteresis import PreisachModel, SpinDimerEnsemble
from hysteresis.relay_table import RelayTable

U = np.finfo(float).eps / 2.0


def nested_relays(rng, n_groups, ties=0.0, zero_width=False, zero_weight=0.0):
    """Thresholds with ``up`` and ``down`` both increasing (widths vary), ``ties``: fraction of
    relays that repeat another relay's thresholds (a group of several relays)."""
    down = np.cumsum(rng.uniform(0.05, 0.5, size=n_groups)) - 0.25 * n_groups
    if zero_width:
        up = down.copy()
    else:
        # the maximum of two strictly increasing sequences increases strictly: varied widths,
        # some of them zero
        up = np.cumsum(rng.uniform(0.05, 0.5, size=n_groups)) - 0.25 * n_groups
        up = np.maximum(up + rng.uniform(0.0, 1.0), down)
    copies = np.flatnonzero(rng.random(n_groups) < ties)
    alpha = np.concatenate([up, up[copies]])
    beta = np.concatenate([down, down[copies]])
    perm = rng.permutation(alpha.size)  # the table order is not the group order
    w = rng.random(alpha.size) + 0.1
    w[rng.random(alpha.size) < zero_weight] = 0.0
    if w.sum() == 0.0:
        w[0] = 1.0
    w /= w.sum()
    return alpha[perm], beta[perm], w[perm]


def inputs_on_thresholds(rng, alpha, beta, size, scale=1.0):
    """Gaussian inputs mixed with inputs exactly on a threshold and one ulp either side."""
    u = rng.normal(0.0, scale * (1.0 + np.std(alpha)), size=size)
    hit = rng.random(size) < 0.5
    th = rng.choice(np.concatenate([alpha, beta]), size=size)
    nudge = rng.integers(-1, 2, size=size)
    th = np.where(nudge > 0, np.nextafter(th, np.inf), th)
    th = np.where(nudge < 0, np.nextafter(th, -np.inf), th)
    return np.where(hit, th, u)


def relays_by_hand(alpha, beta, inputs, y):
    """Relay outputs after each input (rows), every relay driven with the relay rule."""
    y = np.array(y, dtype=float)
    states = np.empty((inputs.size, alpha.size))
    for t, v in enumerate(inputs):
        y[v >= alpha] = 1.0
        y[v < beta] = -1.0
        states[t] = y
    return states


def mval_bound(weights) -> float:
    w = np.asarray(weights)
    n, total = w.size, math.fsum(w)
    equal = bool(np.all(w == w[0]))
    return ((n + 3) if equal else (3 * n + 3)) * U * total


def preisach_bound(weights, steps: int) -> float:
    n, total = len(weights), math.fsum(weights)
    return abs(1.0 - total) + (2 * n + 3) * (steps + 1) * U * total


CASES = [  # (seed, groups, ties, zero_width, zero_weight, steps)
    (0, 1, 0.0, False, 0.0, 300),
    (1, 7, 0.5, False, 0.0, 500),
    (2, 40, 0.3, False, 0.2, 1500),
    (3, 40, 0.0, True, 0.0, 1500),
    (4, 120, 0.2, False, 0.0, 2000),
    (5, 25, 1.0, True, 0.3, 800),
]


@pytest.mark.parametrize("seed, groups, ties, zero_width, zero_weight, steps", CASES)
def test_drive_matches_relays_by_hand(seed, groups, ties, zero_width, zero_weight, steps):
    rng = np.random.default_rng(seed)
    alpha, beta, w = nested_relays(rng, groups, ties, zero_width, zero_weight)
    table = RelayTable(alpha, beta, w)
    plan = table.nested_plan()
    assert plan is not None
    u = inputs_on_thresholds(rng, alpha, beta, steps)
    k0 = plan.index_at(float(u[0]))
    y0 = table.initial_outputs(float(u[0]))
    assert np.array_equal(plan.outputs(k0, table.n_relays), y0)  # the start of initial_state
    out, k_final = plan.drive(u, k0)
    states = relays_by_hand(alpha, beta, u, y0)
    bound = mval_bound(w)
    for t in range(u.size):
        # exact: the relays up are a prefix of the plan and the output is its mval
        k = plan.index_of(states[t])
        assert k is not None
        assert out[t] == plan.mval[k]
        assert abs(out[t] - math.fsum(w * states[t])) <= bound
    assert k_final == plan.index_of(states[-1])
    # driving in pieces continues from the returned index: the same outputs, bit for bit
    first, k_mid = plan.drive(u[: steps // 3], k0)
    rest, k_end = plan.drive(u[steps // 3 :], k_mid)
    assert np.array_equal(np.concatenate([first, rest]), out) and k_end == k_final


@pytest.mark.parametrize("seed, groups, ties, zero_width, zero_weight, steps", CASES)
def test_drive_matches_the_preisach_kernel(seed, groups, ties, zero_width, zero_weight, steps):
    rng = np.random.default_rng(100 + seed)
    alpha, beta, w = nested_relays(rng, groups, ties, zero_width, zero_weight)
    model = PreisachModel.from_relays(alpha, beta, w)
    plan = model.relay_table().nested_plan()
    assert plan is not None
    u = inputs_on_thresholds(rng, alpha, beta, 10 * steps)  # long sequences
    expected, _ = model.apply(u)  # starts at initial_state(u[0])
    out, _ = plan.drive(u, plan.index_at(float(u[0])))
    err = np.abs(out - expected)
    assert np.all(err <= mval_bound(w) + preisach_bound(w, u.size))


def test_equal_width_model_on_a_grid_long_sequence():
    # equal widths, centres on a grid (many relays per group), a long sequence near the loop
    rng = np.random.default_rng(7)
    c = np.round(rng.normal(size=600) / 0.05) * 0.05
    w = np.full(600, 1.0 / 600)
    model = PreisachModel.from_relays(c + 0.8, c - 0.8, w)
    plan = model.relay_table().nested_plan()
    assert plan is not None and plan.n_groups < 600
    u = inputs_on_thresholds(rng, c + 0.8, c - 0.8, 50_000)
    expected, _ = model.apply(u)
    out, _ = plan.drive(u, plan.index_at(float(u[0])))
    assert np.max(np.abs(out - expected)) <= mval_bound(w) + preisach_bound(w, u.size)


@pytest.mark.parametrize("seed", [0, 1])
def test_dimers_drive_matches_spin_flips_and_apply(seed):
    ens = SpinDimerEnsemble.random(300, 2.0, 1.0, 2.0, seed)
    table = RelayTable(*ens.relays())
    ref = ens.relay_table()
    for a, b in ((table.alpha, ref.alpha), (table.beta, ref.beta), (table.weights, ref.weights)):
        assert np.array_equal(a, b)  # relays() is the order and weights of relay_table()
    plan = table.nested_plan()
    assert plan is not None
    u = np.random.default_rng(seed + 10).normal(0.0, 2.0, size=4000)
    out, _ = plan.drive(u, plan.index_at(float(u[0])))
    spins, _ = ens.simulate(u)  # all spins down, relaxed at u[0]: exact counts / N
    assert np.max(np.abs(out - spins)) <= mval_bound(table.weights)
    applied, _ = ens.apply(u, ens.initial_state(float(u[0])))
    w = table.weights
    assert np.max(np.abs(out - applied)) <= mval_bound(w) + preisach_bound(w, u.size)


def test_drive_rejects_bad_input():
    plan = RelayTable([1.0, 2.0], [0.0, 1.0], [0.5, 0.5]).nested_plan()
    for bad in ([], [[0.0, 1.0]], [0.0, np.nan], [np.inf], "0.5", [1e301]):
        with pytest.raises(ValueError, match="inputs"):
            plan.drive(bad, 0)
    for bad in (-1, 3, 1.0, True, None, "1"):
        with pytest.raises(ValueError, match="k must be an integer"):
            plan.drive([0.5], bad)
    with pytest.raises(ValueError, match="q must be"):
        plan.index_at(np.nan)
    out, k = plan.drive([2.5, 0.5], 2)  # k = G is allowed (every group up)
    assert k == 1 and list(out) == [1.0, 0.0]
