"""The switching kernel's trigger structure (per-list boundaries, membership words, candidates:
:mod:`oscillators.engines._switching_kernels`) against a brute force over all spins, event by
event, on random small graphs and lattices over long random histories with reversals: after
every event the spins must be the previous spins relaxed at the event's input (every unstable
spin flipped until none is left), ``n_up`` and ``M`` their count, and the two next triggers the
least threshold ``−(f_i + J·n_i)`` of a down spin and the greatest of an up spin (exact float
equality: the kernel forms the same sums)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hysteresis.rfim import RandomFieldIsing
from oscillators import ForcedOscillator
from oscillators.engines import _relay_kernels as rk
from oscillators.engines import _switching_kernels as sk

ZETA, OMEGA = 0.05, 1.0


def neighbour_sums(edges: np.ndarray, s: np.ndarray) -> np.ndarray:
    n = np.zeros(s.size, dtype=np.int64)
    np.add.at(n, edges[:, 0], s[edges[:, 1]])
    np.add.at(n, edges[:, 1], s[edges[:, 0]])
    return n


def relax(s: np.ndarray, u: float, f: np.ndarray, edges: np.ndarray, j: float) -> np.ndarray:
    """Flip every spin against h = u + (f + J n) (h = 0: up) until none is left."""
    s = s.copy()
    while True:
        bad = ((u + (f + j * neighbour_sums(edges, s))) >= 0.0) != (s > 0)
        if not bad.any():
            return s
        s[bad] = -s[bad]


def triggers(s: np.ndarray, f: np.ndarray, edges: np.ndarray, j: float) -> tuple[float, float]:
    thr = -(f + j * neighbour_sums(edges, s))
    up = float(thr[s < 0].min()) if np.any(s < 0) else math.inf
    down = float(thr[s > 0].max()) if np.any(s > 0) else -math.inf
    return up, down


def models():
    rng = np.random.default_rng(11)
    out = []
    for k in range(4):  # random graphs, degrees 0 to ~12, fields with and without ties
        n = int(rng.integers(20, 70))
        pairs = np.unique(np.sort(rng.integers(0, n, (3 * n, 2)), axis=1), axis=0)
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]
        f = rng.normal(0.0, 1.5, n)
        if k % 2:
            f = np.round(f * 2) / 2  # exact ties: several spins share a threshold
        out.append(RandomFieldIsing(f, pairs, float(rng.choice([0.25, 0.5, 1.0]))))
    out.append(RandomFieldIsing.lattice((4, 5, 3), 1.2, seed=4))
    tied = RandomFieldIsing.lattice((6, 6), 1.0, spin_coupling=0.5, seed=5)
    out.append(RandomFieldIsing(np.round(np.asarray(tied.fields) * 4) / 4, tied.edges(), 0.5))
    out.append(RandomFieldIsing.lattice(9, 0.8, seed=6))
    return out


@pytest.mark.parametrize("model", models(), ids=lambda m: repr(m))
def test_triggers_and_spins_match_brute_force_over_random_histories(model):
    """600 events per model, direction kept with probability 0.8 (reversals all along), the
    engine's plan driven event by event (``switch``), every event checked against the brute
    force; the event order and the copies (``_switched_copy``) agree too."""
    f, e, j = np.asarray(model.fields), model.edges(), model.spin_coupling
    rng = np.random.default_rng(model.n_spins)
    eng = ForcedOscillator(model, 1.0, ZETA, OMEGA).engine()
    st, ist, plan = eng._st, eng._ist, eng._plan
    s = model.spins(eng.state().operator_state).astype(np.int64)
    assert (st[rk.S_UP], st[rk.S_DN]) == triggers(s, f, e, j)
    direction, reversals, flips = 1, 0, 0
    for _ in range(600):
        if rng.random() > 0.8:
            direction = -direction
            reversals += 1
        if not math.isfinite(st[rk.S_UP] if direction > 0 else st[rk.S_DN]):
            direction = -direction  # saturated: the other way
        trig = st[rk.S_UP] if direction > 0 else st[rk.S_DN]
        u = trig if direction > 0 else math.nextafter(trig, -math.inf)
        copy = eng._switched_copy(direction)
        jump, count = sk.switch(direction, st, ist, plan)
        relaxed = relax(s, u, f, e, j)
        assert count == int(np.sum(relaxed != s)) >= 1
        s = relaxed
        flips += count
        bits = np.unpackbits(plan[sk.PL_BITS], count=model.n_spins, bitorder="little")
        np.testing.assert_array_equal(2 * bits.astype(np.int64) - 1, s)
        n_up = int(np.sum(s > 0))
        assert ist[sk.I_NUP] == n_up and st[rk.S_MV] == (2 * n_up - s.size) / s.size
        assert st[sk.S_U] == u
        assert (st[rk.S_UP], st[rk.S_DN]) == triggers(s, f, e, j)
        assert copy == (st[rk.S_MV], st[rk.S_UP], st[rk.S_DN])
        assert jump == st[rk.S_MV] - (2 * (n_up - direction * count) - s.size) / s.size
    assert reversals >= 80 and flips >= 600
