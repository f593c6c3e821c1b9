"""Kaplan–Yorke and box-counting dimensions against closed forms and known sets."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.dimensions import box_counting_dimension, box_counts, kaplan_yorke_dimension

# ------------------------------------------------------------------------------------------
# Kaplan–Yorke
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("exponents", "expected"),
    [
        # Hénon map (a=1.4, b=0.3): λ = 0.41922, -1.62319 -> D_KY = 1.2583 (literature value)
        ([0.41922, -1.62319], 1.0 + 0.41922 / 1.62319),
        # Lorenz (σ=10, ρ=28, β=8/3): λ = 0.9056, 0, -14.5723 -> D_KY = 2.0621
        ([0.9056, 0.0, -14.5723], 2.0 + 0.9056 / 14.5723),
        # a limit cycle of the forced oscillator with the phase direction kept: (0, -ζ, -ζ) -> 1
        ([0.0, -0.05, -0.05], 1.0),
        # hand example: j = 2, partial sum 0.3 - 0.1 = 0.2, next |λ3| = 0.4
        ([0.3, -0.1, -0.4, -2.0], 2.0 + 0.2 / 0.4),
    ],
)
def test_kaplan_yorke_known_spectra(exponents, expected):
    assert kaplan_yorke_dimension(exponents) == pytest.approx(expected, rel=1e-12)


def test_kaplan_yorke_unsorted_input_is_sorted():
    assert kaplan_yorke_dimension([-1.62319, 0.41922]) == pytest.approx(1.0 + 0.41922 / 1.62319)


def test_kaplan_yorke_minus_infinity():
    # the play limit (phase neglected): (λ2, λ3, -inf); λ2 + λ3 < 0 -> interpolation with λ3
    assert kaplan_yorke_dimension([0.1, -0.2, -np.inf]) == pytest.approx(1.5)
    # if the finite partial sums stay >= 0 the next exponent is -inf: D_KY = j exactly
    assert kaplan_yorke_dimension([0.3, -0.1, -np.inf]) == 2.0
    # only -inf after a zero sum: j = 1, contribution 0 / inf = 0
    assert kaplan_yorke_dimension([0.0, -np.inf]) == 1.0


def test_kaplan_yorke_all_negative_is_zero():
    # regular motion in the Poincaré section: (-ζ, -ζ)
    assert kaplan_yorke_dimension([-0.05, -0.05]) == 0.0
    assert kaplan_yorke_dimension([-1e-9]) == 0.0
    assert kaplan_yorke_dimension([-0.1, -np.inf]) == 0.0


def test_kaplan_yorke_all_nonnegative_is_full_dimension():
    assert kaplan_yorke_dimension([0.2, 0.1, 0.0]) == 3.0


@pytest.mark.parametrize("bad", [[], [[0.1, -0.2]], [np.nan, -1.0], [np.inf, -1.0]])
def test_kaplan_yorke_rejects_bad_input(bad):
    with pytest.raises(ValueError):
        kaplan_yorke_dimension(bad)


# ------------------------------------------------------------------------------------------
# Box counting
# ------------------------------------------------------------------------------------------

N_POINTS = 200_000


def _cantor_times_interval(n: int, rng: np.random.Generator, depth: int = 16) -> np.ndarray:
    """Uniform measure on C × [0, 1], C the middle-thirds Cantor set (ternary digits 0 or 2)."""
    digits = 2 * rng.integers(0, 2, size=(n, depth))
    x = (digits * 3.0 ** -np.arange(1, depth + 1)).sum(axis=1)
    return np.column_stack([x, rng.uniform(0.0, 1.0, n)])


def test_box_counts_by_hand():
    # 11 points 0, 0.1, ..., 1 on a line, anchored grid of side 0.25:
    # floor(x / 0.25) = 0,0,0,1,1,2,2,2,3,3,4 -> 5 occupied boxes; side 2: one box
    x = np.linspace(0.0, 1.0, 11)
    pts = np.column_stack([x, np.zeros_like(x)])
    assert box_counts(pts, [0.25, 2.0]).tolist() == [5.0, 1.0]
    # the minimum over shifted grids can only be lower or equal to the anchored grid
    assert box_counts(pts, [0.25], offsets=8, reduce="min")[0] <= 5.0


def test_box_counting_line_segment_is_one():
    rng = np.random.default_rng(11)
    t = rng.uniform(0.0, 1.0, N_POINTS)
    pts = np.column_stack([0.6 * t + 0.2, 0.8 * t - 0.3])  # tilted segment of length 1
    res = box_counting_dimension(pts, seed=1)
    assert abs(res.dimension - 1.0) < 0.03
    assert res.region[1] - res.region[0] >= 5
    assert res.stderr < 0.03


def test_box_counting_filled_square_is_two():
    rng = np.random.default_rng(12)
    pts = rng.uniform(-1.0, 1.0, (N_POINTS, 2))
    res = box_counting_dimension(pts, seed=2)
    assert abs(res.dimension - 2.0) < 0.03


def test_box_counting_cantor_times_interval():
    rng = np.random.default_rng(13)
    pts = _cantor_times_interval(N_POINTS, rng)
    res = box_counting_dimension(pts, seed=3)
    assert abs(res.dimension - (1.0 + math.log(2.0) / math.log(3.0))) < 0.03


def test_box_counting_result_is_consistent():
    rng = np.random.default_rng(14)
    pts = rng.uniform(0.0, 1.0, (20_000, 2))
    res = box_counting_dimension(pts, seed=0)
    assert np.all(np.diff(res.sizes) < 0)
    assert np.all(np.diff(res.counts) >= 0)  # finer boxes never cover with fewer boxes
    i, j = res.region
    x = np.log(1.0 / res.sizes[i:j])
    slope, intercept = np.polyfit(x, np.log(res.counts[i:j]), 1)
    assert res.dimension == pytest.approx(slope, rel=1e-9)
    assert res.intercept == pytest.approx(intercept, rel=1e-9, abs=1e-9)
    assert res.local_slopes.shape == (res.sizes.size - 1,)
    assert res.n_points == 20_000


def test_box_counting_rejects_bad_input():
    with pytest.raises(ValueError):
        box_counting_dimension(np.zeros((1, 2)))
    with pytest.raises(ValueError):
        box_counting_dimension(np.ones((100, 2)))  # all points coincide
    with pytest.raises(ValueError):
        box_counting_dimension(np.random.default_rng(0).uniform(size=(100, 2)), max_fill=0.0)
    with pytest.raises(ValueError):
        box_counts(np.random.default_rng(0).uniform(size=(100, 2)), [0.1, -1.0])


def test_occupied_cells_count_as_numpy_unique():
    """The box count's distinct-cell counter (sort and compare) against np.unique over rows,
    on random cells with many repeats, in 1-3 dimensions and a grid too large to pack."""
    from analysis.dynamics.dimensions import _occupied

    rng = np.random.default_rng(11)
    for d in (1, 2, 3):
        for n in (1, 2, 50, 3000):
            cells = rng.integers(0, 40, size=(n, d))
            assert _occupied(cells) == np.unique(cells, axis=0).shape[0]
    wide = rng.integers(0, 2**40, size=(200, 2))  # span**2 > 2**62: the unpacked path
    wide[100:] = wide[:100]
    assert _occupied(wide) == 100


@pytest.mark.parametrize("scale", [1e200, 1e-200, 2.0**-900])
def test_box_counting_is_scale_invariant(scale):
    # the dimension of a scaled set is the same: the boxes are laid in units of the extent, so
    # a curve times 1e±200 (whose squared distances overflow / underflow) gets the same fit
    t = np.linspace(0.0, 2.0 * np.pi, 20000)
    curve = np.c_[np.cos(t) + 0.3 * np.cos(7.0 * t), np.sin(3.0 * t)]
    ref = box_counting_dimension(curve, seed=0)
    got = box_counting_dimension(curve * scale, seed=0)
    assert np.array_equal(got.counts, ref.counts) and got.region == ref.region
    # the same counts against log(1/ε) shifted by −log(scale), rounded to ~ε·|log scale|
    # (5e-14 at 1e±200) over a region spanning ~1 in log(1/ε): the slope to 1e-12
    assert got.dimension == pytest.approx(ref.dimension, rel=1e-12)
    assert np.allclose(got.sizes / scale, ref.sizes, rtol=1e-12)
    explicit_ref = box_counting_dimension(curve, sizes=ref.sizes, seed=0)
    explicit = box_counting_dimension(curve * scale, sizes=ref.sizes * scale, seed=0)
    assert np.array_equal(explicit.counts, explicit_ref.counts)
    assert explicit.dimension == pytest.approx(explicit_ref.dimension, rel=1e-12)
