"""The integrated avalanche-size exponent of the 3-D random-field Ising model at its critical
disorder, against the literature (slow: three 64³ lattices, a full hysteresis loop each).

No 2-D test, on purpose (square lattice, Gaussian fields, J = 1; measured with the estimator
below, L = 500–2000, full loops, 4 seeds): the critical disorder quoted for 2-D (R_c ≈ 0.54)
could not be checked against a stored source, and at R = 0.54–0.65 one avalanche flips
>= 99.9 % of the spins for every L <= 2000 (finite-size R_c(L), where the mean largest
avalanche is N/2: 0.78, 0.73, 0.72, 0.66 at L = 500, 1000, 2000, 4000; R_c + a·L^−b fits give
R_c = 0.45, 0.62 for b = 0.19, 0.5: no extrapolation). Above R_c(L) the
fixed-window slope is 1.1–1.3 (window [10, 1000]: 1.12 ± 0.01 at R = 0.70, L = 2000; 1.27 at
R = 0.9) and a two-disorder collapse D(s, R) = s^−x f(s/S(R)) gives x ≈ 2.0 — but there 87–99 %
of the flips are in avalanches >= 1000, so the sum rule Σ s D(s) = 2 forces x = 2 whatever the
exponent: neither number is a measurement of τ + σβδ to compare with a literature value."""

from __future__ import annotations

import numpy as np
import pytest

from hysteresis.rfim import RandomFieldIsing

#: Perković, Dahmen and Sethna, Phys. Rev. B 59, 6106 (1999): τ + σβδ = 2.03 ± 0.03 and
#: R_c = 2.16 ± 0.03 (Gaussian fields, J = 1, simple cubic lattice)
TAU_PLUS_SIGMA_BETA_DELTA = 2.03
R_C = 2.16
#: apparent exponent's dependence on the fit window and on R − R_c at L = 64 (measured over
#: windows [2, 200] … [10, 1000] and R = 2.16 … 2.2: 2.00 … 2.10), with the literature's ±0.03
FINITE_SIZE_ALLOWANCE = 0.06


def integrated_exponent(sizes: np.ndarray, lo: int, hi: int, bins: int = 12) -> tuple[float, float]:
    """Slope of the integrated size distribution D(s) ~ s^−x on log bins in [lo, hi): weighted
    least squares of log(count/width) on log s with Poisson weights (var log n = 1/n); returns
    (x, its standard error)."""
    edges = np.unique(np.round(np.logspace(np.log10(lo), np.log10(hi), bins)).astype(int))
    counts = np.histogram(sizes, bins=edges)[0]
    assert counts.min() >= 5  # every bin resolved (Poisson weights take care of the rest)
    centres = np.sqrt(edges[:-1] * (edges[1:] - 1))
    a = np.column_stack([np.ones(centres.size), np.log(centres)])
    w = counts.astype(float)
    coef = np.linalg.lstsq(a * np.sqrt(w)[:, None], np.log(counts / np.diff(edges)) * np.sqrt(w),
                           rcond=None)[0]  # fmt: skip
    cov = np.linalg.inv(a.T @ (a * w[:, None]))
    return -float(coef[1]), float(np.sqrt(cov[1, 1]))


@pytest.mark.slow
def test_integrated_avalanche_exponent_3d_near_critical_disorder():
    """Three 64³ lattices at R = R_c = 2.16, one full loop each (every avalanche of the rising
    and falling sweeps: the integrated distribution), fit window s ∈ [5, 500] (above the
    lattice-scale corrections of the smallest sizes, below the finite-size cutoff of
    L = 64). The error of the mean is the seeds' spread (SEM) combined with the mean fit
    standard error over √3; the tolerance is twice that plus the allowance
    ``FINITE_SIZE_ALLOWANCE`` for the window and R − R_c dependence of the apparent exponent
    at this size (the literature's estimate comes from a scaling collapse up to 320³, not a
    fixed-window fit). Measured: 2.041 ± 0.004 (SEM), fit standard error 0.028."""
    fits = []
    for seed in range(3):
        model = RandomFieldIsing.lattice((64, 64, 64), R_C, seed=seed)
        sizes, _ = model.avalanche_sizes([1e3, -1e3], model.initial_state(-1e3))
        assert int(sizes.sum()) == 2 * model.n_spins  # every spin flipped up and down once
        fits.append(integrated_exponent(sizes, 5, 500))
    slopes, errors = np.array(fits).T
    sem = slopes.std(ddof=1) / np.sqrt(slopes.size)
    error = np.hypot(sem, errors.mean() / np.sqrt(slopes.size))
    assert abs(slopes.mean() - TAU_PLUS_SIGMA_BETA_DELTA) <= 2 * error + FINITE_SIZE_ALLOWANCE
