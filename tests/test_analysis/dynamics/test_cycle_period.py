"""``cycle_period``: the smallest k with every pair ``(x_i, x_{i+k})`` within the tolerance.

Truth: the definition, checked pair by pair in plain Python over every k; sections with a
planted period (exact, and with perturbations at, just below and just above the tolerance),
aperiodic ones, and short ones (fewer points than ``max_period + 1``).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.attractors import cycle_period


def _definition(points, tolerance, max_period):
    n = len(points)
    for k in range(1, min(max_period, n - 1) + 1):
        pairs = range(n - k)
        if all(
            all(abs(a - b) <= tolerance for a, b in zip(points[i + k], points[i], strict=True))
            for i in pairs
        ):
            return k
    return 0


@pytest.mark.parametrize("seed", range(6))
def test_cycle_period_is_the_definition(seed):
    rng = np.random.default_rng(seed)
    tol = 1e-6
    for _ in range(300):
        n = int(rng.integers(1, 60))
        d = int(rng.integers(1, 5))
        kind = rng.integers(0, 3)
        if kind == 0:  # aperiodic
            pts = rng.normal(size=(n, d))
        else:  # planted period, perturbed at about the tolerance
            k = int(rng.integers(1, 12))
            cycle = rng.normal(size=(k, d))
            pts = cycle[np.arange(n) % k] + rng.choice([0.0, 0.4, 0.9, 1.1]) * tol * rng.uniform(
                -1, 1, size=(n, d)
            )
            if kind == 2 and n > 2:  # a transient: the first points off the cycle
                pts[: int(rng.integers(1, n))] += rng.normal(size=d)
        max_period = int(rng.integers(1, 40))
        assert cycle_period(pts, tol, max_period) == _definition(pts.tolist(), tol, max_period)
