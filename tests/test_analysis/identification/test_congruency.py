"""Minor-loop congruency (analysis.identification.congruency): exactly congruent for Preisach
operators (Mayergoyz's theorem), not for the random-field Ising model — checked against a
brute-force relaxation of the spins, independent of the operator's sorted-threshold engine."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.identification.congruency import (
    congruency_scan,
    default_histories,
    minor_loop_congruency,
)
from hysteresis import PreisachModel, RandomFieldIsing, SpinDimerEnsemble

#: round-off of an output that is a sum of a few hundred weights (differences of such sums)
ROUND_OFF = 1e-13


def _preisach(seed: int) -> PreisachModel:
    rng = np.random.default_rng(seed)
    s, r = rng.normal(0.0, 1.0, 500), np.abs(rng.normal(0.8, 0.3, 500))
    w = rng.random(500)
    return PreisachModel.from_relays(s + r, s - r, w / w.sum())


def _dimers(seed: int) -> SpinDimerEnsemble:
    """Dimers of many loop widths (``α − β = 2J − (b1 − b2)``), unlike the paper's fixed p."""
    return SpinDimerEnsemble(np.random.default_rng(seed).normal(0.0, 1.0, (300, 2)), 1.0)


@pytest.mark.parametrize("operator", [_preisach(0), _dimers(1)], ids=["preisach", "dimers"])
def test_preisach_operators_have_congruent_minor_loops(operator):
    scan = congruency_scan(operator, np.linspace(-2.0, 2.0, 6), 8.0)
    assert scan["violation"] <= ROUND_OFF and scan["return_gap"] <= ROUND_OFF
    # the loops are not trivial and the histories leave different states at the loop's start
    assert max(scan["heights"]) > 0.5
    r = minor_loop_congruency(operator, -0.6, 0.6, default_histories(-0.6, 0.6, 8.0))
    assert r["spread_at_low"] > 0.05 and r["height"] > 0.02 and r["violation"] <= ROUND_OFF


def _brute_force_outputs(op: RandomFieldIsing, drive: np.ndarray) -> np.ndarray:
    """M after each input: all spins down, then at every input all unstable spins flipped
    (down→up where h_i >= 0, up→down where h_i < 0) until none is; h_i = u + f_i + J·Σ s_j."""
    n = op.n_spins
    nbrs = [[] for _ in range(n)]
    for i, j in op.edges():
        nbrs[i].append(j)
        nbrs[j].append(i)
    nbrs = np.array(nbrs)
    s = -np.ones(n)
    out = []
    for u in drive:
        while True:
            h = u + op.fields + op.spin_coupling * s[nbrs].sum(axis=1)
            up, down = (s < 0) & (h >= 0), (s > 0) & (h < 0)
            if not (up.any() or down.any()):
                break
            s[up], s[down] = 1.0, -1.0
        out.append(s.mean())
    return np.array(out)


def test_lattice_near_rc_violates_congruency_as_brute_force_shows():
    op = RandomFieldIsing.lattice((6, 6, 6), 2.16, seed=4)
    sat = float(np.max(np.abs(op.fields))) + 8.0
    scan = congruency_scan(op, np.linspace(-2.0, 2.0, 7), sat)
    low, high = scan["worst_loop"]
    hist = default_histories(low, high, sat)
    got = minor_loop_congruency(op, low, high, hist)
    assert got["violation"] == scan["violation"]
    # the same statistic from the brute-force spins (the drive of minor_loop_congruency)
    up = np.linspace(low, high, 16)
    loop = np.concatenate([up[1:], up[::-1][1:]])
    deltas = []
    for h in hist:
        m = _brute_force_outputs(op, np.concatenate([h, [high, low], loop]))
        deltas.append(m[h.size + 2 :] - m[h.size + 1])
        assert m[-1] == m[h.size + 1]  # return-point memory
    d = np.asarray(deltas)
    brute = float(np.max(np.abs(d[1:] - d[0])))
    assert brute == pytest.approx(got["violation"], abs=1e-15)
    assert brute >= 2.0 / op.n_spins  # at least one spin ends the loop differently
    assert got["return_gap"] == 0.0


def test_bad_input_raises():
    op = _preisach(1)
    with pytest.raises(ValueError, match="low must be < high"):
        minor_loop_congruency(op, 1.0, 0.0, default_histories(-1.0, 0.0, 5.0))
    with pytest.raises(ValueError, match="samples"):
        minor_loop_congruency(op, 0.0, 1.0, default_histories(0.0, 1.0, 5.0), samples=1)
    with pytest.raises(ValueError, match="saturation"):
        default_histories(0.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="count"):
        default_histories(0.0, 1.0, 5.0, count=1)
    with pytest.raises(ValueError, match="nodes"):
        congruency_scan(op, [1.0, 0.0], 5.0)
