"""Ensemble statistics over disorder realizations: self-averaging, variance, PDFs, power laws,
and the sampling errors of these estimates (standard error of a mean, of a ratio of two standard
deviations, of a two-point power-law slope; the Kolmogorov–Smirnov and Wilson scales)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hysteresis._validation import real_array

__all__ = [
    "self_averaging_parameter",
    "magnetization_variance",
    "empirical_pdf",
    "EmpiricalPDF",
    "power_law_fit",
    "PowerLawFit",
    "Z95",
    "wilson_interval",
    "standard_error_of_mean",
    "std_ratio_relative_error",
    "ks_sampling_scale",
    "local_exponent",
    "variance_slope_stderr",
]

#: two-sided 95 % normal quantile
Z95 = 1.96


def wilson_interval(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial fraction ``k/n`` (95 % with the default ``z``;
    ``nan`` for ``n = 0``). Unlike the normal (Wald) interval it stays inside [0, 1] and does not
    collapse to a point for ``k = 0`` or ``k = n``."""
    if n == 0:
        return float("nan"), float("nan")
    p = k / n
    d = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / d
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, centre - half), min(1.0, centre + half)


def _values(values: Sequence[float] | np.ndarray, name: str = "values") -> np.ndarray:
    x = real_array(values, name)
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be finite")
    return x


def self_averaging_parameter(values: Sequence[float] | np.ndarray) -> float:
    """Self-averaging parameter ``SAP[D] = (mean(D²) − mean(D)²) / mean(D)²`` (paper eq. SAP).

    The relative variance of a quantity over disorder realizations (population moments, i.e.
    divided by K, not K − 1, as in the paper's overlines). It vanishes for N → ∞ when one large
    realization represents the ensemble.

    Raises ``ValueError`` when the mean is 0 (the SAP is undefined; use the variance then).
    """
    d = _values(values)
    mean = float(np.mean(d))
    if mean == 0.0:
        raise ValueError("values have mean 0: SAP is undefined (use magnetization_variance)")
    return float((np.mean(d * d) - mean * mean) / (mean * mean))


def magnetization_variance(values: Sequence[float] | np.ndarray) -> float:
    """``VAR[M] = mean(M_T²) − mean(M_T)²`` over realizations (population variance, paper)."""
    return float(np.var(_values(values)))


@dataclass(frozen=True)
class EmpiricalPDF:
    """Histogram normalized to a probability density: ``sum(density * widths) == 1``."""

    edges: np.ndarray
    density: np.ndarray

    @property
    def centers(self) -> np.ndarray:
        return 0.5 * (self.edges[1:] + self.edges[:-1])

    @property
    def widths(self) -> np.ndarray:
        return np.diff(self.edges)


def empirical_pdf(
    values: Sequence[float] | np.ndarray,
    bins: int | Sequence[float] | np.ndarray = 30,
    range: tuple[float, float] | None = None,  # noqa: A002 - numpy's name
) -> EmpiricalPDF:
    """Empirical probability density of ``values`` (e.g. the time-averaged magnetization M_T).

    ``bins`` is a number of equal bins over ``range`` (default: the data range) or explicit
    edges. Values outside explicit edges/range are not counted, and the density is normalized
    by the number of values *inside*, so it integrates to 1 over the edges.
    """
    x = _values(values)
    if isinstance(bins, bool):
        raise TypeError("bins must be an int or a sequence of edges, got a bool")
    if isinstance(bins, int | np.integer):
        if bins < 1:
            raise ValueError(f"bins must be >= 1, got {bins}")
        if bins > 10_000_000:
            raise ValueError(f"bins must be <= 10000000 (memory), got {bins}")
    elif isinstance(bins, str):
        raise TypeError(f"bins must be an int or a sequence of edges, got {bins!r}")
    else:
        edges = _values(bins, "bins")
        if edges.size < 2 or np.any(np.diff(edges) <= 0):
            raise ValueError("bins edges must be at least 2 strictly increasing values")
    counts, edges = np.histogram(x, bins=bins, range=range)
    inside = counts.sum()
    if inside == 0:
        raise ValueError("no values fall inside the bins")
    density = counts / (inside * np.diff(edges))
    return EmpiricalPDF(edges=edges, density=density)


@dataclass(frozen=True)
class PowerLawFit:
    """``y ≈ prefactor · x^exponent`` from a straight-line fit of ``log y`` on ``log x``."""

    exponent: float
    stderr: float
    prefactor: float
    n: int

    def __call__(self, x: np.ndarray | float) -> np.ndarray | float:
        return self.prefactor * np.asarray(x, dtype=float) ** self.exponent


def power_law_fit(
    x: Sequence[float] | np.ndarray,
    y: Sequence[float] | np.ndarray,
    sigma_y: Sequence[float] | np.ndarray | None = None,
) -> PowerLawFit:
    """Least-squares fit of ``log y = log a + b log x``; returns ``b`` and its standard error.

    With ``sigma_y`` (absolute errors of y) the points are weighted by ``(y/σ_y)²`` (the
    variance of ``log y`` is ``(σ_y/y)²``) and the standard error is the one of the weighted
    fit scaled by the residual scatter (as ``numpy.polyfit(cov=True)``). Requires x, y > 0 and at
    least 3 points for an error estimate (2 points give ``stderr = nan``).
    """
    xv = _values(x, "x")
    yv = _values(y, "y")
    if xv.shape != yv.shape:
        raise ValueError(f"x and y must have the same length, got {xv.size} and {yv.size}")
    if xv.size < 2:
        raise ValueError("power_law_fit needs at least 2 points")
    if np.any(xv <= 0) or np.any(yv <= 0):
        raise ValueError("x and y must be > 0 for a log-log fit")
    lx, ly = np.log(xv), np.log(yv)
    if sigma_y is None:
        w = np.ones_like(lx)
    else:
        s = _values(sigma_y, "sigma_y")
        if s.shape != yv.shape or np.any(s <= 0):
            raise ValueError("sigma_y must be > 0 and have the length of y")
        w = (yv / s) ** 2
    sw = w.sum()
    xm = np.sum(w * lx) / sw
    ym = np.sum(w * ly) / sw
    sxx = np.sum(w * (lx - xm) ** 2)
    if sxx == 0:
        raise ValueError("x must take at least 2 distinct values")
    slope = float(np.sum(w * (lx - xm) * (ly - ym)) / sxx)
    intercept = float(ym - slope * xm)
    n = xv.size
    if n > 2:
        resid = ly - (intercept + slope * lx)
        chi2 = np.sum(w * resid**2) / (n - 2)
        stderr = float(np.sqrt(chi2 / sxx))
    else:
        stderr = float("nan")
    return PowerLawFit(exponent=slope, stderr=stderr, prefactor=float(np.exp(intercept)), n=n)


def standard_error_of_mean(values: Sequence[float] | np.ndarray) -> float:
    """Standard error of the mean of the finite entries of ``values``: ``std/sqrt(n)`` with the
    population standard deviation (divided by ``n``, as the paper's overlines), over the ``n``
    finite entries only (a realization whose statistic is ``nan`` or ``inf`` is left out).

    ``nan`` for fewer than two finite entries (one value has no spread to estimate from)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.std(v) / math.sqrt(v.size)) if v.size > 1 else float("nan")


def std_ratio_relative_error(realizations: int) -> float:
    """Relative standard error of a ratio of two sample standard deviations, each from
    ``realizations`` = k independent Gaussian samples.

    A sample standard deviation of k Gaussian values has relative standard error
    ``1/sqrt(2(k−1))``; the two are independent, so their ratio has
    ``sqrt(2 · 1/(2(k−1))) = 1/sqrt(k−1)`` (to first order). ``inf`` for k <= 1."""
    return 1.0 / math.sqrt(realizations - 1) if realizations > 1 else float("inf")


def ks_sampling_scale(n1: int, n2: int) -> float:
    """The two-sample Kolmogorov–Smirnov 95 % critical distance ``1.36 sqrt((n1+n2)/(n1 n2))``
    (the asymptotic Kolmogorov quantile ``c(0.05) = 1.36``): the scale of the KS statistic's
    sampling noise between two samples of one distribution with ``n1`` and ``n2`` independent
    points. Successive points of a trajectory are correlated (fewer independent points), so for
    them it is a lower bound. ``inf`` if a sample is empty."""
    if n1 < 1 or n2 < 1:
        return float("inf")
    return 1.36 * math.sqrt((n1 + n2) / (n1 * n2))


def _one_d(ns: Sequence[float] | np.ndarray, name: str = "ns") -> np.ndarray:
    n = np.asarray(ns)
    if n.ndim != 1:
        raise ValueError(f"{name} must be a 1-D sequence, got shape {n.shape}")
    return n


def local_exponent(ns: Sequence[float] | np.ndarray, var: Sequence[float] | np.ndarray) -> float:
    """Local (two-point) power-law exponent of ``var`` in ``ns`` at the two largest sizes: the
    log-log slope ``ln(var[-1]/var[-2]) / ln(ns[-1]/ns[-2])`` (``ns`` ascending; paper fig:mag:
    ``VAR[M] ∝ N^slope``, −1 for independent dimers, 0 for a non-self-averaging magnetization).

    Its standard error from the sampling of the two variances is
    :func:`variance_slope_stderr`. ``nan`` for fewer than two sizes or a variance <= 0 (no
    logarithm)."""
    n = _one_d(ns)
    v = np.asarray(var, dtype=float)
    if v.shape != n.shape:
        raise ValueError(f"var must have the shape of ns {n.shape}, got {v.shape}")
    if n.size < 2 or v[-1] <= 0 or v[-2] <= 0:
        return float("nan")
    return float(np.log(v[-1] / v[-2]) / np.log(n[-1] / n[-2]))


def variance_slope_stderr(ns: Sequence[float] | np.ndarray, realizations: int) -> float:
    """Standard error of :func:`local_exponent` when each variance is a sample variance over
    ``realizations`` = K independent realizations.

    A sample variance of K Gaussian values has relative standard error ``sqrt(2/(K−1))``, so its
    logarithm has that standard error; the two variances are independent, so the difference of
    their logarithms has ``sqrt(2 · 2/(K−1))``, and the slope ``sqrt(4/(K−1)) / ln(N2/N1)``.
    ``nan`` for fewer than two sizes, K < 2 or sizes not increasing."""
    n = _one_d(ns)
    if n.size < 2 or realizations < 2 or n[-1] <= n[-2]:
        return float("nan")
    return math.sqrt(4.0 / (realizations - 1)) / math.log(n[-1] / n[-2])
