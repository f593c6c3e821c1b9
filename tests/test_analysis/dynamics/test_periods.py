"""The one period test of a section (:mod:`analysis.dynamics.periods`).

Truth: sections whose period is constructed (a cycle repeated, with noise of a known size below
or above the tolerance, a transient of known decay, a chaotic map), and the definition checked
pair by pair in plain Python. The three users (``orbit_period``/``section_period`` of the
bifurcation diagrams, the basins' ``cycle_period``, the periodic-orbit search) are checked to be
this one function with their own choices.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.attractors import cycle_period
from analysis.dynamics.bifurcation import orbit_period, section_period
from analysis.dynamics.periods import (
    return_distances,
    section_extent,
    smallest_period,
    transient_length,
)

TOL = 1e-6


def _definition(points, tol, max_period, divisors_of=None):
    """The smallest k whose every pair (x_i, x_{i+k}) agrees within tol, in plain Python."""
    n = len(points)
    for k in range(1, min(max_period, n - 1) + 1):
        if divisors_of is not None and divisors_of % k:
            continue
        if all(
            all(abs(a - b) <= tol for a, b in zip(points[i + k], points[i], strict=True))
            for i in range(n - k)
        ):
            return k
    return 0


def _cycle(k: int, d: int, n: int, seed: int = 0) -> np.ndarray:
    """n points of a period-k cycle in d coordinates whose points are >= 0.1 apart."""
    rng = np.random.default_rng(seed)
    base = np.arange(k)[:, None] * 0.37 + rng.uniform(0, 0.05, size=(k, d))
    return base[np.arange(n) % k]


@pytest.mark.parametrize("k", [1, 2, 3, 7])
def test_a_constructed_period_is_found_with_noise_below_the_tolerance(k):
    pts = _cycle(k, 3, 12 * k + 5)
    noise = np.random.default_rng(k).uniform(-0.45 * TOL, 0.45 * TOL, size=pts.shape)
    # pair differences are at most 0.9·TOL: the period holds
    assert smallest_period(pts + noise, TOL) == k


@pytest.mark.parametrize("k", [1, 2, 3, 5])
def test_noise_above_the_tolerance_breaks_the_period_but_not_its_double(k):
    """Every other round of the cycle is offset by 0.6·TOL (or 0.4·TOL): pairs k apart differ by
    1.2·TOL (0.8·TOL), pairs 2k apart not at all, so the smallest period is 2k (k)."""
    n = 10 * k + 3
    pts = _cycle(k, 2, n)
    sign = (-1.0) ** (np.arange(n) // k)
    assert smallest_period(pts + 0.6 * TOL * sign[:, None], TOL) == 2 * k
    assert smallest_period(pts + 0.4 * TOL * sign[:, None], TOL) == k
    # with the double beyond max_period there is none
    assert smallest_period(pts + 0.6 * TOL * sign[:, None], TOL, max_period=2 * k - 1) == 0


def test_a_chaotic_section_has_no_period():
    x = np.empty(400)
    x[0] = 0.1234
    for i in range(1, x.size):  # the logistic map at r = 4 (chaotic, no attracting cycle)
        x[i] = 4.0 * x[i - 1] * (1.0 - x[i - 1])
    assert smallest_period(x, TOL) == 0
    assert smallest_period(np.column_stack([x[:-1], x[1:]]), 1e-3) == 0
    assert smallest_period(x, 1e-3, relative_to="extent") == 0


def test_the_window_need_not_be_a_multiple_of_the_period_and_the_smallest_wins():
    k = 4
    for n in (3 * k, 3 * k + 1, 3 * k + 3):
        assert smallest_period(_cycle(k, 2, n), TOL) == k
    # a period-2 sequence also repeats after 4, 6, ...: the smallest is reported
    assert smallest_period(_cycle(2, 1, 40), TOL, max_period=20) == 2
    # seen once (k + 1 points): not found with the default max_period n // 2, found if allowed
    once = _cycle(k, 2, k + 1)
    assert smallest_period(once, TOL) == 0
    assert smallest_period(once, TOL, max_period=k) == k
    # max_period below the period
    assert smallest_period(_cycle(5, 2, 50), TOL, max_period=4) == 0
    # too few points for any pair
    assert smallest_period(np.zeros((1, 2)), TOL) == 0
    assert smallest_period(np.zeros((0, 2)), TOL) == 0


def test_divisors_of_the_orbit_length_only():
    """Six orbit points a b c d a b: lag 4 fits the window (two pairs) but a closed orbit of six
    points repeats only after a divisor of 6."""
    a, b, c, d = ([float(i), 2.0 * i] for i in range(4))
    pts = np.array([a, b, c, d, a, b])
    assert smallest_period(pts, TOL, max_period=5) == 4
    assert smallest_period(pts, TOL, max_period=5, divisors_of=6) == 0
    # a period-3 orbit covered twice is found at 3 = 6 / 2
    assert smallest_period(_cycle(3, 2, 6), TOL, divisors_of=6) == 3


def test_relative_tolerances_scale_with_the_section():
    k, scale = 3, 1e4
    pts = scale * _cycle(k, 2, 30)
    noisy = pts + np.random.default_rng(1).uniform(-1e-4, 1e-4, size=pts.shape)
    extent = section_extent(noisy)
    assert extent == pytest.approx(np.ptp(pts, axis=0).max(), abs=2e-4)
    assert smallest_period(noisy, TOL) == 0  # 2e-4 > 1e-6 absolute
    assert smallest_period(noisy, 1e-7, relative_to="extent") == k  # tol = 1e-7·extent ≈ 7e-4
    assert smallest_period(noisy, 1e-9, relative_to="extent") == 0  # ≈ 7e-6
    # a section far from 0 with a small extent: "magnitude" scales with max|x|, "extent" not
    far = 1e6 + _cycle(k, 2, 30) * 1e-3 + np.random.default_rng(2).uniform(-1e-5, 1e-5, (30, 2))
    assert section_extent(far) == 1.0  # extent below 1: the scale is 1
    # the cycle's points are 3.7e-4 apart, the noise at most 2e-5
    assert smallest_period(far, 1e-10, relative_to="magnitude") == k  # tol ≈ 1e-4
    assert smallest_period(far, 1e-10, relative_to="extent") == 0  # tol = 1e-10


def test_nan_points_never_agree():
    pts = _cycle(2, 2, 20)
    pts[7, 1] = np.nan
    assert smallest_period(pts, TOL) == 0
    assert smallest_period(pts[8:], TOL) == 2  # the NaN point left out
    assert smallest_period(pts, TOL, relative_to="magnitude") == 0  # NaN magnitude: scale 1


@pytest.mark.parametrize("seed", range(4))
def test_smallest_period_is_the_definition(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        n = int(rng.integers(1, 50))
        d = int(rng.integers(1, 4))
        if rng.integers(0, 3) == 0:
            pts = rng.normal(size=(n, d))
        else:
            k = int(rng.integers(1, 10))
            pts = rng.normal(size=(k, d))[np.arange(n) % k]
            pts += rng.choice([0.0, 0.4, 0.9, 1.1]) * TOL * rng.uniform(-1, 1, size=(n, d))
        max_period = int(rng.integers(0, 30))
        divisors_of = None if rng.integers(0, 2) else int(rng.integers(1, 13))
        want = _definition(pts.tolist(), TOL, max_period, divisors_of)
        assert smallest_period(pts, TOL, max_period, divisors_of=divisors_of) == want
        rel = TOL / 3.0
        extent = max(*np.ptp(pts, axis=0).tolist(), 1.0) if n else 1.0
        want = _definition(pts.tolist(), rel * extent, max_period)
        assert smallest_period(pts, rel, max_period, relative_to="extent") == want


def test_the_callers_are_this_function():
    """orbit_period (absolute, default max_period n // 2), section_period (relative to the
    extent), cycle_period (absolute, explicit max_period) against the definition."""
    rng = np.random.default_rng(5)
    for _ in range(100):
        n = int(rng.integers(2, 40))
        k = int(rng.integers(1, 8))
        pts = rng.normal(size=(k, 2))[np.arange(n) % k] * rng.choice([1e-3, 1.0, 1e3])
        pts += rng.choice([0.0, 0.9, 1.1]) * 1e-7 * rng.uniform(-1, 1, size=pts.shape)
        q, v = pts[:, 0], pts[:, 1]
        assert orbit_period(q, v, TOL) == _definition(pts.tolist(), TOL, n // 2)
        assert orbit_period(q, None, TOL, 5) == _definition(q[:, None].tolist(), TOL, 5)
        scale = max(float(np.ptp(q)), float(np.ptp(v)), 1.0)
        assert section_period(q, v) == _definition(pts.tolist(), 1e-7 * scale, n // 2)
        assert cycle_period(pts, TOL, 6) == _definition(pts.tolist(), TOL, 6)


def test_return_distances_and_the_closest_return():
    """A period-3 cycle approached geometrically: the distance at lag 3 is the first pair's,
    ``A·(1 − r³)``, the smallest of all lags (the others carry the cycle's own spacing)."""
    a, r, n = 1e-2, 0.8, 40
    pts = _cycle(3, 2, n) + a * r ** np.arange(n)[:, None]
    dist = return_distances(pts, 6)
    assert dist[2] == pytest.approx(a * (1.0 - r**3), rel=1e-9)
    assert dist[5] == pytest.approx(a * (1.0 - r**6), rel=1e-9)
    assert int(np.argmin(dist)) + 1 == 3
    want = [
        max(abs(x - y) for i in range(n - k) for x, y in zip(pts[i + k], pts[i], strict=True))
        for k in range(1, 7)
    ]
    np.testing.assert_array_equal(dist, want)
    assert smallest_period(pts, TOL) == 0  # still decaying above the tolerance at the start


@pytest.mark.parametrize("k", [1, 2, 5])
def test_transient_length_of_a_geometric_approach(k):
    """x_i = cycle + A·r^i: pairs k apart differ by A·r^i·(1 − r^k), decreasing, so the
    transient ends at the first i with A·r^i·(1 − r^k) <= tol (closed form)."""
    a, r, n, tol = 1.0, 0.7, 120, 1e-6
    pts = _cycle(k, 2, n) + a * r ** np.arange(n)[:, None]
    want = math.ceil(math.log(tol / (a * (1.0 - r**k))) / math.log(r))
    # the closed form is not at a rounding boundary
    assert abs(math.log(tol / (a * (1.0 - r**k))) / math.log(r) - want) > 1e-3
    assert transient_length(pts, k, tol) == want
    assert transient_length(_cycle(k, 2, n), k, tol) == 0


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: smallest_period(np.zeros(5), np.nan), "tolerance"),
        (lambda: smallest_period(np.zeros(5), -1.0), "tolerance"),
        (lambda: smallest_period(np.zeros(5), TOL, relative_to="size"), "relative_to"),
        (lambda: smallest_period(np.zeros((2, 2, 2)), TOL), "points"),
        (lambda: smallest_period(np.zeros(5), TOL, -1), "max_period"),
        (lambda: smallest_period(np.zeros(5), TOL, divisors_of=0), "divisors_of"),
        (lambda: return_distances(np.zeros(5), 5), "max_period"),
        (lambda: transient_length(np.zeros(5), 0, TOL), "period"),
    ],
)
def test_bad_input_names_the_parameter(call, match):
    with pytest.raises(ValueError, match=match):
        call()
