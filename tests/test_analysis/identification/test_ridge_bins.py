"""The identified masses along the ridge β = α − p, cell by cell: the erf play's against the
Gaussian probabilities (closed form, math.erf), a dimer ensemble's against the histogram of its
own thresholds (brute-force count)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from analysis.identification import compare_ridge_bins, identify_preisach
from hysteresis.play import GeneralizedPlay
from hysteresis.spin_dimers import SpinDimerEnsemble

P, R = 2.0, 1.0
SAT = 5 * R + P / 2

#: round-off of a cell mass: a mixed difference of four Everett values of size <= 1, each
#: carrying an ulp, plus three roundings of the differences (the report allows 1e-9)
CELL_ROUND_OFF = 8 * np.finfo(float).eps


def _phi(x: float) -> float:
    return 0.5 * (1.0 + math.erf(x / math.sqrt(2.0)))


@pytest.mark.parametrize("k", [20, 4])
def test_erf_play_bins_are_the_gaussian_probabilities(k):
    step = P / k
    ident = identify_preisach(GeneralizedPlay.erf(P, R), step, SAT)
    bins = compare_ridge_bins(ident, P, R)
    n = ident.cell_mass.shape[0]
    assert bins.bins == n - k
    # cell alpha in (a_{i-1}, a_i] holds the loops with s in (a_{i-1} - p/2, a_i - p/2]
    a = ident.alpha[k:]
    expected = [_phi((a[i + 1] - P / 2) / R) - _phi((a[i] - P / 2) / R) for i in range(n - k)]
    np.testing.assert_allclose(bins.expected, expected, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(bins.alpha, a[1:])
    assert bins.max_error < CELL_ROUND_OFF
    # the off-ridge mass sums the round-off of every cell
    assert abs(bins.off_ridge_mass) < ident.cell_mass.size * CELL_ROUND_OFF
    # a ridge centred elsewhere is told apart: the bins then differ by ~ the shift's effect
    assert compare_ridge_bins(ident, P, R, centre=0.5).max_error > 1e-2


def test_dimer_bins_are_the_histogram_of_their_thresholds():
    n_spins = 2000
    ens = SpinDimerEnsemble.random(n_spins, P, R, 2.0, seed=3)
    th = ens.thresholds()
    step = 0.25
    saturation = max(SAT, float(np.max(np.abs([th.alpha, th.beta]))) + step)
    ident = identify_preisach(ens, step, saturation)
    bins = compare_ridge_bins(ident, P, R)
    k = round(P / step)
    # the 1-based cell of each loop's alpha (grid[i-1] < alpha <= grid[i]); ridge cell i - 1 - k
    cell = np.searchsorted(ident.alpha, th.alpha, side="left")
    counts = np.bincount(cell - 1 - k, minlength=bins.bins)
    np.testing.assert_allclose(bins.masses * (n_spins / 2), counts, rtol=0, atol=1e-8)
    assert abs(bins.off_ridge_mass) < 1e-10  # every loop has width p: all mass on the ridge
    # a finite sample of n centres: a bin's mass differs from its probability by the binomial
    # sampling error sqrt(p(1-p)/n) <= 0.5/sqrt(n); the largest of ~50 bins within 4 of those
    assert bins.max_error < 4 * 0.5 / math.sqrt(n_spins / 2)


def test_bad_arguments():
    ident = identify_preisach(GeneralizedPlay.erf(P, R), 0.5, SAT)
    with pytest.raises(ValueError, match="width must be an integer multiple"):
        compare_ridge_bins(ident, 2.2, R)
    with pytest.raises(ValueError, match="width must be below the grid's span"):
        compare_ridge_bins(ident, 20.0, R)
    with pytest.raises(ValueError, match="spread must be > 0"):
        compare_ridge_bins(ident, P, 0.0)
    with pytest.raises(ValueError, match="regular grid"):
        compare_ridge_bins(dataclasses.replace(ident, step=None), P, R)
