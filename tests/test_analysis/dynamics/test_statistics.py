"""Ensemble statistics against closed forms and an independent regression."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from analysis.dynamics.statistics import (
    empirical_pdf,
    magnetization_variance,
    power_law_fit,
    self_averaging_parameter,
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
