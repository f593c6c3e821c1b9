"""Metrics of an identified density: comparison with the analytic ridge ``N(s; s0, R²) δ(r − p/2)``
(:func:`compare_with_ridge`: mass, the ridge's position and width, the s-marginal's CDF distance;
:func:`compare_ridge_bins`: the masses along the ridge cell by cell).

The density's own summaries (total, reversible and irreversible mass, the FORC peak) are
properties of :class:`~analysis.identification.result.PreisachIdentification`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ndtr

from analysis.identification._checks import finite_number, positive_number
from analysis.identification.result import PreisachIdentification
from hysteresis._validation import real_array

__all__ = [
    "RIDGE_DIAGONAL_TOLERANCE",
    "RidgeBins",
    "RidgeComparison",
    "compare_ridge_bins",
    "compare_with_ridge",
    "empirical_cdf",
    "s_cdf_distance",
]


def empirical_cdf(samples: Any) -> Callable[[np.ndarray], np.ndarray]:
    """Right-continuous empirical CDF of ``samples``."""
    x = np.sort(real_array(samples, "samples").ravel())
    if x.size == 0:
        raise ValueError("samples must be non-empty")

    def cdf(t: Any) -> np.ndarray:
        return np.searchsorted(x, real_array(t, "t"), side="right") / x.size

    return cdf


def s_cdf_distance(ident: PreisachIdentification, cdf: Callable[[np.ndarray], np.ndarray]) -> float:
    """Sup-norm distance between the identified s-marginal CDF and ``cdf``.

    A cell's mass lies in ``s ∈ ((α_lo+β_lo)/2, (α_hi+β_hi)/2]``, so the CDF ``G`` of the
    identified mass is only known to lie between ``L(x) = Σ m[s_hi <= x]`` and
    ``U(x) = Σ m[s_lo < x]``. The distance is ``sup_x max(cdf − U, L − cdf, 0)``, the distance of
    ``cdf`` to that band (mass outside the grid is not included). It is exact at the resolution
    of the grid: for a ridge on one diagonal the band collapses to points at the cell edges, and
    the empirical CDF of the relays' own centres has distance exactly 0.
    """
    a_lo, a_hi, b_lo, b_hi = ident.cell_bounds()
    m = np.asarray(ident.cell_mass).ravel()
    keep = m != 0.0
    s_lo = (0.5 * (a_lo + b_lo)).ravel()[keep]
    s_hi = (0.5 * (a_hi + b_hi)).ravel()[keep]
    m = m[keep]
    if m.size == 0:
        return float("nan")
    o_hi = np.argsort(s_hi, kind="stable")
    o_lo = np.argsort(s_lo, kind="stable")
    sh, ch = s_hi[o_hi], np.cumsum(m[o_hi])
    sl, cl = s_lo[o_lo], np.cumsum(m[o_lo])
    # L at x = s_hi values: all cells with s_hi <= x
    lower = ch[np.searchsorted(sh, sh, side="right") - 1]
    # U at x = s_lo values: all cells with s_lo < x
    pos = np.searchsorted(sl, sl, side="left")
    upper = np.where(pos > 0, cl[np.maximum(pos - 1, 0)], 0.0)
    d1 = np.max(lower - np.asarray(cdf(sh), dtype=float))
    d2 = np.max(np.asarray(cdf(sl), dtype=float) - upper)
    return float(max(d1, d2, 0.0))


@dataclass(frozen=True)
class RidgeComparison:
    """Identified density vs ``N(s; centre, R²) δ(r − p/2)``.

    ``r_mass_within_2_cells``: fraction of the identified mass whose cell centre is within two
    grid cells of the ridge (``|r_c − p/2| <= Δ``, two diagonals on the regular lattice where
    ``r`` steps by ``Δ/2``). ``s_cdf_distance_empirical`` and ``kolmogorov_bound``
    (``1.36/sqrt(n)``, 95 %) are set when the finite ensemble's centres were given.
    """

    total_mass: float
    r_centre: float
    r_spread: float
    r_mass_within_2_cells: float
    s_cdf_distance_gaussian: float
    s_cdf_distance_empirical: float | None = None
    kolmogorov_bound: float | None = None
    n_units: int | None = None

    def as_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def compare_with_ridge(
    ident: PreisachIdentification,
    width: float,
    spread: float,
    centre: float = 0.0,
    centres: Any | None = None,
) -> RidgeComparison:
    """Compare with the paper's density ``N(s; centre, R²) δ(r − p/2)`` (width p, spread R).

    ``centres``: the loop centres ``s_k`` of a finite ensemble (e.g. ``(α + β)/2`` from
    ``SpinDimerEnsemble.thresholds()``) for the distance to their empirical CDF.
    """
    width = positive_number(width, "width")
    spread = positive_number(spread, "spread")
    m = np.asarray(ident.cell_mass)
    total = float(m.sum())
    r_c, _ = ident.cell_centres_rs()
    if total == 0.0:
        raise ValueError("the identified mass is zero; check step and saturation")
    r_mean = float((m * r_c).sum() / total)
    r_spread = float(np.sqrt(max((m * (r_c - r_mean) ** 2).sum() / total, 0.0)))
    cell = ident.step if ident.step is not None else float(np.median(np.diff(ident.alpha)))
    near = np.abs(r_c - 0.5 * width) <= cell * (1 + 1e-9)
    within = float(m[near].sum() / total)

    def gauss(x: np.ndarray) -> np.ndarray:
        return ndtr((np.asarray(x, dtype=float) - centre) / spread)  # the normal CDF

    d_gauss = s_cdf_distance(ident, gauss)
    d_emp = bound = n = None
    if centres is not None:
        c = np.asarray(centres, dtype=float).ravel()
        d_emp = s_cdf_distance(ident, empirical_cdf(c))
        n = int(c.size)
        bound = 1.36 / math.sqrt(n)
    return RidgeComparison(total, r_mean, r_spread, within, d_gauss, d_emp, bound, n)


#: how far ``p/Δ`` may be from an integer for the ridge to lie on one diagonal of cells
#: (round-off of the grid step, which is the grid's span over its number of cells)
RIDGE_DIAGONAL_TOLERANCE = 1e-9


@dataclass(frozen=True)
class RidgeBins:
    """The identified masses of the cells on the ridge ``β = α − p`` against the probabilities
    of ``N(s; centre, R²)`` over the same s-intervals (see :func:`compare_ridge_bins`).

    ``alpha``: the upper α node of each ridge cell; ``masses``: the identified cell masses;
    ``expected``: the Gaussian probabilities; ``off_ridge_mass``: ``Σ|m|`` over every cell minus
    ``Σ|m|`` over the ridge cells (0 for a density on the ridge alone).
    """

    alpha: np.ndarray
    masses: np.ndarray
    expected: np.ndarray
    off_ridge_mass: float

    @property
    def bins(self) -> int:
        """The number of ridge cells compared."""
        return int(self.masses.size)

    @property
    def max_error(self) -> float:
        """``max |mass − probability|`` over the ridge cells."""
        return float(np.max(np.abs(self.masses - self.expected)))


def compare_ridge_bins(
    ident: PreisachIdentification, width: float, spread: float, centre: float = 0.0
) -> RidgeBins:
    """Compare the identified density, cell by cell along the ridge, with the paper's
    ``N(s; centre, R²) δ(r − p/2)`` (loop width ``p`` = ``width``, spread ``R``).

    On a regular grid of step ``Δ`` with ``p/Δ`` an integer ``d`` the ridge ``β = α − p`` fills
    one diagonal of cells: the cell ``α ∈ (α_{i−1}, α_i]``, ``β = α − p`` holds exactly the
    loops with ``s = α − p/2 ∈ (α_{i−1} − p/2, α_i − p/2]``, whose probability under the
    Gaussian is ``Φ((α_i − p/2 − centre)/R) − Φ((α_{i−1} − p/2 − centre)/R)``. For an operator
    whose Everett function is exact (the erf play) mass and probability differ by round-off of
    the mixed differences only, so :attr:`RidgeBins.max_error` and
    :attr:`RidgeBins.off_ridge_mass` are round-off (~1e-15) there; for a finite ensemble they
    measure its sampling of the Gaussian.

    ``ValueError`` for an irregular grid, ``p/Δ`` not an integer (within
    :data:`RIDGE_DIAGONAL_TOLERANCE`) or a ridge outside the grid (``p`` at least its span).
    """
    width = positive_number(width, "width")
    spread = positive_number(spread, "spread")
    centre = finite_number(centre, "centre")
    if ident.step is None:
        raise ValueError("ident: the ridge bins need a regular grid (equal, uniform α and β nodes)")
    ratio = width / ident.step
    if abs(ratio - round(ratio)) > RIDGE_DIAGONAL_TOLERANCE:
        raise ValueError(
            f"width must be an integer multiple of the grid step {ident.step:g} (the ridge on "
            f"one diagonal of cells), got p/Δ = {ratio:g}"
        )
    d = int(round(ratio))
    m = np.asarray(ident.cell_mass)
    n = m.shape[0]
    if d >= n:
        raise ValueError(f"width must be below the grid's span {n * ident.step:g}, got {width:g}")
    ridge = np.array([m[i, i - d] for i in range(d, n)])
    alpha = np.asarray(ident.alpha)[d:]
    expected = np.diff(ndtr((alpha - 0.5 * width - centre) / spread))  # the normal CDF
    off_ridge = float(np.abs(m).sum() - np.abs(ridge).sum())
    return RidgeBins(alpha[1:], ridge, expected, off_ridge)
