"""Preisach-plane identification: exact cell masses, ridge statistics, smoothing, CLI.

Truth is independent of the code under test: Gaussian bin probabilities from scipy.stats.norm,
histograms of the sampled thresholds, a brute-force relay system written here, analytic
integrals of a smooth density, and exactly quadratic test surfaces.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm
from support_paths import DATA

from analysis.identification import (
    ReversalCurves,
    compare_with_ridge,
    identify_from_curves,
    identify_preisach,
    local_quadratic_density,
    measure_reversal_curves,
    pike_to_preisach,
    preisach_to_pike,
    regular_grid,
    s_cdf_distance,
)
from hysteresis.play import GeneralizedPlay

P, R = 2.0, 1.0
SAT = 5 * R + P / 2  # 6


class BruteRelays:
    """Independent brute-force relay system (DESIGN conventions): +1 once u >= alpha, −1 once
    u < beta, each relay updated at every input."""

    output_range = (-1.0, 1.0)

    def __init__(self, alpha, beta, weights):
        self.alpha = np.asarray(alpha, float)
        self.beta = np.asarray(beta, float)
        self.weights = np.asarray(weights, float)

    def initial_state(self, u0):
        return self.alpha <= u0

    def apply(self, inputs, state=None):
        inputs = np.asarray(inputs, float)
        up = self.initial_state(inputs[0]) if state is None else np.array(state)
        out = np.empty(inputs.size)
        for k, u in enumerate(inputs):
            up = np.where(u >= self.alpha, True, np.where(u < self.beta, False, up))
            out[k] = self.weights @ np.where(up, 1.0, -1.0)
        return out, up


def cell_index(grid, x):
    """1-based cell index i with grid[i-1] < x <= grid[i] (independent of the code under test)."""
    return np.searchsorted(grid, x, side="left")


# ----------------------------------------------------------------------------------------------
# erf play: the paper's N -> infinity density N(s; 0, R^2) delta(r - p/2)
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("k", [20, 15, 4])
def test_erf_play_ridge_exact(k):
    step = P / k
    ident = identify_preisach(GeneralizedPlay.erf(P, R), step, SAT)
    grid = regular_grid(step, SAT)
    assert np.array_equal(ident.alpha, grid) and ident.step == pytest.approx(step)
    # total mass telescopes to the saturation magnetisation minus the Gaussian tails beyond the grid
    assert ident.total_mass == pytest.approx(1.0, abs=1e-6)
    # all the mass on the single diagonal d = p/step, centre exactly p/2
    r, mr = ident.r_marginal()
    assert mr[k] == pytest.approx(ident.total_mass, abs=1e-12)
    assert np.abs(np.delete(mr, k)).max() < 1e-12
    cmp = compare_with_ridge(ident, P, R)
    assert abs(cmp.r_centre - P / 2) < 1e-9
    assert cmp.r_mass_within_2_cells == pytest.approx(1.0, abs=1e-12)
    # s-marginal cells: probability that s lies in (alpha_{i-1} - p/2, alpha_i - p/2]
    s, ms = ident.s_marginal()
    i = np.arange(1, grid.size)
    j = i - k
    ok = j >= 1
    kk = i[ok] + j[ok]  # bin index i + j; s_marginal starts at i + j = 2
    expected = norm.cdf(grid[i[ok]] - P / 2, scale=R) - norm.cdf(grid[i[ok] - 1] - P / 2, scale=R)
    np.testing.assert_allclose(ms[kk - 2], expected, rtol=0, atol=1e-9)
    # bin centres are the cell centres s = (alpha_i + beta_j)/2 - step/2
    np.testing.assert_allclose(s[kk - 2], 0.5 * (grid[i[ok]] + grid[j[ok]]) - step / 2, atol=1e-12)
    # every other half-step bin is empty
    rest = np.ones(ms.size, bool)
    rest[kk - 2] = False
    assert np.abs(ms[rest]).max() < 1e-12
    # CDF distance to the Gaussian: only the tail below the grid (Phi(-5) = 2.9e-7)
    assert cmp.s_cdf_distance_gaussian < 1e-6


def test_step_not_dividing_width_splits_ridge_but_keeps_centre():
    step = 0.3  # p/step = 6.67
    # saturation 7: the Gaussian tails cut off by the grid edge (Phi(-6) = 1e-9) would bias the
    # split between the two diagonals by ~1e-8 at saturation 6 (Phi(-5) = 3e-7)
    ident = identify_preisach(GeneralizedPlay.erf(P, R), step, 7.0)
    r, mr = ident.r_marginal()
    on = np.flatnonzero(mr > 1e-12)
    assert list(on) == [6, 7]
    theta = P / step - 6  # fraction of the ridge on the upper diagonal for uniform phases
    assert mr[7] / mr.sum() == pytest.approx(theta, abs=1e-6)
    cmp = compare_with_ridge(ident, P, R)
    assert abs(cmp.r_centre - P / 2) < 1e-9
    assert cmp.r_mass_within_2_cells == pytest.approx(1.0, abs=1e-12)


def test_everett_function_on_grid_matches_closed_form():
    step = 0.5
    ident = identify_preisach(GeneralizedPlay.erf(P, R), step, SAT)
    a, b = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    # E = P(beta + p/2 < s <= alpha - p/2) for s ~ N(0, R^2)
    expected = np.clip(norm.cdf(a - P / 2) - norm.cdf(b + P / 2), 0, None)
    np.testing.assert_allclose(ident.everett, expected, atol=1e-13)


# ----------------------------------------------------------------------------------------------
# relay systems: half-open cells, Pike = Mayergoyz, dimers
# ----------------------------------------------------------------------------------------------
def test_relays_on_grid_points_belong_to_the_lower_left_cell():
    grid = regular_grid(0.5, 3.0)  # -3, -2.5, ..., 3
    alpha = np.array([0.5, 0.5, 1.0, -1.0, 2.0, 0.75, -0.2])
    beta = np.array([-1.0, 0.5, 0.25, -1.0, -2.5, -0.25, -0.3])  # zero-width relays included
    w = np.array([0.1, 0.2, 0.15, 0.05, 0.2, 0.1, 0.2])
    op = BruteRelays(alpha, beta, w)
    ident = identify_preisach(op, 0.5, 3.0)
    expected = np.zeros((grid.size - 1, grid.size - 1))
    for a_, b_, w_ in zip(alpha, beta, w, strict=True):
        expected[cell_index(grid, a_) - 1, cell_index(grid, b_) - 1] += w_
    np.testing.assert_allclose(ident.cell_mass, expected, atol=1e-14)
    assert ident.total_mass == pytest.approx(1.0, abs=1e-14)
    # the same masses from Pike curves (positive saturation, down to H_r, up through H)
    pike = measure_reversal_curves(op, grid, convention="pike", saturation=3.0)
    ident_pike = identify_from_curves(pike)
    np.testing.assert_allclose(ident_pike.cell_mass, expected, atol=1e-14)


@settings(max_examples=25, deadline=None)
@given(
    st.integers(1, 12),
    st.lists(
        st.tuples(st.integers(-8, 8), st.integers(0, 10), st.booleans()), min_size=1, max_size=8
    ),
    st.floats(0.0, 0.999),
)
def test_random_relays_match_their_histogram(n_relays_scale, units, jitter):
    """Relays on and off the grid points (half-open cells), zero widths included."""
    step = 0.25
    grid = regular_grid(step, 3.0)
    alpha, beta = [], []
    for k, width_steps, on_grid in units:
        a = k * step if on_grid else (k - jitter) * step
        alpha.append(a)
        beta.append(a - width_steps * step * (1.0 if on_grid else 0.5 + 0.5 * jitter))
    alpha, beta = np.array(alpha), np.array(beta)
    w = np.arange(1, alpha.size + 1, dtype=float) * n_relays_scale
    w /= w.sum()
    ident = identify_preisach(BruteRelays(alpha, beta, w), step, 3.0)
    inside = beta > grid[0]  # relays with beta <= beta_0 lie outside every cell
    expected = np.zeros_like(ident.cell_mass)
    idx = (cell_index(grid, alpha[inside]) - 1, cell_index(grid, beta[inside]) - 1)
    np.add.at(expected, idx, w[inside])
    np.testing.assert_allclose(ident.cell_mass, expected, atol=1e-13)
    assert ident.total_mass == pytest.approx(w[inside].sum(), abs=1e-13)


def test_irregular_curves_without_shared_fields_telescope():
    """Each curve on its own random fields, all ending at -6: the masses still telescope to
    E(a_last, -6) - E(a_first, -6) (closed form for the erf play)."""
    op = GeneralizedPlay.erf(P, R)
    rng = np.random.default_rng(3)
    rev = np.sort(rng.uniform(-5.5, 6.0, 40))
    fields, moments = [], []
    for a in rev:
        pts = np.concatenate([[a], np.sort(rng.uniform(-6.0, a, 15))[::-1], [-6.0]])
        pts = pts[np.concatenate([[True], np.diff(pts) < -1e-9])]
        y, _ = op.apply(pts, op.initial_state(a))
        fields.append(pts)
        moments.append(y)
    ident = identify_from_curves(ReversalCurves(rev, tuple(fields), tuple(moments)), grid="native")
    assert ident.step is None

    def everett(a, b):  # P(b + p/2 < s <= a - p/2)
        return max(norm.cdf(a - P / 2) - norm.cdf(b + P / 2), 0.0)

    expected = everett(rev[-1], -6.0) - everett(rev[0], -6.0)
    assert ident.total_mass == pytest.approx(expected, abs=1e-12)
    cmp = compare_with_ridge(ident, P, R)
    assert abs(cmp.r_centre - P / 2) < 0.05  # cell centres of an irregular lattice, not exact


def test_pike_and_mayergoyz_agree_for_erf_play_and_mirror():
    op = GeneralizedPlay.erf(P, R)
    grid = regular_grid(0.25, SAT)
    may = identify_from_curves(measure_reversal_curves(op, grid))
    pike_curves = measure_reversal_curves(op, grid, convention="pike", saturation=SAT)
    pike = identify_from_curves(pike_curves)
    np.testing.assert_allclose(pike.cell_mass, may.cell_mass, atol=1e-13)
    # the erf play is mirror-symmetric: mirrored Pike data are its own Mayergoyz data
    mirrored = pike_curves.mirrored()
    assert mirrored.convention == "mayergoyz"
    np.testing.assert_allclose(identify_from_curves(mirrored).cell_mass, may.cell_mass, atol=1e-13)
    # coordinates: (H_r, H) = (beta, alpha); H_c = r, H_u = s
    hr, h = preisach_to_pike(1.5, -0.5)
    assert (hr, h) == (-0.5, 1.5)
    assert tuple(pike_to_preisach(hr, h)) == (1.5, -0.5)


def _dimers(n_spins, seed=0):
    from hysteresis.spin_dimers import SpinDimerEnsemble

    return SpinDimerEnsemble.random(n_spins, P, R, 2.0, seed=seed)


def test_dimers_20000_exact_counts_and_kolmogorov():
    n = 20000
    ens = _dimers(n, seed=0)
    th = ens.thresholds()
    assert np.all(th.hysteretic)
    step = 0.1
    saturation = max(SAT, float(np.max(np.abs([th.alpha, th.beta]))) + step)
    ident = identify_preisach(ens, step, saturation)
    grid = ident.alpha
    counts = ident.cell_mass * (n / 2)
    # integer counts / (N/2)
    assert np.abs(counts - np.round(counts)).max() < 1e-8
    assert ident.total_mass == pytest.approx(1.0, abs=1e-12)
    # exactly the histogram of the sampled thresholds
    expected = np.zeros_like(counts)
    np.add.at(expected, (cell_index(grid, th.alpha) - 1, cell_index(grid, th.beta) - 1), 1)
    assert np.array_equal(np.round(counts), expected)
    # the s-marginal is the empirical distribution of the centres, binned on the ridge diagonal
    k = round(P / step)
    s, ms = ident.s_marginal()
    i = cell_index(grid, th.alpha)
    hist = np.bincount(2 * i - k - 2, minlength=ms.size)
    assert np.array_equal(np.round(ms * n / 2).astype(int), hist)
    cmp = compare_with_ridge(ident, P, R, centres=th.centre)
    assert cmp.s_cdf_distance_empirical < 1e-12  # float round-off of the cumulated masses
    assert cmp.s_cdf_distance_gaussian < 1.36 / math.sqrt(n / 2)
    assert abs(cmp.r_centre - P / 2) < 1e-9
    assert cmp.r_mass_within_2_cells == pytest.approx(1.0, abs=1e-12)


def test_s_cdf_distance_detects_a_wrong_distribution():
    ident = identify_preisach(GeneralizedPlay.erf(P, R), 0.1, SAT)
    d = s_cdf_distance(ident, lambda x: norm.cdf(x, loc=0.2, scale=R))
    # true sup |Phi(x) - Phi(x - 0.2)| = 2 Phi(0.1) - 1 = 0.0797, seen at the grid resolution
    assert 0.07 < d < 0.0797 + 1e-9


# ----------------------------------------------------------------------------------------------
# continuous Preisach model with a smooth density
# ----------------------------------------------------------------------------------------------
def test_continuous_preisach_smooth_density_recovered():
    from hysteresis.preisach import PreisachModel

    # mu(alpha, beta) = c (alpha - beta) on the triangle -1 <= beta <= alpha <= 1, normalised:
    # integral of (alpha - beta) over the triangle = 4/3
    c = 0.75

    def density(alpha, beta):
        a = np.asarray(alpha, float)
        b = np.asarray(beta, float)
        return np.where((b <= a) & (a <= 1) & (b >= -1), c * (a - b), 0.0)

    model = PreisachModel.from_density(density, -1.0, 1.0)
    step = 0.25
    ident = identify_preisach(model, step, 1.0)
    g = ident.alpha
    # analytic cell integrals of c (alpha - beta) over (a0, a1] x (b0, b1], cut to beta <= alpha
    expected = np.zeros_like(ident.cell_mass)
    for i in range(1, g.size):
        a0, a1 = g[i - 1], g[i]
        for j in range(1, i):
            b0, b1 = g[j - 1], g[j]
            expected[i - 1, j - 1] = c * (
                (a1**2 - a0**2) / 2 * (b1 - b0) - (a1 - a0) * (b1**2 - b0**2) / 2
            )
        expected[i - 1, i - 1] = c * (a1 - a0) ** 3 / 6  # triangle: int (a - a0)^2 / 2 da
    # the model tabulates E on a 1/256 lattice that contains our nodes: exact up to quadrature
    np.testing.assert_allclose(ident.cell_mass, expected, rtol=0, atol=1e-10)
    assert ident.total_mass == pytest.approx(1.0, abs=1e-10)


def test_uniform_preisach_density_factor_two_in_rs():
    from hysteresis.preisach import PreisachModel

    # uniform mu_ab = 1/8 on the triangle -2 <= beta <= alpha <= 2 (area 8): mu_rs = 1/4
    def density(alpha, beta):
        a = np.asarray(alpha, float)
        b = np.asarray(beta, float)
        return np.where(b <= a, 1.0 / 8.0, 0.0) + 0.0 * a

    model = PreisachModel.from_density(density, -2.0, 2.0)
    ident = identify_preisach(model, 0.25, 2.0, smoothing=(1.5, 1.5))
    physical = ident.cell_area() > 0
    np.testing.assert_allclose(ident.cell_density_rs()[physical], 0.25, atol=1e-9)
    # diagonal cells are triangles of half the area and half the mass
    np.testing.assert_allclose(np.diag(ident.cell_mass), 0.25**2 / 2 / 8, atol=1e-12)
    # E is exactly quadratic away from the edges: smoothed mu_ab = 1/8, mu_rs = 1/4
    a, b = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    interior = (a - b > 0.8) & (a < 1.2) & (b > -1.2)
    np.testing.assert_allclose(ident.density_alpha_beta[interior], 1 / 8, atol=1e-9)
    np.testing.assert_allclose(ident.density_rs[interior], 1 / 4, atol=1e-9)
    # r-marginal of a uniform triangle: mass of diagonal d is (n - d) cells (half for d = 0)
    r, mr = ident.r_marginal()
    n = ident.alpha.size - 1
    expected = (n - np.arange(n)) * 0.25**2 / 8
    expected[0] /= 2
    np.testing.assert_allclose(mr, expected, atol=1e-12)


# ----------------------------------------------------------------------------------------------
# smoothing: local quadratic regression
# ----------------------------------------------------------------------------------------------
def _quadratic(a, b, g):
    return 0.3 + 0.2 * a - 0.1 * b + 0.05 * a * a - 0.07 * b * b + g * a * b


@pytest.mark.parametrize("convention", ["mayergoyz", "pike"])
@pytest.mark.parametrize("irregular", [False, True])
def test_smoothing_quadratic_surface_exact(convention, irregular):
    g = 0.4
    rng = np.random.default_rng(1)
    if irregular:
        rev = np.sort(rng.uniform(-2, 2, 30))
    else:
        rev = regular_grid(0.2, 2.0)
    fields, moments = [], []
    for r in rev:
        if irregular:
            n_pts = rng.integers(5, 25)
            if convention == "mayergoyz":
                h = np.concatenate([[r], np.sort(rng.uniform(-2.2, r, n_pts))[::-1]])
            else:
                h = np.concatenate([[r], np.sort(rng.uniform(r, 2.2, n_pts))])
            h = h[np.concatenate([[True], np.abs(np.diff(h)) > 1e-6])]
        else:
            h = rev[rev <= r][::-1] if convention == "mayergoyz" else rev[rev >= r]
        fields.append(h)
        # Mayergoyz: M(alpha = r, beta = h); Pike: M(H_r = r, H = h)
        moments.append(_quadratic(r, h, g))
    curves = ReversalCurves(rev, tuple(fields), tuple(moments), convention)
    ident = identify_from_curves(curves, smoothing=(2.0, 3.0), extend=False, grid="native")
    dens = ident.density_alpha_beta
    finite = np.isfinite(dens)
    assert finite.sum() > 20
    # Mayergoyz: mu = +1/2 d2f/dalpha dbeta; Pike: rho = -1/2 d2M/dH_r dH
    expected = g / 2 if convention == "mayergoyz" else -g / 2
    np.testing.assert_allclose(dens[finite], expected, atol=1e-8)
    np.testing.assert_allclose(ident.density_rs[finite], 2 * expected, atol=1e-8)


def test_local_quadratic_density_needs_enough_points():
    a = np.array([0.0, 1.0, 2.0])
    out = local_quadratic_density(a, a - 1, a, [1.0], [0.0], 1.0, 1.0)
    assert np.isnan(out[0])


def test_smoothed_erf_play_ridge_location_and_mass():
    step = 0.1
    ident = identify_preisach(GeneralizedPlay.erf(P, R), step, SAT, smoothing=(1.0, 4.0))
    dens = ident.density_rs
    a, b = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    s_nodes = 0.5 * (a + b)
    r_nodes = 0.5 * (a - b)
    on_axis = np.isclose(s_nodes, 0.0, atol=1e-9) & np.isfinite(dens)
    r_axis = r_nodes[on_axis]
    d_axis = dens[on_axis]
    assert r_axis[np.argmax(d_axis)] == pytest.approx(P / 2, abs=1e-9)
    # total smoothed mass (each node stands for a step x step cell in alpha-beta)
    assert np.nansum(ident.density_alpha_beta) * step**2 == pytest.approx(1.0, abs=1e-3)
    # mu(s) near s = 0: node lines s = 0 and s = step/2 have opposite lattice parity with respect
    # to the delta ridge; their mean (mass per ds = step/2 strip) estimates N(0; 0, 1)
    strips = [
        np.nansum(ident.density_alpha_beta[np.isclose(s_nodes, s0, atol=1e-9)])
        * step**2
        / (step / 2)
        for s0 in (0.0, step / 2)
    ]
    assert np.mean(strips) == pytest.approx(norm.pdf(0.0), rel=0.03)


# ----------------------------------------------------------------------------------------------
# argument checks and the CLI
# ----------------------------------------------------------------------------------------------
def test_bad_arguments():
    op = GeneralizedPlay.erf(P, R)
    with pytest.raises(ValueError, match="step"):
        identify_preisach(op, 0.0, SAT)
    with pytest.raises(ValueError, match="saturation"):
        identify_preisach(op, 0.1, -1.0)
    with pytest.raises(ValueError, match="smoothing"):
        identify_preisach(op, 0.5, SAT, smoothing=(1.0, -1.0))
    with pytest.raises(ValueError, match="first field"):
        ReversalCurves(np.array([0.0]), (np.array([0.1, -1.0]),), (np.array([0.0, 0.0]),))
    with pytest.raises(ValueError, match="decrease"):
        ReversalCurves(np.array([0.0]), (np.array([0.0, 1.0]),), (np.array([0.0, 0.0]),))


def test_cli_json_erf_play_and_dimers(tmp_path, capsys):
    from analysis.cli import main

    assert (
        main(
            [
                "identify",
                "--model",
                "erf-play",
                "--step",
                "0.25",
                "--out",
                str(tmp_path / "play"),
                "--json",
            ]
        )
        == 0
    )
    rep = json.loads(capsys.readouterr().out)
    assert rep["total_mass"] == pytest.approx(1.0, abs=1e-6)
    assert rep["r_centre"] == pytest.approx(1.0, abs=1e-9)
    assert rep["s_cdf_distance_empirical"] is None
    for p in rep["figures"]:
        assert (tmp_path / "play").joinpath(p.split("/")[-1]).exists()

    assert (
        main(
            [
                "identify",
                "--model",
                "dimers",
                "--spins",
                "400",
                "--step",
                "0.25",
                "--out",
                str(tmp_path / "dimers"),
                "--json",
            ]
        )
        == 0
    )
    rep = json.loads(capsys.readouterr().out)
    for key in (
        "total_mass",
        "r_centre",
        "r_mass_within_2_cells",
        "s_cdf_distance_gaussian",
        "s_cdf_distance_empirical",
    ):
        assert key in rep
    assert rep["total_mass"] == pytest.approx(1.0, abs=1e-12)
    assert rep["s_cdf_distance_empirical"] < 1e-12
    assert rep["s_cdf_distance_gaussian"] < 1.36 / math.sqrt(200)
    assert (tmp_path / "dimers" / "fig_preis_dens.png").exists()
    assert (tmp_path / "dimers" / "fig_preis_dens.npz").exists()


def test_cli_identify_from_file(tmp_path, capsys):
    from pathlib import Path

    from analysis.cli import main

    data = DATA
    assert (
        main(
            [
                "identify",
                "--input",
                str(data / "forc_erf_play_pike.micromag"),
                "--format",
                "micromag",
                "--out",
                str(tmp_path),
                "--json",
            ]
        )
        == 0
    )
    rep = json.loads(capsys.readouterr().out)
    assert rep["convention"] == "pike"
    assert rep["n_curves"] == 31 and rep["n_points"] == 496
    # data-driven summaries only: no paper overlay over user data
    for key in ("total_mass", "r_centre", "s_cdf_distance_gaussian", "width", "spread"):
        assert key not in rep
    # the erf play (p = 2, R = 1): every relay has B_c = 1, B_u ~ N(0, 1); all mass irreversible
    assert rep["irreversible_mass"] == pytest.approx(1.0, abs=1e-6)
    assert rep["reversible_mass"] == pytest.approx(0.0, abs=1e-12)
    assert rep["peak_bc_mT"] == pytest.approx(1.0, abs=rep["grid_step_mT"])
    assert abs(rep["peak_bu_mT"]) <= rep["grid_step_mT"]
    for p in rep["figures"]:
        assert Path(p).exists()


def test_cli_paper_metrics_only_for_the_paper_models(tmp_path, capsys):
    """Explicit dimer fields and the uniform Preisach model are not the paper's density: the
    report has data-driven masses, no ridge/Gaussian metrics; the JSON is strict (no NaN)."""
    from analysis.cli import main

    # two dimers, J = 2: (alpha, beta) = (J - b1, -J - b2) = (1, -1) and (1.5, 0), equal weight
    argv = ["identify", "--fields", "1", "-1", "0.5", "-2", "--step", "0.25", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "f"), "--json"]) == 0
    text = capsys.readouterr().out
    rep = json.loads(text)
    assert rep["fields"] == [[1.0, -1.0], [0.5, -2.0]] and rep["spin_coupling"] == 2.0
    assert rep["total_mass"] == pytest.approx(1.0, abs=1e-12)
    assert rep["irreversible_mass"] == pytest.approx(1.0, abs=1e-12)
    for key in ("r_centre", "s_cdf_distance_gaussian", "erf_play", "spread", "width"):
        assert key not in rep
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads((tmp_path / "f" / "identify.json").read_text()) == rep

    argv = ["identify", "--model", "preisach-uniform", "--saturation", "2", "--step", "0.5"]
    assert main([*argv, "--quiet", "--out", str(tmp_path / "u"), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["model"] == "preisach-uniform" and rep["half_extent"] == 2.0
    # the whole triangle lies inside the grid |u| <= H: all its mass is identified
    assert rep["total_mass"] == pytest.approx(1.0, abs=1e-9)
    assert "r_centre" not in rep and "preisach-uniform H=2" in rep["figure_title"]
