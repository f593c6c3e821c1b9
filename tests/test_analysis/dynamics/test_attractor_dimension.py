"""The attractor's Kaplan–Yorke dimension (analysis.dynamics.attractor_dimension): memory-frozen
where neutral memory directions distort the full-space one, against the box-counting dimension
of the same run's section, a periodic orbit's dimension 0, and the paper's systems unchanged."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from analysis.dynamics.attractor_dimension import (
    FULL_SPACE,
    MEMORY_FROZEN,
    UNTESTED,
    attractor_dimension,
    has_neutral_memory,
)
from analysis.dynamics.dimensions import box_counting_dimension, kaplan_yorke_dimension
from analysis.dynamics.lyapunov import LyapunovResult, lyapunov_spectrum
from analysis.dynamics.memory import (
    MemoryFrozenResult,
    exponent_block_errors,
    kaplan_yorke_block_error,
)
from analysis.dynamics.periods import smallest_period
from analysis.experiments.models import build_operator
from hysteresis import PrandtlIshlinskii
from oscillators import ForcedOscillator

TWO_PI = 2 * math.pi


def test_gaussian_preisach_attractor_dky_is_the_box_counting_dimension():
    # the width-disorder model at C = 4 (σ_r = 0.2): the full spectrum in (q, v, extrema) holds
    # neutral memory directions, its D_KY is an integer (docs/width_disorder: 1.0, 2.0 or 3.0)
    system = ForcedOscillator(build_operator("preisach-gauss"), 4.0)
    transient, t_end = 160 * TWO_PI, (160 + 4000) * TWO_PI
    section: list[np.ndarray] = []
    dim = attractor_dimension(
        system, t_end, transient, observer=lambda s: section.append(s.sample[:2])
    )
    assert dim.source == MEMORY_FROZEN and dim.neutral_memory
    assert dim.frozen.zeroed_mean > 1  # extrema survived whole periods
    assert dim.kaplan_yorke == kaplan_yorke_dimension(dim.frozen.exponents)
    assert dim.kaplan_yorke_full_space == dim.spectrum.kaplan_yorke
    bc = box_counting_dimension(np.asarray(section[:-1]), max_fill=0.1, min_boxes=8.0)
    # tolerance from the measured spreads: D_BC of 4000-point sections of this run length from
    # three starts (q0 = -1, 0.41, -1.38) was 1.376, 1.370, 1.307 (sample std 0.038, larger
    # than the fit's stderr ~0.02, which misses the choice of the scaling region); D_KY's own
    # finite-time error (block jackknife) is ~0.006. Three combined standard deviations.
    tol = 3 * math.hypot(dim.kaplan_yorke_error, 0.038)
    print(dim, "D_BC", bc.dimension, "+-", bc.stderr, "tol", tol)
    assert 0.0 < dim.kaplan_yorke_error < 0.03
    assert abs(dim.kaplan_yorke - bc.dimension) <= tol
    # ... while the full-space value is refuted by the same measurement
    assert abs(dim.kaplan_yorke_full_space - bc.dimension) > tol


def test_paper_systems_keep_the_full_space_value():
    # erf play at C = 4: w is reset or dragged in every forcing period, never carried unchanged
    # through one (the exact probe of the frozen loop), so the full-space value stays, bit for
    # bit the one of lyapunov_spectrum; the two spectra agree within their errors anyway
    play = ForcedOscillator(build_operator("erf-play"), 4.0)
    transient, t_end = 160 * TWO_PI, 1160 * TWO_PI
    dim = attractor_dimension(play, t_end, transient)
    ref = lyapunov_spectrum(play, t_end, transient)
    assert dim.source == FULL_SPACE and not dim.neutral_memory
    assert dim.frozen.zeroed_mean == 0.0
    err = np.hypot(dim.frozen.errors, exponent_block_errors(dim.spectrum)[:2])
    assert np.all(np.abs(dim.frozen.exponents - ref.exponents[:2]) <= 2 * err)
    assert dim.kaplan_yorke == dim.kaplan_yorke_full_space == ref.kaplan_yorke
    np.testing.assert_array_equal(dim.exponents, ref.exponents)
    # dimers: no memory rows, no second run
    dimers = ForcedOscillator(build_operator("dimers", spins=200), 4.0)
    dim = attractor_dimension(dimers, 200.0, 20.0)
    ref = lyapunov_spectrum(dimers, 200.0, 20.0)
    assert dim.source == FULL_SPACE and dim.frozen is None
    assert dim.kaplan_yorke == ref.kaplan_yorke


def test_frozen_wagon_reports_the_attractor_value():
    # four plays; the widest (p = 6) is never reached by the period-1 orbit (|q| < 3): its wagon
    # is frozen, an exponent 0 in the full spectrum, which D_KY counts (1.0); the attractor is a
    # fixed point of the section, dimension 0
    op = PrandtlIshlinskii([0.5, 1.0, 2.0, 6.0], [0.4, 0.3, 0.2, 0.1])
    system = ForcedOscillator(op, 0.8)
    section: list[np.ndarray] = []
    dim = attractor_dimension(
        system, 460 * TWO_PI, 160 * TWO_PI, observer=lambda s: section.append(s.sample[:2])
    )
    pts = np.asarray(section[-20:])
    assert smallest_period(pts, 1e-8) == 1
    lam = dim.spectrum.exponents
    assert np.isfinite(lam[:3]).all() and abs(lam[0]) < 1e-6  # the wagon's neutral exponent
    # 1 + λ_w/|λ_2| with λ_w ~ 1e-8 (the QR average's B/t term of the neutral slot)
    assert dim.kaplan_yorke_full_space == pytest.approx(1.0, abs=1e-6)
    assert dim.source == MEMORY_FROZEN and dim.kaplan_yorke == 0.0
    assert np.all(dim.frozen.exponents < 0.0)


def _spectrum(exponents, tangent_space=("q", "v", "M1", "m1")) -> LyapunovResult:
    lam = np.asarray(exponents, dtype=float)
    return LyapunovResult(
        exponents=lam,
        tangent_space=tuple(tangent_space),
        history_t=np.zeros(0),
        history=np.zeros((0, lam.size)),
        n_switches=0,
        t_end=100.0,
        transient=0.0,
        kaplan_yorke=kaplan_yorke_dimension(lam),
        final=None,
    )


def _frozen(exponents, errors=(0.002, 0.004), zeroed=1.0) -> MemoryFrozenResult:
    return MemoryFrozenResult(
        exponents=np.asarray(exponents, dtype=float),
        errors=np.asarray(errors, dtype=float),
        kaplan_yorke_error=0.01,
        projection_periods=1,
        zeroed_mean=zeroed,
        t_end=100.0,
        transient=0.0,
    )


def test_neutral_memory_is_memory_carried_through_whole_intervals():
    assert has_neutral_memory(_frozen([0.077, -0.19], zeroed=0.25))
    assert not has_neutral_memory(_frozen([0.077, -0.19], zeroed=0.0))
    with pytest.raises(TypeError, match="frozen must be a MemoryFrozenResult"):
        has_neutral_memory(_spectrum([0.077, -0.19]))


def test_attractor_dimension_checks_a_given_spectrum():
    system = ForcedOscillator(build_operator("erf-play"), 4.0)
    spec = lyapunov_spectrum(system, 40 * TWO_PI, 10 * TWO_PI)
    with pytest.raises(ValueError, match=r"spectrum averages over"):
        attractor_dimension(system, 50 * TWO_PI, 10 * TWO_PI, spectrum=spec)
    with pytest.raises(ValueError, match="include_phase"):
        attractor_dimension(system, 40 * TWO_PI, 10 * TWO_PI, include_phase=True, spectrum=spec)
    with pytest.raises(ValueError, match="observer"):
        attractor_dimension(
            system, 40 * TWO_PI, 10 * TWO_PI, spectrum=spec, observer=lambda s: None
        )
    # given or computed, the same answer (the frozen run starts from the same state)
    given = attractor_dimension(system, 40 * TWO_PI, 10 * TWO_PI, spectrum=spec)
    assert given.kaplan_yorke == spec.kaplan_yorke and given.source == FULL_SPACE
    # a window shorter than one projection interval cannot be tested: said so
    short = attractor_dimension(system, 10 * TWO_PI + 1.0, 10 * TWO_PI)
    assert short.source == UNTESTED and short.frozen is None
    assert "too short" in short.explanation


def test_memory_frozen_result_is_a_frozen_result_object():
    fr = _frozen([0.08, -0.2])
    assert fr.kaplan_yorke == pytest.approx(1.4, abs=1e-15)  # 1 + 0.08/0.2
    assert fr.max_exponent == 0.08
    with pytest.raises(dataclasses.FrozenInstanceError):
        fr.zeroed_mean = 0.0
    text = repr(fr)
    assert "kaplan_yorke=1.4000" in text and "0.08" in text and "zeroed_mean=1" in text


def test_kaplan_yorke_block_error_is_the_delta_method_to_first_order():
    # equal blocks with small scatter: the jackknife of D = 1 + λ1/|λ2| equals the delta
    # method sqrt(gᵀ Σ g / B) (g the gradient, Σ the covariance of the block rates) up to
    # second order in the scatter (~1 % here)
    rng = np.random.default_rng(5)
    n_blocks, per_block, t0 = 10, 4, 3.0
    rates = np.column_stack(
        [0.08 + 0.001 * rng.standard_normal(n_blocks), -0.2 + 0.002 * rng.standard_normal(n_blocks)]
    )
    steps = np.repeat(rates, per_block, axis=0) / per_block  # unit time per step
    t = t0 + np.arange(1, n_blocks * per_block + 1, dtype=float) / per_block
    sums = np.cumsum(steps, axis=0)
    hist = sums / (t - t0)[:, None]
    res = LyapunovResult(
        exponents=hist[-1].copy(),
        tangent_space=("q", "v"),
        history_t=t,
        history=hist,
        n_switches=0,
        t_end=float(t[-1]),
        transient=t0,
        kaplan_yorke=kaplan_yorke_dimension(hist[-1]),
        final=None,
    )
    lam1, lam2 = rates.mean(axis=0)
    g = np.array([1.0 / -lam2, lam1 / lam2**2])
    delta = math.sqrt(g @ np.cov(rates.T) @ g / n_blocks)
    assert kaplan_yorke_block_error(res, n_blocks) == pytest.approx(delta, rel=0.05)
    # a -inf exponent stays -inf in every batch (the play's w)
    res_inf = dataclasses.replace(
        res,
        exponents=np.append(res.exponents, -np.inf),
        history=np.column_stack([hist, np.full(hist.shape[0], -np.inf)]),
    )
    assert kaplan_yorke_block_error(res_inf, n_blocks) == pytest.approx(delta, rel=0.05)
