"""The random-field Ising model against its exact solution on trees: the ascending branch of
the zero-temperature hysteresis loop on the Bethe lattice of coordination z (Dhar, Shukla and
Sethna, J. Phys. A 30, 5259 (1997); z = 2 is Shukla's chain), compared with the periodic chain
and with random z-regular graphs (locally tree-like).

Derivation (ascending branch, from all spins down at u = −∞; Gaussian fields f ~ N(0, R²)).
A down spin with n up neighbours out of z flips up once u + f + J(2n − z) >= 0, so with
neighbours fixed it is up with probability

    p_n(u) = P(f >= −u − J(2n − z)) = Φ((u + J(2n − z))/R).

*Abelian property*: with J >= 0 the state reached at u does not depend on the order of the
flips, so we may relax the tree from the leaves towards a site i *holding i down*. Let P*(u)
be the probability that a neighbour j of i is up at u when i is held down. j's other z − 1
neighbours head disjoint subtrees (no loops), each up with probability P* independently
(same construction one level down), and j sees i down, so with n up children j's field is
u + f_j + J(2n − z):

    P* = Σ_{n=0}^{z−1} C(z−1, n) P*^n (1 − P*)^(z−1−n) p_n(u).                    (1)

Then release i: its z neighbours are independently up with probability P*, and i is up iff
its own threshold is reached, u + f_i + J(2n − z) >= 0 with n of z up. If i flips, it may flip
some neighbours in turn, but that does not change i's state (no-passing: up spins stay up
while u rises). Hence

    M(u) = 2 Σ_{n=0}^{z} C(z, n) P*^n (1 − P*)^(z−n) p_n(u) − 1.                  (2)

*Which root.* Truncating the tree at depth k (leaves held down) gives P*_k = F(P*_{k−1}),
P*_0 = 0, where F is the right side of (1): F is increasing in P* (p_n increases with n) so
P*_k increases to the *smallest* root of P* = F(P*) in [0, 1] (g = F − P* has g(0) = p_0 >= 0
and g(1) = p_{z−1} − 1 <= 0): the physical root is the smallest one. For z = 2, F is linear and
P* = p_0/(1 − p_1 + p_0). For z = 3, g is quadratic with g(0) >= 0 >= g(1): exactly one root
lies in [0, 1] and it moves continuously with u, so z = 3 has no jump at any disorder. For
z >= 4 (g of degree z − 1 >= 3) the smallest root can vanish in a saddle-node with another
root: P* and M jump to the next root at that u* — an infinite avalanche. For Gaussian fields
and z = 4 this happens below a critical disorder computed here (bisection on the existence
of three roots): R_c = 1.7813 J; above it M(u) is smooth.

The comparison. A random z-regular graph of N spins has O(1) cycles shorter than log N
(O((z−1)^k/(2k)) of length k), so (2) holds up to O(1/N). The sampling error of M = (1/N)Σ s_i
is the binomial sd 2·sqrt(p(1 − p)/N) (p = (1 + M)/2) times the square root of the
correlation volume χ = 1 + Σ_{j≠i} corr(s_i, s_j). χ was measured here from 20 graphs of
N = 10⁵ per case (z = 3, R = 2; z = 4, R = 1.5 and 2.5) and from 24 chains of 10⁶ (R = 0.7,
1.5): sd/binomial sd <= 5.3 on the graphs away from the jump (largest at the steepest part of
the smooth branches) and <= 4.3 on the chains (5.9 from a noisier 8-chain sample), so the
tolerance is ``SIGMAS`` × ``CORRELATION_FACTOR`` × binomial sd + ``LOOPS``/N at each input.
Within 0.15 of the jump the correlation volume diverges (saddle-node) and those inputs are
left to the jump's own check.
"""

from __future__ import annotations

from math import comb

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ndtr

from hysteresis.rfim import RandomFieldIsing

#: bound on sd(M)/binomial sd measured over 20 realizations per case (max seen 5.3)
CORRELATION_FACTOR = 6.0
#: Gaussian sigmas per input (≈ 150 inputs compared in all: 4.5σ leaves < 1e-3 false alarms)
SIGMAS = 4.5
#: O(1/N) loop corrections, in spins (O(1) short cycles, each moving a few spins)
LOOPS = 10.0
#: the saddle-node of z = 4 at R = 1.5 (critical disorder 1.7813): inputs closer than this to
#: the jump are not compared point by point (the correlation volume diverges there)
JUMP_EXCLUSION = 0.15
_GRID = np.linspace(0.0, 1.0, 4001)


def flip_probabilities(u: float, z: int, disorder: float, j: float = 1.0) -> np.ndarray:
    """p_n(u) = Φ((u + J(2n − z))/R), n = 0 … z."""
    n = np.arange(z + 1)
    return ndtr((u + j * (2 * n - z)) / disorder)


def _g(x, p: np.ndarray, z: int):
    """F(x) − x of the self-consistency (1)."""
    n = np.arange(z)
    c = np.array([comb(z - 1, k) for k in n], dtype=float)
    xs = np.asarray(x, dtype=float)[..., None]
    return (c * xs**n * (1.0 - xs) ** (z - 1 - n)) @ p[:z] - xs[..., 0]


def cavity_probability(u: float, z: int, disorder: float) -> float:
    """P*(u): the smallest root of (1) in [0, 1] (first sign change of F − x on a grid of 4001
    points, refined by Brent's method; a tangency inside one cell of 2.5e-4 could be missed,
    which moves a jump by O(1e-8) in u)."""
    p = flip_probabilities(u, z, disorder)
    g = _g(_GRID, p, z)
    if g[0] <= 0.0:
        return 0.0
    k = int(np.argmax(g <= 0.0))
    return float(brentq(lambda x: float(_g(x, p, z)), _GRID[k - 1], _GRID[k], xtol=1e-15))


def bethe_magnetisation(u: float, z: int, disorder: float) -> float:
    """M(u) of (2) on the ascending branch of the Bethe lattice (J = 1)."""
    p = flip_probabilities(u, z, disorder)
    ps = cavity_probability(u, z, disorder)
    n = np.arange(z + 1)
    weights = np.array([comb(z, k) for k in n]) * ps**n * (1.0 - ps) ** (z - n)
    return float(2.0 * weights @ p - 1.0)


def bethe_jump(z: int, disorder: float, lo: float, hi: float) -> tuple[float, float, float]:
    """(u*, M just below, M just above) of the ascending branch's jump in [lo, hi]: the largest
    step of P* on a grid of 0.005, refined by bisection on which branch P* is on."""
    us = np.arange(lo, hi, 0.005)
    roots = np.array([cavity_probability(u, z, disorder) for u in us])
    k = int(np.argmax(np.diff(roots)))
    lo, hi = float(us[k]), float(us[k + 1])
    middle = 0.5 * (roots[k] + roots[k + 1])
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if cavity_probability(mid, z, disorder) < middle:
            lo = mid
        else:
            hi = mid
    return lo, bethe_magnetisation(lo, z, disorder), bethe_magnetisation(hi, z, disorder)


def random_regular_edges(n: int, z: int, rng: np.random.Generator) -> np.ndarray:
    """A random z-regular simple graph: the configuration model (the n·z stubs paired at
    random), then every self-loop or repeated pair is removed by a double-edge swap with a
    random edge, (a, b), (c, d) → (a, d), (c, b), until none is left (O(1) swaps: the pairing
    has O(1) self-loops and multi-edges); the swaps keep every degree z."""
    stubs = rng.permutation(np.repeat(np.arange(n, dtype=np.int64), z)).reshape(-1, 2)
    while True:
        lo, hi = stubs.min(axis=1), stubs.max(axis=1)
        key = lo * n + hi
        order = np.argsort(key, kind="stable")
        repeated = np.zeros(key.size, dtype=bool)
        repeated[order[1:]] = key[order[1:]] == key[order[:-1]]
        bad = np.flatnonzero(repeated | (lo == hi))
        if bad.size == 0:
            return stubs
        partners = rng.integers(0, stubs.shape[0], bad.size)
        ends = stubs[bad, 1].copy()
        stubs[bad, 1] = stubs[partners, 1]
        stubs[partners, 1] = ends


def tolerance(m: np.ndarray, n: int) -> np.ndarray:
    """SIGMAS × CORRELATION_FACTOR × binomial sd of M, plus LOOPS/N (module docstring)."""
    return SIGMAS * CORRELATION_FACTOR * np.sqrt((1.0 - m**2) / n) + LOOPS / n


def test_bethe_solution_z2_fixed_points():
    """The formula's own checks: z = 2 has the closed form P* = p0/(1 − p1 + p0); M is −1 and 1
    far out; z = 3 is smooth even at small disorder (unique root), z = 4 jumps below R_c."""
    for u in (-2.0, -0.3, 0.4, 1.7):
        p = flip_probabilities(u, 2, 0.8)
        assert abs(cavity_probability(u, 2, 0.8) - p[0] / (1 - p[1] + p[0])) < 1e-12
    assert bethe_magnetisation(-20.0, 4, 1.5) == -1.0
    assert abs(bethe_magnetisation(20.0, 4, 1.5) - 1.0) < 1e-12
    us = np.arange(0.5, 1.5, 0.002)
    m3 = np.array([bethe_magnetisation(u, 3, 1.0) for u in us])
    assert np.diff(m3).max() < 0.05  # steep (dM/du ≈ 12) but continuous
    u_star, below, above = bethe_jump(4, 1.5, 0.5, 1.5)
    assert above - below > 1.0


def test_periodic_chain_against_shukla():
    """z = 2: the periodic chain of 10⁶ spins at R = 0.7 and 1.5, 41 inputs on the ascending
    branch (a ring's only loop is the whole ring)."""
    n = 10**6
    us = np.linspace(-2.5, 3.5, 41)
    for disorder, seed in ((0.7, 1), (1.5, 2)):
        model = RandomFieldIsing.lattice((n,), disorder, seed=seed)
        m, _ = model.apply(us, model.initial_state(-20.0))
        theory = np.array([bethe_magnetisation(u, 2, disorder) for u in us])
        assert np.all(np.abs(m - theory) <= tolerance(theory, n))


def test_random_regular_graphs_against_bethe():
    """z = 3 (R = 2) and z = 4 (R = 2.5, above R_c; R = 1.5, below: a jump), N = 2·10⁵ each,
    46 inputs from −1.5 to 3 (those within JUMP_EXCLUSION of the jump left out). The jump at
    R = 1.5 is one avalanche: the only one above 0.1 N, triggered within 0.06 of u* (the
    spread of the finite-N jump over 6 graphs of 10⁵ was sd 0.014; 10⁶: sd 0.003) with
    2s/N within 0.1 of the exact jump (measured spread 0.07 at 10⁵); z = 3 at the same R has no
    avalanche above 1 % of N."""
    n = 200_000
    us = np.linspace(-1.5, 3.0, 46)
    u_star, below, above = bethe_jump(4, 1.5, 0.5, 1.5)
    for z, disorder, seed in ((3, 2.0, 11), (4, 2.5, 12), (4, 1.5, 13), (3, 1.5, 14)):
        rng = np.random.default_rng(seed)
        model = RandomFieldIsing(rng.normal(0.0, disorder, n), random_regular_edges(n, z, rng), 1.0)
        assert np.all(np.bincount(model.edges().ravel(), minlength=n) == z)
        start = model.initial_state(-20.0)
        m, _ = model.apply(us, start)
        theory = np.array([bethe_magnetisation(u, z, disorder) for u in us])
        keep = np.abs(us - u_star) > JUMP_EXCLUSION if (z, disorder) == (4, 1.5) else slice(None)
        assert np.all(np.abs(m - theory)[keep] <= tolerance(theory, n)[keep])
        if disorder == 1.5:
            triggers, sizes, _ = model.avalanches([20.0], start)
            large = np.flatnonzero(sizes > 0.01 * n)
            if z == 3:
                assert large.size == 0
            else:
                assert np.count_nonzero(sizes > 0.1 * n) == 1
                k = int(np.argmax(sizes))
                assert abs(triggers[k] - u_star) <= 0.06
                assert abs(2 * sizes[k] / n - (above - below)) <= 0.1


@pytest.mark.slow
def test_bethe_jump_location_converges():
    """z = 4, R = 1.5, N = 10⁶, three graphs: the jump's trigger within 0.015 of u* (5× the sd
    0.003 of 3 graphs of 10⁶ measured before; sd 0.014 at 10⁵, 0.035 at 10⁴: the finite-N jump
    converges on the saddle-node of (1)) and 2s/N within 0.05 of the exact jump."""
    n = 10**6
    u_star, below, above = bethe_jump(4, 1.5, 0.5, 1.5)
    for seed in (21, 22, 23):
        rng = np.random.default_rng(seed)
        model = RandomFieldIsing(rng.normal(0.0, 1.5, n), random_regular_edges(n, 4, rng), 1.0)
        triggers, sizes, _ = model.avalanches([20.0], model.initial_state(-20.0))
        k = int(np.argmax(sizes))
        assert abs(triggers[k] - u_star) <= 0.015
        assert abs(2 * sizes[k] / n - (above - below)) <= 0.05
