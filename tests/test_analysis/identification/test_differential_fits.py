"""Bouc–Wen and Jiles–Atherton fitted to noisy synthetic records (analysis.identification.
differential_fits).

Truth: records made by the toolkit's own operators with known parameters plus seeded white
noise of standard deviation σ. A correct fit predicts held-out samples to the noise level
(RMS ≈ σ; the bound 2σ leaves room for the estimation error of a few parameters, of relative
size ~sqrt(p/m)), and recovers the parameters within a few of its own standard errors (the
asymptotic least-squares errors are exact to O(1/m) for white noise: |error| <= 4 SE fails with
probability ~6e-5 per parameter).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.identification.differential_fits import loop_features
from analysis.identification.fitting import (
    fit_bouc_wen,
    fit_jiles_atherton,
    fit_prandtl_ishlinskii,
)
from hysteresis import BoucWen, JilesAtherton


def _excitation(n: int, amplitude: float) -> np.ndarray:
    """Four cycles of a sine with a slowly varying amplitude: major and minor reversals."""
    t = np.arange(n)
    return (
        amplitude
        * np.sin(2 * np.pi * t / (n / 4))
        * (0.6 + 0.4 * np.cos(2 * np.pi * t / (0.9 * n)))
    )


def _within(fit, truth: dict[str, float], sigmas: float = 4.0) -> None:
    for name, value in truth.items():
        est, se = fit.parameters[name], fit.standard_errors[name]
        assert math.isfinite(se) and se > 0, name
        assert abs(est - value) <= sigmas * se, (name, est, value, se)


# -- Bouc–Wen -----------------------------------------------------------------------------------

BW_TRUE = {"A": 1.5, "beta": 0.8, "gamma": 0.4, "n": 1.8, "offset": 0.3}
BW_NOISE = 0.01


def _bw_record(seed: int, n: int = 200, linear: float = 0.0, sign: float = 1.0):
    u = _excitation(n, 2.0)
    op = BoucWen(BW_TRUE["A"], BW_TRUE["beta"], BW_TRUE["gamma"], BW_TRUE["n"])
    z, _ = op.apply(u, op.state(0.0, u[0]))
    clean = BW_TRUE["offset"] + linear * u + sign * z
    return u, clean + np.random.default_rng(seed).normal(0.0, BW_NOISE, n), clean


def test_bouc_wen_predicts_held_out_data_and_recovers_its_parameters():
    u, y, clean = _bw_record(seed=1)
    fit = fit_bouc_wen(u, y)
    assert fit.info["orientation"] == 1
    assert fit.validation_rms <= 2.0 * BW_NOISE
    # against the noiseless record the held-out error is the estimation error alone
    err = fit.predict(u)[fit.n_train :] - clean[fit.n_train :]
    assert np.sqrt(np.mean(err**2)) <= BW_NOISE
    _within(fit, {**BW_TRUE, "linear": 0.0})
    # z_max is (A/(beta + gamma))^(1/n): a derived value, consistent
    p = fit.parameters
    assert p["z_max"] == pytest.approx((p["A"] / (p["beta"] + p["gamma"])) ** (1 / p["n"]))
    # the first sample fixes the initial state: the model starts on y[0]
    assert fit.predict(u[:1])[0] == pytest.approx(y[0], abs=1e-9)


def test_bouc_wen_play_like_actuator_and_the_pi_comparison():
    """``y = offset + d·u − z`` (counter-clockwise, a piezo-like actuator): orientation −1 and
    the linear term are found; the PI fit on the same record is worse (it has no saturating
    branch), and the fitted model has an inverse (every branch rises: the slope after a
    reversal at saturation, d − 2wA = 2.5 − 2·(2/3)·1.5 = 0.5, is the least)."""
    u, y, _ = _bw_record(seed=2, linear=2.5, sign=-1.0)
    fit = fit_bouc_wen(u, y)
    assert fit.info["orientation"] == -1
    assert fit.validation_rms <= 2.0 * BW_NOISE
    _within(fit, {**BW_TRUE, "linear": 2.5})
    pi = fit_prandtl_ishlinskii(u, y, np.linspace(0.2, 4.0, 15))
    assert pi.validation_rms > fit.validation_rms
    target = 0.3 + 0.8 * np.sin(np.linspace(0.0, 4 * np.pi, 60))
    command, _ = fit.model.inverse().apply(target - fit.offset)
    np.testing.assert_allclose(fit.offset + fit.model.apply(command)[0], target, atol=1e-6)


def test_bouc_wen_bad_guess_converges_and_features_land_in_the_basin():
    u, y, _ = _bw_record(seed=3)
    bad = {"A": 6.0, "beta": 0.1, "gamma": 2.0, "n": 5.0, "offset": -0.5, "linear": 0.5}
    alone = fit_bouc_wen(u, y, n_starts=1, initial=bad)
    assert alone.info["starts"] == 1
    assert alone.validation_rms <= 2.0 * BW_NOISE
    features = fit_bouc_wen(u, y, n_starts=1)  # the loop-feature guess, n = 1, alone
    assert features.validation_rms <= 2.0 * BW_NOISE
    assert features.parameters["n"] == pytest.approx(alone.parameters["n"], rel=1e-3)


def test_bouc_wen_refusals():
    u, y, _ = _bw_record(seed=4, n=40)
    with pytest.raises(ValueError, match=">= 20"):
        fit_bouc_wen(u[:10], y[:10])
    with pytest.raises(ValueError, match="u must vary"):
        fit_bouc_wen(np.zeros(40), y)
    with pytest.raises(ValueError, match="n_starts"):
        fit_bouc_wen(u, y, n_starts=0)
    with pytest.raises(ValueError, match="unknown keys"):
        fit_bouc_wen(u, y, initial={"A": 1.0, "beta": 1.0, "gamma": 0.0, "k": 1.0})
    with pytest.raises(ValueError, match="finite"):
        fit_bouc_wen(np.r_[u[:-1], np.nan], y)


def test_loop_features_of_a_known_loop():
    """A Bouc–Wen loop with n = 1 driven to saturation: the slope at z = 0 is A whatever the
    direction, the saturation z_max, the centre the offset."""
    u = np.concatenate([np.linspace(-6, 6, 400), np.linspace(6, -6, 400)])
    op = BoucWen(2.0, 1.0, 1.0, 1.0)  # z_max = 1
    z, _ = op.apply(u, op.state(-1.0, -6.0))
    f = loop_features(u, 0.5 + z)
    assert f["center"] == pytest.approx(0.5, abs=1e-6)
    assert f["saturation"] == pytest.approx(1.0, abs=1e-6)
    # the slope over |z| < 0.35 of a branch A − λz... averages to A within λ·0.35·(A/λ)/A
    assert f["initial_susceptibility"] == pytest.approx(2.0, rel=0.15)


# -- Jiles–Atherton -----------------------------------------------------------------------------

JA_TRUE = {"ms": 1.2e6, "a": 800.0, "k": 600.0, "c": 0.15, "alpha": 5e-4}


def _ja_record(seed: int, n: int = 600):
    h = _excitation(n, 5000.0)
    op = JilesAtherton(**JA_TRUE)
    m, _ = op.apply(h, op.state(0.0, h[0]))
    noise = 0.01 * float(np.max(np.abs(m)))
    return h, m + np.random.default_rng(seed).normal(0.0, noise, n), noise


def test_jiles_atherton_predicts_held_out_data_and_recovers_its_parameters():
    h, m, noise = _ja_record(seed=1)
    fit = fit_jiles_atherton(h, m)
    assert fit.validation_rms <= 2.0 * noise
    _within(fit, JA_TRUE)
    # M_irr from the first sample: the model's output there is M[0]
    assert fit.predict(h[:1])[0] == pytest.approx(m[0], rel=1e-9, abs=1e-9 * JA_TRUE["ms"])
    pi = fit_prandtl_ishlinskii(h, m, np.linspace(500.0, 8000.0, 15))
    assert pi.validation_rms > fit.validation_rms  # PI does not saturate


def test_jiles_atherton_bad_guess_converges():
    h, m, noise = _ja_record(seed=2)
    bad = {"ms": 3e6, "a": 3000.0, "k": 100.0, "c": 0.6, "alpha": 1e-4}
    fit = fit_jiles_atherton(h, m, n_starts=1, initial=bad)
    assert fit.validation_rms <= 2.0 * noise
    with pytest.raises(ValueError, match="exactly"):
        fit_jiles_atherton(h, m, initial={"ms": 1.0})


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(10, 16))
def test_jiles_atherton_error_coverage(seed):
    """Coverage: over seeds, each parameter within 3 standard errors (a failure rate of
    0.3 % per parameter if the errors are right)."""
    h, m, noise = _ja_record(seed=seed)
    fit = fit_jiles_atherton(h, m)
    assert fit.validation_rms <= 2.0 * noise
    _within(fit, JA_TRUE, sigmas=3.0)


def test_bouc_wen_error_coverage_over_seeds():
    """Coverage of the standard errors: over 8 seeds × 6 parameters |error| <= 2 SE should
    hold for ~95 %. Measured: 38 of 48 (A, beta, gamma of one seed move together, so the count
    scatters more than a binomial; their z-scores have RMS ~1.5: the asymptotic errors look up
    to ~1.5× optimistic for them on this 280-sample record). Asserted: at least 36 (75 %) —
    errors 2× too small would give ~68 %.
    The optimism is the small record's, not the errors': on 3000-sample records (16 seeds)
    96.9 % lie within 2 SE and every parameter's z-scores have RMS 0.8–1.1."""
    inside = 0
    for seed in range(20, 28):
        u, y, _ = _bw_record(seed=seed, n=400)
        fit = fit_bouc_wen(u, y)
        for name, value in {**BW_TRUE, "linear": 0.0}.items():
            inside += abs(fit.parameters[name] - value) <= 2.0 * fit.standard_errors[name]
    assert inside >= 36, inside
