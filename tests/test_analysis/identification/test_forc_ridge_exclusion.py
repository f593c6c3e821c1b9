"""The peak search and the profiles skip the ``B_c ≈ 0`` ridge (``B_c`` below
``RIDGE_EXCLUSION_STEPS`` grid steps), tested on synthetic FORCs of a known density
(forc_synthetic.py: ρ ∝ φ((H − ha)/SA) φ((hb − Hr)/SB), unit step)."""

from __future__ import annotations

import numpy as np
import pytest
from forc_synthetic import noisy_curves, true_rho

from analysis.identification import identify_from_curves, identify_preisach
from analysis.identification.plots import forc_profiles
from analysis.identification.result import RIDGE_EXCLUSION_STEPS
from analysis.identification.uncertainty import summarize_uncertainty
from hysteresis import GeneralizedPlay

GRID = np.arange(-30.0, 31.0, 1.0)


def identify(ha, hb, noise=0.0, uncertainty=False):
    rng = np.random.default_rng(1)
    curves = noisy_curves(rng, noise, GRID, ha, hb)
    return identify_from_curves(curves, smoothing=(2.0, 2.0), extend=False, uncertainty=uncertainty)


def test_mask_is_bc_below_three_steps():
    ident = identify(2.0, -4.0)
    bc = 0.5 * (ident.alpha[:, None] - ident.beta[None, :])
    assert RIDGE_EXCLUSION_STEPS == 3
    assert np.array_equal(ident.ridge_excluded(), bc < 3.0 * ident.step - 1e-9)


def test_peak_beyond_the_ridge_is_unchanged():
    # true peak at B_c = (10 − (−10))/2 = 10, B_u = 0, far from the ridge
    ident = identify(10.0, -10.0)
    assert ident.density_peak() == ident.density_peak(exclude_ridge=False)
    bc, bu, _ = ident.density_peak()
    assert (bc, bu) == pytest.approx((10.0, 0.0), abs=0.5)  # a node of the half-step lattice


def test_peak_on_the_ridge_is_skipped():
    # true peak at B_c = 1 step: the search skips it and takes the largest node at B_c >= 3
    ident = identify(1.0, -1.0)
    bc_all, _, _ = ident.density_peak(exclude_ridge=False)
    assert bc_all < 3.0
    bc, bu, rho = ident.density_peak()
    assert bc >= 3.0
    dens = ident.density_alpha_beta
    beyond = np.where(ident.ridge_excluded(), np.nan, dens)
    assert rho == np.nanmax(beyond)
    # on the noise-free density (σ = 0) the largest node beyond the ridge is where the true ρ,
    # decreasing away from its peak, is largest among the evaluated nodes there
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    truth = np.where(np.isfinite(beyond), true_rho(aa, bb, 1.0, -1.0), np.nan)
    i, j = np.unravel_index(np.nanargmax(truth), truth.shape)
    assert bc == pytest.approx(0.5 * (ident.alpha[i] - ident.beta[j]), abs=1.0)


def test_bootstrap_and_summary_skip_the_ridge():
    ident = identify(1.0, -1.0, noise=1e-3, uncertainty=True)
    u = summarize_uncertainty(ident, n_boot=40, seed=2)
    assert u.peak_bc >= 3.0
    assert u.peak_bc_interval[0] >= 3.0 - 0.5  # replicate peaks refined by at most half a step


def test_profiles_start_at_the_exclusion():
    ident = identify(10.0, -10.0)
    bc, pc, bu, pu = forc_profiles(ident)
    assert bc[0] == pytest.approx(3.0 * ident.step)
    # both profiles integrate the same nodes: ∫∫ρ dB_c dB_u two ways (lattice sums)
    rho = np.nan_to_num(ident.density_alpha_beta)
    keep = ~ident.ridge_excluded() & (ident.beta[None, :] <= ident.alpha[:, None])
    area = 0.5 * ident.step**2  # a lattice node's share of the (B_c, B_u) plane
    total = float(rho[keep].sum()) * area
    assert np.sum(pc) * 0.5 * ident.step == pytest.approx(total, rel=1e-12)
    assert np.sum(pu) * 0.5 * ident.step == pytest.approx(total, rel=1e-12)


def test_mass_conventions_and_their_jacobian():
    # the erf play saturates in [−1, 1] with no reversible part: all its weight, 1, lies off the
    # ridge; ∬ρ dB_c dB_u over the diagram is half of it (dB_c dB_u = ½ dH dH_r)
    ident = identify_preisach(GeneralizedPlay.erf(2.0, 0.5), step=0.1, saturation=6.0)
    assert ident.irreversible_mass == pytest.approx(1.0, abs=1e-9)
    assert ident.irreversible_mass_bcbu == 0.5 * ident.irreversible_mass
    # independent: the smoothed ρ of noise-free synthetic FORCs summed over the (B_c, B_u)
    # lattice (Δ²/2 of area per node) is the diagram's integral, half the cell-mass sum
    synth = identify(10.0, -10.0)
    rho = synth.density_alpha_beta
    inside = np.isfinite(rho)
    lattice = float(rho[inside].sum()) * 0.5 * synth.step**2
    cells = synth.cell_mass[inside[1:, :-1] & inside[:-1, 1:] & inside[1:, 1:] & inside[:-1, :-1]]
    # the region whose ρ was evaluated and the cells inside it agree to its boundary's share
    assert lattice == pytest.approx(0.5 * float(cells.sum()), rel=0.05)
