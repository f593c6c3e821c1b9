"""The model registry (analysis.experiments.models): every name builds the operator it documents.

Truths are independent of the builders: closed-form branch masses of the Gaussian density by
quadrature, sampling statistics of the truncated normal from scipy.stats, the dimers' direct
constructor.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import integrate, stats

from analysis.experiments.models import (
    MODELS,
    ModelParameters,
    build_operator,
    canonical_model_name,
    describe_model,
    model_record,
)


def test_registry_names_are_canonical_and_complete():
    assert set(MODELS) == {
        "dimers", "erf-play", "play", "relay", "n2", "n4", "preisach", "preisach-gauss", "pi",
        "preisach-uniform", "bouc-wen", "jiles-atherton", "rfim",
    }  # fmt: skip
    for name in MODELS:  # one spelling: lower case, words joined by '-'
        assert name == name.lower() and "_" not in name


def test_old_spelling_is_a_deprecated_alias_and_unknown_names_are_refused():
    with pytest.warns(DeprecationWarning, match="erf-play"):
        assert canonical_model_name("erf_play") == "erf-play"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert canonical_model_name("erf-play") == "erf-play"
    with pytest.raises(ValueError, match="model must be one of"):
        build_operator("erf play")
    with pytest.raises(TypeError, match="unknown model parameter"):
        build_operator("play", widht=2.0)


def test_dimers_equal_the_direct_constructor():
    from hysteresis import SpinDimerEnsemble

    op = build_operator("dimers", spins=200, seed=5)
    ref = SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, seed=5)
    np.testing.assert_array_equal(op.fields, ref.fields)
    pair = build_operator("dimers", fields=[[1.0, -1.0]], spin_coupling=2.0)
    # paper Table I: alpha = J - b1 = 1, beta = -J - b2 = -1
    assert pair.thresholds().alpha[0] == 1.0 and pair.thresholds().beta[0] == -1.0


def test_paper_examples_n2_n4_thresholds():
    n2 = build_operator("n2").thresholds()
    assert (n2.alpha[0], n2.beta[0]) == (0.0, -2.0)  # J = 2, b = (2, 0)
    n4 = build_operator("n4").thresholds()
    np.testing.assert_allclose(n4.alpha, [0.0, 2.5])
    np.testing.assert_allclose(n4.beta, [-2.0, 0.5])


def test_relay_play_erf_play_parameters():
    relay = build_operator("relay", width=3.0)
    assert (relay.alpha, relay.beta) == (1.5, -1.5)
    relay = build_operator("relay", alpha=0.5, beta=-2.0)
    assert (relay.alpha, relay.beta) == (0.5, -2.0)
    assert build_operator("play", width=3.0).width == 3.0
    erf = build_operator("erf-play", width=2.0, spread=0.5)
    assert erf.width == 2.0


def test_preisach_random_relays_sample_the_truncated_normal_half_widths():
    n, p, r_spread, sr = 20000, 2.0, 1.0, 0.8
    op = build_operator("preisach", spins=n, seed=1, width=p, spread=r_spread, width_spread=sr)
    alpha, beta = np.asarray(op.alpha), np.asarray(op.beta)
    half = 0.5 * (alpha - beta)
    centre = 0.5 * (alpha + beta)
    assert np.all(half >= 0)
    a = (0.0 - p / 2) / sr  # truncation at r = 0 in standard units
    dist = stats.truncnorm(a, np.inf, loc=p / 2, scale=sr)
    # Kolmogorov-Smirnov against the exact truncated normal and the centre normal
    assert stats.kstest(half, dist.cdf).pvalue > 1e-3
    assert stats.kstest(centre, stats.norm(0.0, r_spread).cdf).pvalue > 1e-3
    # sigma_r = 0: the paper's equal widths
    eq = build_operator("preisach", spins=50, seed=0, width=p, width_spread=0.0)
    np.testing.assert_allclose(np.asarray(eq.alpha) - np.asarray(eq.beta), p, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="width_spread"):
        build_operator("preisach", spins=5, width_spread=-1.0)


@pytest.mark.parametrize("sr", [0.2, 0.6])
def test_preisach_gauss_ascending_branch_equals_the_density_mass(sr):
    """From negative saturation, rising to u switches up every relay with alpha = s + r <= u:
    M(u) = -1 + 2 P(s + r <= u), with P computed here by quadrature of the stated density."""
    p, big_r = 2.0, 1.0
    op = build_operator("preisach-gauss", width=p, spread=big_r, width_spread=sr)
    z = stats.norm.sf(0.0, loc=p / 2, scale=sr)

    def prob_alpha_below(u: float) -> float:
        def f(r: float) -> float:
            return stats.norm.pdf(r, p / 2, sr) / z * stats.norm.cdf((u - r) / big_r)

        return integrate.quad(f, 0.0, p / 2 + 12 * sr, limit=200)[0]

    lo = -(5 * big_r + p / 2 + 5 * sr)
    us = np.array([-2.0, -0.5, 0.0, 1.0, 2.5])
    y, _ = op.apply(np.concatenate([[lo], us]), op.initial_state(lo))
    expected = np.array([-1.0 + 2.0 * prob_alpha_below(u) for u in us])
    np.testing.assert_allclose(y[1:], expected, atol=2e-3)
    with pytest.raises(ValueError, match="width_spread"):
        build_operator("preisach-gauss", width_spread=0.0)


def test_pi_plays_and_weights():
    op = build_operator("pi", width=2.0, plays=5)
    np.testing.assert_allclose(op.widths, [1.0, 1.5, 2.0, 2.5, 3.0])
    assert math.isclose(float(np.sum(op.weights)), 1.0)
    with pytest.raises(ValueError, match="plays"):
        build_operator("pi", plays=0)


def test_model_record_lists_only_what_the_model_reads_and_titles_name_it():
    assert model_record("play") == {"model": "play", "width": 2.0}
    rec = model_record("dimers", spins=20)
    assert rec == {
        "model": "dimers", "spins": 20, "seed": 0, "width": 2.0, "spread": 1.0,
        "spin_coupling": 2.0,
    }  # fmt: skip
    rec = model_record("dimers", fields=[[1, -1]])
    assert rec == {"model": "dimers", "fields": [[1.0, -1.0]], "spin_coupling": 2.0}
    title = describe_model(model_record("preisach-gauss"), [("C", 4.0)])
    assert title == "preisach-gauss p=2 R=1 σ_r=0.2, C=4"
    assert ModelParameters().spins == 20000  # paper Table II default


def test_preisach_uniform_follows_the_closed_form_of_the_uniform_triangle():
    """Uniform density 1/(2H²) on -H <= β <= α <= H: rising from -H to u switches up the
    relays with α <= u, mass (u + H)²/(4H²), so M(u) = -1 + (u + H)²/(2H²); falling from H
    to v switches down those with β >= v, mass (H - v)²/(4H²)."""
    h = 2.0
    op = build_operator("preisach-uniform", half_extent=h, resolution=256)
    up = np.linspace(-h, h, 9)
    y_up, state = op.apply(up, op.initial_state(-h))
    np.testing.assert_allclose(y_up, -1.0 + (up + h) ** 2 / (2 * h**2), atol=1e-12)
    down = np.linspace(h, -h, 9)
    y_down, _ = op.apply(down, state)
    np.testing.assert_allclose(y_down, 1.0 - (h - down) ** 2 / (2 * h**2), atol=1e-12)
    # default H = 5R + p/2, and the record names H (the only parameter the density reads)
    assert model_record("preisach-uniform", width=2.0, spread=1.0) == {
        "model": "preisach-uniform",
        "half_extent": 6.0,
    }
    with pytest.raises(ValueError, match="half_extent"):
        build_operator("preisach-uniform", half_extent=-1.0)


def test_duhem_models_build_from_their_fields_and_name_them_in_errors():
    """bouc-wen and jiles-atherton read their prefixed fields; a library error names the
    field (the CLI maps it to its option)."""
    from hysteresis import BoucWen, JilesAtherton

    bw = build_operator("bouc-wen", bw_a=2.0, bw_beta=0.5, bw_gamma=0.5, bw_n=2.0)
    assert isinstance(bw, BoucWen) and (bw.A, bw.beta, bw.gamma, bw.n) == (2.0, 0.5, 0.5, 2.0)
    ja = build_operator("jiles-atherton", ja_ms=2.0, ja_a=0.3, ja_k=0.4, ja_c=0.1, ja_alpha=0.2)
    assert isinstance(ja, JilesAtherton)
    assert (ja.ms, ja.a, ja.k, ja.c, ja.alpha) == (2.0, 0.3, 0.4, 0.1, 0.2)
    with pytest.raises(ValueError, match=r"^bw_beta \+ bw_gamma must be > 0"):
        build_operator("bouc-wen", bw_beta=0.0, bw_gamma=0.0)
    with pytest.raises(ValueError, match=r"^ja_c must lie in \[0, 1\]"):
        build_operator("jiles-atherton", ja_c=1.5)
    rec = model_record("bouc-wen")
    assert rec == {"model": "bouc-wen", "bw_a": 1.0, "bw_beta": 0.75, "bw_gamma": 0.25, "bw_n": 1.0}
    assert describe_model(rec) == "bouc-wen A=1 β=0.75 γ=0.25 n=1"
