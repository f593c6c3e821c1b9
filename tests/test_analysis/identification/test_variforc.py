"""VARIFORC smoothing and the standard errors of the local regression.

* the compiled lattice regression against a straightforward per-node weighted least-squares
  fit written here (Egli 2013's weights and smoothing law coded again from the paper's
  formulas), on a shipped synthetic MicroMag file;
* the fixed-factor special case against the FFT smoother;
* coverage of the 95 % intervals ``ρ̂ ± 1.96 se`` on synthetic FORCs with a known density and
  Gaussian noise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from forc_synthetic import noisy_curves, true_rho
from scipy.stats import norm
from support_paths import DATA

from analysis.identification import identify_from_curves
from analysis.identification.density import _protocol_tables
from analysis.identification.forc_io import read_forc_file
from analysis.identification.smoothing import grid_quadratic_density
from analysis.identification.smoothing_choice import AUTO_CANDIDATES, T_MAX, auto_candidates
from analysis.identification.uncertainty import irreversible_mass_error, significance
from analysis.identification.variforc import (
    VariforcParameters,
    variforc_factors,
    weighted_quadratic_density,
)

SAMPLE = DATA / "forc_micromag_0016_hybrid_si.frc"


# -- an independent implementation ------------------------------------------------------------
def egli_weight(u: np.ndarray, s: float) -> np.ndarray:
    """Egli (2013) eq. 6, coded from the formula: 1 inside s−1, two parabolic shoulders."""
    a = np.abs(u)
    return np.select(
        [a <= s - 1, a <= s - 0.5, a <= s],
        [np.ones_like(a), 1 - 2 * (a - s + 1) ** 2, 2 * (a - s) ** 2],
        0.0,
    )


def egli_factor(s0: float, s1: float, lam: float, distance: float) -> float:
    return min(max((1 - lam) * s1 + lam * distance, s0), max(s0, distance))


def per_node_regression(values, valid, nodes, step, node, sc, sb, box=False):
    """One node: weighted least squares of the quadratic over the whole lattice (weights zero
    outside the window), in field units; returns (rho, se) or None if the 3/4 rule fails."""
    i0, j0 = node
    aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
    da, db = aa - nodes[i0], bb - nodes[j0]
    ur, us = 0.5 * (da - db) / step, 0.5 * (da + db) / step
    if box:
        w = ((np.abs(ur) <= sc + 1e-9) & (np.abs(us) <= sb + 1e-9)).astype(float)
    else:
        w = egli_weight(ur, sc) * egli_weight(us, sb)
    # the half-window rule, counted on an unbounded lattice (offsets off the array: invalid)
    K = int(math.floor(sc + sb + 1e-9))
    di, dj = np.meshgrid(np.arange(-K, K + 1), np.arange(-K, K + 1), indexing="ij")
    if box:
        inw = (np.abs(di - dj) <= 2 * sc + 1e-9) & (np.abs(di + dj) <= 2 * sb + 1e-9)
    else:
        inw = (egli_weight(0.5 * (di - dj), sc) * egli_weight(0.5 * (di + dj), sb)) > 0
    ii, jj = i0 + di, j0 + dj
    inside = (ii >= 0) & (ii < len(nodes)) & (jj >= 0) & (jj < len(nodes))
    good = np.zeros_like(inw)
    good[inside] = valid[ii[inside], jj[inside]]
    for side in (di - dj <= -1, di - dj >= 1, di + dj <= -1, di + dj >= 1):
        if (good & inw & side).sum() < 0.75 * (inw & side).sum() - 1e-6:
            return None
    for side in (di <= -1, di >= 1, dj <= -1, dj >= 1):
        if (good & inw & side).sum() < 0.75 * (inw & side).sum() - 1e-6:
            return None
    use = valid & (w > 0)
    x, y, v, w = da[use], db[use], values[use], w[use]
    X = np.column_stack([np.ones_like(x), x, y, x * x, y * y, x * y])
    sw = np.sqrt(w)
    coef, *_ = np.linalg.lstsq(X * sw[:, None], v * sw, rcond=None)
    A = X.T @ (w[:, None] * X)
    B = X.T @ ((w * w)[:, None] * X)
    Ainv = np.linalg.inv(A)
    r = v - X @ coef
    s2 = np.sum(w * r * r) / (w.sum() - np.trace(Ainv @ B))
    cov = s2 * Ainv @ B @ Ainv
    return -coef[5], math.sqrt(cov[5, 5])


@pytest.fixture(scope="module")
def lattice():
    data = read_forc_file(SAMPLE)
    nodes, E, measured, step, offset = _protocol_tables(data.curves, None)
    aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
    return data, nodes, E + offset, measured, measured & (bb <= aa), step


def test_variforc_law_matches_the_published_formula():
    p = VariforcParameters()
    assert (p.sc0, p.sc1, p.sb0, p.sb1, p.lam) == (3.0, 7.0, 3.0, 7.0, 0.07)
    bc = np.array([0.0, 1.0, 2.5, 4.0, 6.0, 10.0, 100.0, 400.0])
    bu = -bc + 3.0
    sc, sb = variforc_factors(bc, bu, 0.5, VariforcParameters(bu0=1.0))
    for k in range(bc.size):
        assert sc[k] == pytest.approx(egli_factor(3, 7, 0.07, abs(bc[k]) / 0.5), rel=1e-15)
        assert sb[k] == pytest.approx(egli_factor(3, 7, 0.07, abs(bu[k] - 1.0) / 0.5), rel=1e-15)
    # the ridge: the smallest window s0, growing with the distance, never crossing the ridge
    assert (
        sc[0] == 3.0 and np.all(np.diff(sc) >= 0) and np.all(sc[1:] <= np.maximum(3, bc[1:] / 0.5))
    )


@pytest.mark.parametrize(
    "params",
    [VariforcParameters(), VariforcParameters(sc0=2, sc1=4, sb0=2.5, sb1=5, lam=0.2, bu0=-3.0)],
)
def test_variforc_matches_a_per_node_weighted_regression(lattice, params):
    data, nodes, values, valid, evaluate, step = lattice
    ident = identify_from_curves(data.curves, smoothing=params, extend=False, uncertainty=True)
    assert ident.smoothing_method == "variforc" and ident.variforc == params.as_dict()
    rho, se = ident.density_alpha_beta, ident.density_se
    assert np.array_equal(ident.alpha, nodes)
    scale = np.nanmax(np.abs(rho))
    idx = np.argwhere(evaluate)
    checked = 0
    for i, j in idx[:: max(1, len(idx) // 400)]:  # ~400 nodes, spread over the diagram
        bc, bu = 0.5 * (nodes[i] - nodes[j]), 0.5 * (nodes[i] + nodes[j])
        sc = egli_factor(params.sc0, params.sc1, params.lam, abs(bc) / step)
        sb = egli_factor(params.sb0, params.sb1, params.lam, abs(bu - params.bu0) / step)
        ref = per_node_regression(values, valid, nodes, step, (i, j), sc, sb)
        if ref is None:
            assert np.isnan(rho[i, j])
            continue
        checked += 1
        # 1e-8 of the peak: both are double-precision least squares of a 6-parameter fit with
        # a condition number of at most ~1e4 (scaled design), i.e. rounding ~1e-12
        assert abs(rho[i, j] - ref[0]) <= 1e-8 * scale
        assert se[i, j] == pytest.approx(ref[1], rel=1e-8)
    assert checked > 100


def test_fixed_factor_with_errors_is_the_fft_estimator(lattice):
    _, nodes, values, valid, evaluate, step = lattice
    fit = weighted_quadratic_density(values, valid, evaluate, step, (3.0, 2.0), nodes[0])
    fft = grid_quadratic_density(values, valid, evaluate, step, 3.0, 2.0)
    assert np.array_equal(np.isfinite(fit.rho), np.isfinite(fft))
    both = np.isfinite(fft)
    # two exact solvers of the same normal equations: rounding of the FFT correlations
    assert np.max(np.abs(fit.rho[both] - fft[both])) <= 1e-9 * np.nanmax(np.abs(fft))
    i, j = np.argwhere(both)[len(np.argwhere(both)) // 2]
    ref = per_node_regression(values, valid, nodes, step, (i, j), 3.0, 2.0, box=True)
    assert fit.se[i, j] == pytest.approx(ref[1], rel=1e-8)


# -- coverage of the standard errors -----------------------------------------------------------
@pytest.mark.parametrize("smoothing", [(3.0, 3.0), VariforcParameters(sc1=4, sb1=4)])
def test_standard_errors_cover_the_true_density(smoothing):
    """95 % intervals cover the true ρ at 95 ± 3 % of the nodes over many noise draws."""
    rng = np.random.default_rng(20)
    grid = np.arange(-30.0, 31.0, 1.0)
    # noise of 3 % of the saturation: se ~ 30 % of the peak, so that the smoothing bias of the
    # quadratic fit (a few % of the peak) is small against it (checked below); no extension
    # below the diagonal (the model M is not continued there)
    noise = 3e-2
    kw = {"smoothing": smoothing, "uncertainty": True, "extend": False}
    ref = identify_from_curves(noisy_curves(rng, 0.0, grid), **kw)
    aa, bb = np.meshgrid(ref.alpha, ref.beta, indexing="ij")
    # nodes away from the lattice edges, where the density is not negligible
    inner = np.isfinite(ref.density_alpha_beta) & (aa - bb >= 4) & (np.abs(aa) <= 22)
    inner &= np.abs(bb) <= 22
    truth = true_rho(aa, bb)[inner]
    bias = ref.density_alpha_beta[inner] - truth
    hits, total, rel_bias = 0, 0, 0.0
    for _ in range(40):
        ident = identify_from_curves(noisy_curves(rng, noise, grid), **kw)
        est, se = ident.density_alpha_beta[inner], ident.density_se[inner]
        rel_bias = max(rel_bias, float(np.max(np.abs(bias) / se)))
        hits += int(np.sum(np.abs(est - truth) <= norm.ppf(0.975) * se))
        total += truth.size
    # precondition: the smoothing bias is < 0.15 se, which lowers a 95 % coverage by < 0.3 %
    assert rel_bias < 0.15
    # 40 draws × ~1000 nodes; neighbouring nodes share their windows (~50 nodes each), so
    # ≥ 40·1000/50 = 800 independent checks: sd of the coverage <= 0.8 %, ±3 % is ±3.9 sd
    assert total > 30000
    assert 0.92 <= hits / total <= 0.98


@pytest.mark.parametrize("smoothing", [(3.0, 3.0), VariforcParameters(sc1=4, sb1=4)])
def test_mass_error_over_noise_draws(smoothing):
    """The irreversible mass's standard error matches its spread over noise draws (the peak
    interval's coverage: test_peak_bootstrap.py)."""
    rng = np.random.default_rng(7)
    grid = np.arange(-30.0, 31.0, 1.0)
    kw = {"smoothing": smoothing, "uncertainty": True, "extend": False}
    draws, masses, errors = 40, [], []
    for _ in range(draws):
        ident = identify_from_curves(noisy_curves(rng, 3e-2, grid), **kw)
        masses.append(ident.irreversible_mass)
        errors.append(irreversible_mass_error(ident))
        sig = significance(ident)
        assert np.array_equal(np.isfinite(sig), np.isfinite(ident.density_alpha_beta))
    # the sample sd of 40 draws has a relative standard error 1/sqrt(2·39) ≈ 11 %: ±35 % is ±3 sd
    assert np.std(masses, ddof=1) == pytest.approx(np.mean(errors), rel=0.35)


@pytest.mark.parametrize("seed", [11, 12])
def test_automatic_smoothing_is_near_the_oracle_and_grows_with_the_noise(seed):
    """``smoothing="auto"`` (Lepski rule on ρ) against the true ρ: on a low-noise and a
    high-noise draw of the same sample the chosen candidate's ρ error is within √5 of the best
    candidate's (the oracle, known here because ρ is), and the noisier data get more smoothing.

    The factor: the rule accepts candidate k only while the mean squared difference to every
    finer j, in units of se_j, is <= 2 (noise alone: <= 2, smoothing_choice's docstring), so
    the chosen k̂ >= oracle j* has a bias |b_k̂| <= |b_j*| + √2·se_j* (root mean square over
    the nodes) and se_k̂ <= se_j*, whence MSE_k̂ <= (|b| + √2 se)² + se² <= 2b² + 5se²
    <= 5·MSE_j*: RMSE within √5 ≈ 2.24 (Lepski's oracle inequality for this threshold)."""
    rng = np.random.default_rng(seed)
    grid = np.arange(-30.0, 31.0, 1.0)
    chosen = []
    for noise in (1e-3, 3e-2):  # 0.1 % and 3 % of the saturation moment
        data = noisy_curves(rng, noise, grid)
        ident = identify_from_curves(data, smoothing="auto", extend=False)
        choice = ident.smoothing_choice
        assert ident.smoothing_method == "variforc"
        assert ident.variforc["sc1"] == choice["chosen_s1"]
        # the chosen one ends the run of accepted candidates (scores <= T_MAX)
        k = AUTO_CANDIDATES.index(choice["chosen_s1"])
        assert all(t <= T_MAX for t in choice["scores"][: k + 1])
        assert len(choice["scores"]) == k + 1 or choice["scores"][k + 1] > T_MAX
        # the lattice noise (fourth differences) recovers the half moments' noise: ~3000
        # overlapping runs, the median's relative sd is a few % (10 % is > 2.5 sd); the
        # model's own fourth differences are < 1e-5, below both noise levels
        assert choice["noise_sigma"] == pytest.approx(noise / 2, rel=0.1)
        aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
        truth = true_rho(aa, bb)
        fits = [
            identify_from_curves(data, smoothing=c, extend=False).density_alpha_beta
            for c in auto_candidates()
        ]
        common = np.logical_and.reduce([np.isfinite(f) for f in fits])
        rmse = [math.sqrt(np.mean((f[common] - truth[common]) ** 2)) for f in fits]
        err = math.sqrt(np.mean((ident.density_alpha_beta[common] - truth[common]) ** 2))
        assert err <= math.sqrt(5.0) * min(rmse)
        chosen.append(choice["chosen_s1"])
    assert chosen[1] > chosen[0]
