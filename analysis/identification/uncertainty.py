"""Uncertainty of a FORC identification: significance map, peak interval, irreversible mass.

All three start from an identification made with ``uncertainty=True``
(:func:`~analysis.identification.identify_from_curves`): the smoothed density ``ρ`` and its
per-node standard error ``se`` (:mod:`analysis.identification.variforc`).

* **Significance** ``ρ/se`` per node; a node is significant at 95 % where ``|ρ| > 1.96 se``.
* **Peak interval**: the 95 % percentile interval of the peak's ``B_c`` and ``B_u`` over a
  parametric bootstrap of the noise, re-smoothed with the same smoothing
  (:mod:`analysis.identification.peak_bootstrap`; its coverage is tested on synthetic data).
  The range of the nodes not significantly below the peak would cover the true peak in every
  draw: conservative, not a 95 % interval.
* **Irreversible mass** ``Σ m_ij`` over the cells off the diagonal is a linear combination of the
  lattice values, ``Σ c_k v_k`` (the mixed differences telescope to the boundary of the region);
  with independent noise of variance ``σ²`` at the measured nodes its standard error is
  ``σ·sqrt(Σ c_k²)``, ``σ`` the median residual noise of the local regressions. Regridding of
  measured data onto the lattice correlates neighbouring nodes, so for the protocol lattice this
  is an estimate, not an exact standard error.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from analysis.identification.peak_bootstrap import peak_bootstrap
from analysis.identification.result import PreisachIdentification

__all__ = [
    "significance",
    "peak_interval",
    "irreversible_mass_error",
    "UncertaintySummary",
    "summarize_uncertainty",
]

Z95 = 1.959963984540054  # two-sided 95 % normal quantile


def _require(ident: PreisachIdentification) -> tuple[np.ndarray, np.ndarray]:
    if ident.density_alpha_beta is None or ident.density_se is None:
        raise ValueError("needs an identification made with smoothing and uncertainty=True")
    return ident.density_alpha_beta, ident.density_se


def significance(ident: PreisachIdentification) -> np.ndarray:
    """``ρ/se`` at every node (NaN where either is NaN or ``se = 0``)."""
    rho, se = _require(ident)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(se > 0, rho / se, np.nan)
    return out


def peak_interval(
    ident: PreisachIdentification,
    n_boot: int = 200,
    seed: int | np.random.Generator = 0,
    level: float = 0.95,
) -> tuple[tuple[float, float], tuple[float, float]]:
    """``((Bc_lo, Bc_hi), (Bu_lo, Bu_hi))``: the bootstrap interval of the peak
    (:func:`~analysis.identification.peak_bootstrap.peak_bootstrap`)."""
    boot = peak_bootstrap(ident, n_boot=n_boot, seed=seed, level=level)
    return boot.bc_interval, boot.bu_interval


def mass_coefficients(ident: PreisachIdentification) -> np.ndarray:
    """``c`` with ``irreversible_mass = Σ c·E`` over the nodes (the transposed mixed
    difference of the off-diagonal cells)."""
    off = (~ident._diagonal_cells()).astype(float)
    c = np.zeros(ident.everett.shape)
    c[1:, :-1] += off
    c[:-1, :-1] -= off
    c[1:, 1:] -= off
    c[:-1, 1:] += off
    return c


def irreversible_mass_error(ident: PreisachIdentification, sigma: float | None = None) -> float:
    """Standard error of :attr:`~PreisachIdentification.irreversible_mass` for independent
    noise ``sigma`` (default: the identification's ``noise_sigma``) on the half moments at
    the measured nodes (all nodes below the diagonal if the identification has no mask)."""
    if sigma is None:
        sigma = ident.noise_sigma
    if sigma is None or not math.isfinite(sigma):
        raise ValueError("needs a noise level: an identification made with uncertainty=True")
    c = mass_coefficients(ident)
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    # Σ c·E = Σ c·(M/2) exactly (a function of one index cancels in every mixed difference),
    # so the noise enters through the measured half moments, reversal points included
    noisy = ident.measured if ident.measured is not None else bb <= aa
    noisy = noisy & (bb <= aa)
    return float(sigma * math.sqrt(np.sum(c[noisy] ** 2)))


@dataclass(frozen=True)
class UncertaintySummary:
    """The numbers a report gives (field unit of the data; ρ in moment/field²)."""

    peak_bc: float
    peak_bu: float
    peak_rho: float
    peak_rho_se: float
    peak_bc_interval: tuple[float, float]
    peak_bu_interval: tuple[float, float]
    irreversible_mass: float
    irreversible_mass_se: float
    significant_fraction: float
    noise_sigma: float

    def as_dict(self) -> dict:
        return asdict(self)


def summarize_uncertainty(
    ident: PreisachIdentification, n_boot: int = 200, seed: int | np.random.Generator = 0
) -> UncertaintySummary:
    """Peak with its bootstrap interval (``n_boot`` replicates, ``seed``) and standard error
    (NaN for a density exactly 0: no peak), irreversible mass with its standard error,
    fraction of the evaluated nodes significant at 95 %, noise level."""
    rho, se = _require(ident)
    bc, bu, top = ident.density_peak()
    sig = significance(ident)
    evaluated = np.isfinite(sig)
    if ident.density_is_zero:  # no peak (density_peak warned): no interval either
        top_se = math.nan
        bc_interval = bu_interval = (math.nan, math.nan)
    else:
        usable = ident.peak_search_nodes(np.where(np.isfinite(se), rho, np.nan))
        k = np.nanargmax(np.where(usable, rho, np.nan))
        top_se = float(se.flat[k])
        bc_interval, bu_interval = peak_interval(ident, n_boot=n_boot, seed=seed)
    return UncertaintySummary(
        peak_bc=bc,
        peak_bu=bu,
        peak_rho=top,
        peak_rho_se=top_se,
        peak_bc_interval=bc_interval,
        peak_bu_interval=bu_interval,
        irreversible_mass=ident.irreversible_mass,
        irreversible_mass_se=irreversible_mass_error(ident),
        significant_fraction=float(np.mean(np.abs(sig[evaluated]) > Z95))
        if evaluated.any()
        else float("nan"),
        noise_sigma=float(ident.noise_sigma),
    )
