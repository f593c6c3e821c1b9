"""Ensemble statistics against closed forms and an independent regression; their error estimates
against closed forms and seeded Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from analysis.dynamics.statistics import (
    empirical_pdf,
    ks_sampling_scale,
    local_exponent,
    magnetization_variance,
    power_law_fit,
    self_averaging_parameter,
    standard_error_of_mean,
    std_ratio_relative_error,
    variance_slope_stderr,
    wilson_interval,
)


def test_sap_closed_forms():
    assert self_averaging_parameter([1.0, 3.0]) == pytest.approx((5.0 - 4.0) / 4.0)
    assert self_averaging_parameter([1.3] * 7) == pytest.approx(0.0, abs=1e-15)


def test_sap_of_regular_fraction():
    # paper fig:sap(b): K_0 of K realizations regular (D = 0), the rest at one value d.
    # SAP = (f d² − f² d²)/(f² d²) with f = (K − K_0)/K the chaotic fraction = K_0/(K − K_0).
    values = np.array([0.0] * 100 + [1.4] * 400)
    assert self_averaging_parameter(values) == pytest.approx(100 / 400)


def test_sap_scale_invariant_and_zero_mean_error():
    rng = np.random.default_rng(0)
    d = rng.uniform(1.0, 2.0, 1000)
    assert self_averaging_parameter(3.7 * d) == pytest.approx(self_averaging_parameter(d))
    assert self_averaging_parameter(d) == pytest.approx(np.var(d) / np.mean(d) ** 2)
    with pytest.raises(ValueError, match="mean 0"):
        self_averaging_parameter([-1.0, 1.0])
    with pytest.raises(ValueError):
        self_averaging_parameter([])


def test_magnetization_variance_closed_forms():
    assert magnetization_variance([-1.0, 1.0]) == pytest.approx(1.0)
    assert magnetization_variance([0.2, 0.2, 0.2]) == pytest.approx(0.0, abs=1e-15)
    # population variance (divide by K), as the paper's overlines
    assert magnetization_variance([0.0, 1.0, 2.0]) == pytest.approx(2.0 / 3.0)


def test_empirical_pdf_normalized_and_gaussian():
    rng = np.random.default_rng(1)
    x = rng.normal(0.0, 1.0, 200_000)
    # explicit edges: values outside are dropped and the density is conditional on the bins;
    # the normal density is nearly flat on ±0.1, so both halves are ≈ 1/0.2 = 5
    pdf = empirical_pdf(x, bins=np.linspace(-0.1, 0.1, 3))
    assert np.sum(pdf.density * pdf.widths) == pytest.approx(1.0)
    assert pdf.density == pytest.approx([5.0, 5.0], rel=0.03)
    full = empirical_pdf(x, bins=80)
    assert np.sum(full.density * full.widths) == pytest.approx(1.0)
    centre = np.argmin(np.abs(full.centers))
    assert full.density[centre] == pytest.approx(1.0 / np.sqrt(2.0 * np.pi), rel=0.05)


def test_power_law_exact():
    n = np.array([100.0, 300.0, 1000.0, 3000.0])
    fit = power_law_fit(n, 3.0 / n)
    assert fit.exponent == pytest.approx(-1.0, abs=1e-12)
    assert fit.prefactor == pytest.approx(3.0, rel=1e-10)
    assert fit.stderr == pytest.approx(0.0, abs=1e-10)
    assert fit(10.0) == pytest.approx(0.3)


def test_power_law_matches_scipy_linregress():
    rng = np.random.default_rng(2)
    x = np.geomspace(10, 1e4, 12)
    y = 2.0 * x**-0.5 * np.exp(rng.normal(0, 0.1, x.size))
    fit = power_law_fit(x, y)
    ref = stats.linregress(np.log(x), np.log(y))
    assert fit.exponent == pytest.approx(ref.slope, rel=1e-12)
    assert fit.stderr == pytest.approx(ref.stderr, rel=1e-10)


def test_power_law_rejects_nonpositive():
    with pytest.raises(ValueError):
        power_law_fit([1.0, 2.0, 3.0], [1.0, -1.0, 0.5])
    with pytest.raises(ValueError):
        power_law_fit([1.0, 1.0, 1.0], [1.0, 2.0, 3.0])


# ----------------------------------------------------------------------------------------------
# error estimates of the ensemble statistics
# ----------------------------------------------------------------------------------------------
#: relative tolerance of a Monte Carlo standard deviation from REPS seeded repetitions: 3 σ of the
#: sample std (relative error 1/sqrt(2(REPS − 1)) = 1.1 %) plus ~1 % for the first-order
#: (delta-method) error formulas at K = 100–200 realizations, whose next term is O(1/K)
REPS = 4000
MC_RTOL = 3 / math.sqrt(2 * (REPS - 1)) + 0.01


def test_wilson_interval_matches_the_textbook_value():
    lo, hi = wilson_interval(20, 100)  # textbook 95 % Wilson interval for 20/100: [0.1333, 0.2888]
    assert lo == pytest.approx(0.1333, abs=5e-4) and hi == pytest.approx(0.2888, abs=5e-4)
    lo, hi = wilson_interval(0, 100)  # upper bound z²/(n + z²) = 3.8416/103.8416
    assert lo == pytest.approx(0.0, abs=1e-12) and hi == pytest.approx(0.0370, abs=5e-4)
    assert all(math.isnan(x) for x in wilson_interval(0, 0))


def test_standard_error_of_mean_closed_forms():
    # population std of (1, 3) is 1, over sqrt(2) values
    assert standard_error_of_mean([1.0, 3.0]) == pytest.approx(1 / math.sqrt(2), abs=1e-15)
    # non-finite realizations are left out: the same two values remain
    assert standard_error_of_mean([1.0, np.nan, 3.0, np.inf]) == standard_error_of_mean([1.0, 3.0])
    assert math.isnan(standard_error_of_mean([2.0]))
    assert math.isnan(standard_error_of_mean([np.nan, 2.0]))


def test_std_ratio_relative_error_against_monte_carlo():
    k = 200
    rng = np.random.default_rng(2)
    s = rng.normal(size=(REPS, 2, k)).std(axis=2)
    ratio = s[:, 1] / s[:, 0]
    measured = ratio.std(ddof=1) / ratio.mean()
    assert measured == pytest.approx(std_ratio_relative_error(k), rel=MC_RTOL)
    assert std_ratio_relative_error(1) == math.inf


def test_ks_sampling_scale_is_the_kolmogorov_quantile():
    # 1.36·sqrt(60/900) = 0.351 for 30 points each
    assert ks_sampling_scale(30, 30) == pytest.approx(0.3512, abs=1e-3)
    # the constant is the 95 % quantile of the Kolmogorov distribution (1.3581), to its digits
    c = ks_sampling_scale(400, 100) / math.sqrt(500 / (400 * 100))
    assert c == pytest.approx(stats.kstwobign.ppf(0.95), abs=0.005)
    assert ks_sampling_scale(0, 10) == math.inf


def test_local_exponent_of_an_exact_power_law():
    ns = np.array([1000, 5000, 20000])
    for b in (-1.0, -0.3, 0.0):
        assert local_exponent(ns, 0.7 * ns.astype(float) ** b) == pytest.approx(b, abs=1e-12)
    # only the two largest sizes count
    assert local_exponent(ns, [5.0, 2.0, 1.0]) == pytest.approx(-0.5, abs=1e-15)
    assert math.isnan(local_exponent(ns[:1], [1.0]))
    assert math.isnan(local_exponent(ns, [1.0, 0.0, 1.0]))  # a zero variance has no logarithm
    with pytest.raises(ValueError, match="var must have the shape of ns"):
        local_exponent(ns, [1.0, 2.0])


def test_variance_slope_stderr_closed_form_and_monte_carlo():
    # sqrt(4/99)/ln(4) = 0.2010/1.3863
    assert variance_slope_stderr(np.array([5000, 20000]), 100) == pytest.approx(0.1450, abs=1e-3)
    assert math.isnan(variance_slope_stderr(np.array([20000]), 100))
    assert math.isnan(variance_slope_stderr(np.array([20000, 5000]), 100))
    assert math.isnan(variance_slope_stderr(np.array([5000, 20000]), 1))
    # K = 100 realizations per N of a magnetization with variance 1/N: the scatter of the
    # measured slope over seeded repetitions is the predicted standard error, its mean −1
    k, ns = 100, np.array([5000, 20000])
    rng = np.random.default_rng(1)
    m = rng.normal(size=(REPS, 2, k)) / np.sqrt(ns)[None, :, None]
    slopes = np.array([local_exponent(ns, v) for v in m.var(axis=2)])
    err = variance_slope_stderr(ns, k)
    assert slopes.std(ddof=1) == pytest.approx(err, rel=MC_RTOL)
    assert abs(slopes.mean() + 1.0) < 3 * err / math.sqrt(REPS)  # 3 σ of the mean
