"""FORC unmixing of sample series against known truth: series mixed from known Preisach
populations in known proportions (forc_series.py), the algebra of the end-member simplex
against brute force, PCA against a direct SVD, invariance to the order of the inputs,
diagrams on different grids, and the shipped instrument files end to end."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from forc_series import core_proportions, mixed_curves, population_curves, population_models
from support_paths import DATA

from analysis.identification import (
    ReversalCurves,
    identify_from_curves,
    measure_reversal_curves,
    regular_grid,
)
from analysis.identification.endmembers import (
    nfindr,
    principal_components,
    simplex_proportions,
    simplex_volume,
)
from analysis.identification.unmixing import unmix_forc
from oscillators import ForcedOscillator

PUBLIC = DATA / "forc_public"
NOISE = 3e-3  # moment noise (saturation moment 1): peak ρ / se ≈ 30 on the pure samples
N_SAMPLES = 12


@pytest.fixture(scope="module")
def series():
    """12 samples (the three pure populations first), noisy curves, the true proportions."""
    truth = core_proportions(N_SAMPLES, seed=1)
    rng = np.random.default_rng(7)
    return truth, [mixed_curves(p, NOISE, rng) for p in truth]


@pytest.fixture(scope="module")
def unmixed(series):
    return unmix_forc(series[1], seed=3)


def _aligned(result, truth):
    """The estimated proportions with their columns in the populations' order (an automatic
    end-member is a pure sample: its population is the one it is made of)."""
    cols = [int(np.argmax(truth[i])) for i in result.end_member_samples]
    est, se = np.zeros_like(truth), np.zeros_like(truth)
    est[:, cols], se[:, cols] = result.proportions, result.proportion_se
    return est, se


# -- the algebra -------------------------------------------------------------------------------


def test_pca_matches_a_direct_svd():
    rng = np.random.default_rng(11)
    x = rng.normal(size=(9, 4)) @ rng.normal(size=(4, 300)) + 1e-3 * rng.normal(size=(9, 300))
    pcs = principal_components(x)
    xc = x - x.mean(axis=0)
    _, s, vt = np.linalg.svd(xc, full_matrices=False)
    r = pcs.singular_values.size
    assert r == 8  # the centred series of 9 samples has rank 8
    # the Gram route squares the condition: eigenvalue errors ~ε·s_1², i.e. singular values
    # off by ~ε·s_1²/s_k and unit vectors by ~ε·(s_1/s_k)²·(gap factor); 64ε covers both
    eps = 64 * np.finfo(float).eps
    np.testing.assert_allclose(pcs.singular_values, s[:r], rtol=0, atol=eps * s[0] ** 2 / s[r - 1])
    gaps = np.minimum(np.abs(np.diff(s[:r], prepend=np.inf)), np.abs(np.diff(s[:r], append=0)))
    for k in range(r):  # the same unit vectors, up to the sign convention
        sign = np.sign(vt[k] @ pcs.loadings[k])
        atol = eps * s[0] ** 2 / (s[k] * gaps[k])
        np.testing.assert_allclose(pcs.loadings[k], sign * vt[k], atol=atol)
    np.testing.assert_allclose(pcs.mean + pcs.scores @ pcs.loadings, x, atol=1e-12)
    np.testing.assert_allclose(pcs.explained_variance_ratio.sum(), 1.0, rtol=1e-12)


def test_nfindr_finds_the_vertices_whatever_the_order():
    rng = np.random.default_rng(5)
    vertices = np.array([[0.0, 0.0], [4.0, 0.5], [1.0, 3.0]])
    inside = rng.dirichlet(np.ones(3), size=20) @ vertices
    points = np.vstack([inside[:7], vertices[0], inside[7:15], vertices[1:], inside[15:]])
    found = nfindr(points, 3)
    assert sorted(found.tolist()) == [7, 16, 17]
    for seed in range(3):  # any order of the samples gives the same points
        perm = np.random.default_rng(seed).permutation(points.shape[0])
        again = nfindr(points[perm], 3)
        assert sorted(perm[again].tolist()) == [7, 16, 17]
    # the volume is the largest over all triples (brute force)
    best = max(simplex_volume(points[list(c)]) for c in itertools.combinations(range(23), 3))
    assert simplex_volume(points[found]) == pytest.approx(best, rel=1e-12)


def test_simplex_proportions_inside_and_outside():
    v = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    p_true = np.random.default_rng(2).dirichlet(np.ones(3), size=10)
    p, dist = simplex_proportions(p_true @ v, v)
    np.testing.assert_allclose(p, p_true, atol=1e-9)  # barycentric coordinates inside
    assert np.all(dist < 1e-9)
    # outside: the nearest point of the triangle, by brute force over a fine sampling
    point = np.array([[0.8, 0.9]])
    p, dist = simplex_proportions(point, v)
    assert np.all(p >= 0) and p.sum() == pytest.approx(1.0, abs=1e-12)
    grid = np.array([(a, b) for a in np.linspace(0, 1, 401) for b in np.linspace(0, 1, 401)])
    grid = grid[grid.sum(axis=1) <= 1.0]
    brute = np.min(np.hypot(*(grid - point[0]).T))
    assert dist[0] == pytest.approx(brute, abs=2e-3)  # the sampling step 1/400
    np.testing.assert_allclose(p[0] @ v, [0.45, 0.55], atol=1e-9)  # closed form: edge x+y=1


def test_a_mixed_sample_is_the_operator_of_the_algebra():
    # the synthetic series mixes the populations' curves; the algebra's operator Σ p_k·model_k
    # driven through the same reversal curves gives the same moments
    grid = regular_grid(0.25, 3.0)
    p = (0.2, 0.5, 0.3)
    models = population_models()
    mixture = p[0] * models[0] + p[1] * models[1] + p[2] * models[2]
    direct = measure_reversal_curves(mixture, grid)
    parts = [measure_reversal_curves(m, grid) for m in models]
    for c in range(direct.n_curves):
        combined = sum(pk * part.moments[c] for pk, part in zip(p, parts, strict=True))
        np.testing.assert_allclose(direct.moments[c], combined, atol=1e-12)


# -- synthetic series ----------------------------------------------------------------------------


def test_recovers_the_number_of_end_members_and_the_proportions(series, unmixed):
    truth, _ = series
    res = unmixed
    # evidence: χ² falls from ≫ 1 to below its bound at three end-members and stays flat
    chi2 = [row["chi2"] for row in res.component_test]
    assert res.n_components == 3 and res.chosen_by == "noise"
    assert chi2[0] > 50 and chi2[1] > 10 and chi2[2] < res.component_test[2]["bound"]
    assert abs(chi2[3] - chi2[2]) < 0.05 * chi2[2]
    # the end-members are the three pure samples, ordered by median Bc (soft first)
    assert res.end_member_samples == (2, 1, 0)
    est, se = _aligned(res, truth)
    err = np.abs(est - truth)
    # each proportion within 4 bootstrap standard deviations (27 free entries: a 4σ excursion
    # has probability ~0.2 %); the vertices themselves are exact
    assert np.all(err <= 4.0 * se + 1e-9), (err / np.maximum(se, 1e-12)).max()
    assert err.max() < 0.02  # "a few hundredths": measured 0.004 at this noise
    assert np.allclose(res.proportions.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(res.proportion_intervals[..., 0] <= res.proportions + 1e-12)
    assert np.all(res.proportion_intervals[..., 1] >= res.proportions - 1e-12)


def test_invariant_to_the_order_of_the_inputs(series, unmixed):
    truth, curves = series
    perm = np.random.default_rng(4).permutation(len(curves))
    again = unmix_forc([curves[i] for i in perm], seed=3)
    assert again.n_components == unmixed.n_components
    np.testing.assert_allclose(again.proportions, unmixed.proportions[perm], atol=1e-9)
    np.testing.assert_allclose(again.end_members, unmixed.end_members, atol=1e-9, equal_nan=True)
    np.testing.assert_allclose(np.abs(again.scores), np.abs(unmixed.scores[perm]), atol=1e-9)


def test_end_members_given_as_samples_or_coordinates(series, unmixed):
    _, curves = series
    by_index = unmix_forc(curves, end_members=[2, 1, 0], seed=3)
    np.testing.assert_allclose(by_index.proportions, unmixed.proportions, atol=1e-12)
    coords = unmixed.end_member_scores
    by_coords = unmix_forc(curves, end_members=coords, seed=3)
    np.testing.assert_allclose(by_coords.proportions, unmixed.proportions, atol=1e-12)
    assert by_coords.end_member_samples is None and by_coords.chosen_by == "end_members"


def test_diagrams_on_different_grids(series, unmixed):
    # half the series measured with another step and extent: resampled onto the coarser
    # lattice, the proportions agree with the same-grid series within their uncertainty
    truth, curves = series
    rng = np.random.default_rng(8)
    other = [mixed_curves(p, NOISE, rng, step=0.04, saturation=2.6) for p in truth[1::2]]
    mixed = list(curves)
    mixed[1::2] = other
    res = unmix_forc(mixed, seed=3)
    assert res.n_components == 3 and res.step == pytest.approx(0.05)
    assert res.bu[-1] <= 2.6 and res.bu[0] >= -2.6  # the common region is the overlap
    est, se = _aligned(res, truth)
    assert np.all(np.abs(est - truth) <= 4.0 * se + 1e-9)


def test_a_diagram_that_does_not_overlap_is_left_out(series):
    _, curves = series
    far = curves[3]
    shifted = ReversalCurves(
        far.reversal_field + 40.0, tuple(h + 40.0 for h in far.fields), far.moments, far.convention
    )
    res = unmix_forc([*curves[:6], shifted], labels=[f"s{k}" for k in range(7)], seed=0)
    assert res.labels == tuple(f"s{k}" for k in range(6))
    assert res.excluded == (("s6", "its diagram does not overlap the others' common region"),)


def test_end_member_models_and_the_sample_operator(series):
    # a fixed smoothing window, whose density integrates to the cell masses exactly (VARIFORC's
    # varying windows do not conserve the integral: 1.047 for the hard population here)
    truth, curves = series
    res = unmix_forc(curves, smoothing=(3.0, 3.0), seed=3)
    assert res.n_components == 3 and res.end_member_samples == (2, 1, 0)
    projections = res.projections()
    for p in projections:
        assert np.all(p.weights >= 0) and p.weights.sum() == pytest.approx(1.0, abs=1e-12)
    # the hard population (Bc = 1 ± 0.15, Bu = 0 ± 0.25) lies inside the common region: its
    # end-member carries its whole moment (M_s = 1), K = 1 within the noise of the sample
    # (the irreversible mass's standard error, σ·sqrt(Σc²) ≈ 3e-3·few, and the clipped
    # negative noise lobes of the projection)
    hard = res.end_member_samples.index(0)
    assert projections[hard].scale == pytest.approx(1.0, abs=0.01)
    # its model's Everett function against the population's own (both of mass 1)
    model = res.models()[hard]
    true = population_models()[0]
    h = (projections[hard].alpha.max() - projections[hard].beta.min()) / 47
    for a, b in [(1.5, -0.5), (1.2, -1.0), (0.8, -1.4), (1.0, 0.2), (2.0, -2.0)]:
        e_model = projections[hard].scale * float(model.everett(a, b))
        e_true = float(true.everett(a, b))
        # the model is a staircase on a lattice of step h: E is off by at most the mass of one
        # lattice row and column through (a, b), ≤ 2·h·max marginal density (≈ 2·h·1.6)
        assert e_model == pytest.approx(e_true, abs=2 * h * 1.6 + 0.01), (a, b)
    # a sample as an operator of the algebra, coupled to the oscillator
    op = res.sample_operator(5)
    row = res.proportions[5] * [p.scale for p in projections]
    assert res.sample_scale(5) == pytest.approx(row.sum())
    traj = ForcedOscillator(op, coupling=0.3).trajectory(5.0, sample_dt=0.5)
    assert np.all(np.isfinite(traj.q))


def test_inputs_without_standard_errors_need_the_number_of_end_members(series):
    _, curves = series
    idents = [identify_from_curves(c, smoothing=(3.0, 3.0)) for c in curves[:5]]
    with pytest.raises(ValueError, match="^n_components: give the number of end-members"):
        unmix_forc(idents)
    res = unmix_forc(idents, n_components=3)
    assert res.proportion_intervals is None and res.proportions.shape == (5, 3)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"n_components": 0}, r"^n_components must lie in \[1, 4\]"),
        ({"n_components": 2.5}, "^n_components must be an integer"),
        ({"end_members": [0, 9]}, "^end_members: input 9 is not a usable sample"),
        ({"end_members": [0, 0]}, "^end_members: the sample indices must be distinct"),
        ({"end_members": np.zeros((3, 3))}, r"^end_members must be .* shape \(3, 3\)"),
        ({"end_members": [0, 1], "n_components": 3}, r"^n_components \(3\) and end_members"),
        ({"normalize": "kg"}, "^normalize must be one of"),
        ({"n_boot": 5}, "^n_boot must be an integer >= 20"),
        ({"level": 1.5}, r"^level must lie in \(0, 1\)"),
    ],
)
def test_bad_arguments_are_one_line_errors(series, kwargs, message):
    _, curves = series
    with pytest.raises(ValueError, match=message) as info:
        unmix_forc(curves[:4], **kwargs)
    assert "\n" not in str(info.value)


def test_fewer_than_two_inputs():
    with pytest.raises(ValueError, match="^inputs must hold at least two diagrams"):
        unmix_forc([population_curves()[0]])


# -- files -----------------------------------------------------------------------------------


def test_shipped_instrument_files_end_to_end(tmp_path):
    files = sorted(p for p in PUBLIC.iterdir() if p.suffix != ".md")
    bad = tmp_path / "broken.csv"
    bad.write_text("reversal_field,field,moment\n1,2\n")
    seen = []
    res = unmix_forc([*files, bad], progress=lambda k, n, label, status: seen.append(status))
    # the excerpt of the Lake Shore file keeps curves 1-20, 123-128 and the last two: smoothed
    # like the others in field units (windows 6.66/1.60 = 4.2 times its own steps), its
    # diagram has too few nodes with data on every side of their windows to overlap them
    lakeshore = "B-9-3-85-87-FORC-1.5T_excerpt.csv"
    assert res.labels == tuple(p.name for p in files if p.name != lakeshore)
    assert [label for label, _ in res.excluded] == ["broken.csv", lakeshore]
    assert "line 2" in res.excluded[0][1]  # the reader's one-line reason
    assert seen[:4] == ["ok"] * 4 and seen[4] != "ok"
    # protocols differ (5.2 to 6.7 mT steps): the common lattice has the coarsest step
    assert res.step == pytest.approx(6.657385, rel=1e-6)
    assert 1 <= res.n_components <= 4 and res.component_test[0]["chi2"] > 10
    assert np.allclose(res.proportions.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(res.proportions >= 0)
    for m in res.models():
        assert np.all(m.weights >= 0)
    assert not math.isnan(res.sample_scale(0))


@pytest.mark.slow
def test_bootstrap_intervals_against_the_spread_over_noise_draws():
    # 20 noise draws of the series: the bootstrap's standard deviation against the actual
    # spread of the estimates, and the coverage of the true proportions by the 95 % intervals.
    # Measured: bootstrap sd / spread median 1.63 (0.76-7.0 over the 27 mixed entries),
    # coverage 98 %, bias < 0.001 against a spread of 0.003: conservative, as the module
    # docstring says (independent node noise instead of the smoothed density's correlated
    # noise, whose zero-mean kernel averages out of smooth directions). The spread of 20 draws
    # scatters by ~16 % per entry; the median over 27 entries by less.
    truth = core_proportions(N_SAMPLES, seed=1)
    ests, ses, cover = [], [], []
    for r in range(20):
        rng = np.random.default_rng(100 + r)
        res = unmix_forc([mixed_curves(p, NOISE, rng) for p in truth], seed=r, n_boot=100)
        est, se = _aligned(res, truth)
        cols = [int(np.argmax(truth[i])) for i in res.end_member_samples]
        lo, hi = np.zeros_like(truth), np.zeros_like(truth)
        lo[:, cols], hi[:, cols] = (
            res.proportion_intervals[..., 0],
            res.proportion_intervals[..., 1],
        )
        ests.append(est)
        ses.append(se)
        cover.append((lo - 1e-12 <= truth) & (truth <= hi + 1e-12))
    ests, ses, cover = np.array(ests)[:, 3:], np.array(ses)[:, 3:], np.array(cover)[:, 3:]
    ratio = ses.mean(axis=0) / ests.std(axis=0, ddof=1)
    assert 1.0 <= np.median(ratio) <= 2.5
    assert cover.mean() >= 0.93
    assert np.max(np.abs(ests.mean(axis=0) - truth[3:])) < 0.5 * ests.std(axis=0).mean()
