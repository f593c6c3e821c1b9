"""Metrics of an identified density: comparison with the analytic ridge ``N(s; s0, R²) δ(r − p/2)``.

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

from analysis.identification._checks import positive_number
from analysis.identification.result import PreisachIdentification
from hysteresis._validation import real_array

__all__ = ["RidgeComparison", "compare_with_ridge", "empirical_cdf", "s_cdf_distance"]


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
