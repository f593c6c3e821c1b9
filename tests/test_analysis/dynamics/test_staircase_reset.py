"""Reset directions of continuous Preisach orbits: the own extrema replaced inside the orbit.

Truth: the characteristic polynomial of the closed-loop Jacobian itself, from its principal
minors (no eigen-solver): with ``r`` structural zero multipliers the sums ``E_j`` of its
principal ``j × j`` minors vanish for ``j > n − r``, and the other multipliers are the roots of
the remaining factor.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import ContinuousPreisachModel
from oscillators import ForcedOscillator

# the tangent flow (fixed-step RK8, local error ~1e-16 per step) over a few forcing periods
# carries a relative error far below this bound on the Jacobian's entries
ENTRY_ERROR = 1e-10


def _principal_minor_sums(a: np.ndarray) -> np.ndarray:
    """E_j = Σ of the principal j × j minors (det(λI − A) = Σ_j (−1)^j E_j λ^(n−j))."""
    n = a.shape[0]
    return np.array(
        [1.0]
        + [
            sum(np.linalg.det(a[np.ix_(idx, idx)]) for idx in itertools.combinations(range(n), j))
            for j in range(1, n + 1)
        ]
    )


@pytest.mark.parametrize("coupling, period", [(1.0, 1), (1.5, 1), (2.0, 3)])
def test_reset_multipliers_are_exact_zeros_of_the_characteristic_polynomial(coupling, period):
    # Gaussian width disorder p = 2, R = 1, σ_r = 0.1: period-1 orbits with one own extremum
    # (C = 1) and two (C = 1.5, where the computed zero pair splits like a Jordan block,
    # 3.5e-10 and 1.2e-14, if left to the eigen-solver), and the period-3 border orbit at C = 2
    system = ForcedOscillator(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.1), coupling)
    orbit = find_periodic_orbit(system, transient=200, max_period=8)
    assert orbit.period == period
    tags = np.array(orbit.multiplier_labels)
    reset = tags == "reset"
    n_frozen = len(orbit.frozen)
    own = len(orbit.tangent_space) - 2 - n_frozen
    assert own >= 1 and reset.sum() == own  # every own extremum is replaced inside the orbit
    assert np.all(orbit.multipliers[reset] == 0.0) and np.all(orbit.exponents[reset] == -math.inf)
    d = orbit.to_dict()
    assert [e for e, t in zip(d["exponents"], tags, strict=True) if t == "reset"] == ["-inf"] * own
    # the truth: the free block (q, v, own extrema) of D P̃ at the orbit
    jac = orbit.monodromy
    free = [0, 1, *range(2 + n_frozen, jac.shape[0])]
    a = jac[np.ix_(free, free)]
    n = a.shape[0]
    e = _principal_minor_sums(a)
    scale = max(1.0, float(np.max(np.abs(a))))
    for j in range(3, n + 1):
        # a perturbation of relative size ENTRY_ERROR moves E_j by at most C(n, j)·j·n^(j−1)
        # times it (Jacobi's formula over the minors' entries)
        bound = math.comb(n, j) * j * n ** (j - 1) * ENTRY_ERROR * scale**j
        assert abs(e[j]) <= bound, (j, e[j], bound)
    # the other multipliers: the roots of λ² − E_1 λ + E_2
    roots = np.roots([1.0, -e[1], e[2]])
    others = orbit.multipliers[(~reset) & ~np.char.startswith(tags, "frozen")]
    assert others.size == 2
    assert np.allclose(np.sort_complex(roots), np.sort_complex(others), rtol=0, atol=1e-8)
