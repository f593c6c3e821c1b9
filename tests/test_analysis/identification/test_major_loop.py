"""Hysteresis parameters from FORC data against closed forms: a Preisach ridge
``N(s; 0, R²) δ(r − p/2)`` (the erf generalized play) has ``M_s = 1``,
``M_rs = 2Φ(p/2R) − 1`` and ``B_c = B_cr = p/2`` (module docstring of major_loop.py)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ndtr

from analysis.identification import measure_reversal_curves
from analysis.identification.major_loop import hysteresis_parameters
from hysteresis import GeneralizedPlay

P, R = 2.0, 0.5
STEP = 0.02


@pytest.mark.parametrize("convention", ["pike", "mayergoyz"])
def test_erf_play_closed_forms(convention):
    grid = np.arange(-5.0, 5.0 + STEP / 2, STEP)  # saturated within 1e-12 beyond |H| = 4
    curves = measure_reversal_curves(
        GeneralizedPlay.erf(P, R), grid, convention=convention, saturation=6.0
    )
    hp = hysteresis_parameters(curves)
    # linear interpolation between nodes STEP apart: error <= STEP²/8 · max|M''|, M'' of
    # 2Φ((H ± p/2)/R) at most 2φ(1)/R² ≈ 1.94 → 1e-4 in moment; crossings through slope ≥ 1/R·φ(0)
    assert hp.ms == pytest.approx(1.0, abs=1e-10)
    assert hp.mrs == pytest.approx(2.0 * ndtr(P / (2 * R)) - 1.0, abs=2e-4)
    assert hp.bc == pytest.approx(P / 2, abs=2e-4)
    assert hp.bcr == pytest.approx(P / 2, abs=2e-4)
    assert hp.bcr_bc == pytest.approx(1.0, abs=1e-3)


def test_coarse_remanence_unreachable_and_errors():
    # curves that never return to H = 0: no B_cr; one curve: an error
    grid = np.arange(-5.0, -3.0, 0.5)
    curves = measure_reversal_curves(
        GeneralizedPlay.erf(P, R), grid, convention="pike", saturation=6.0
    )
    assert hysteresis_parameters(curves).bcr is None
    with pytest.raises(ValueError, match="at least 2 curves"):
        hysteresis_parameters(
            measure_reversal_curves(
                GeneralizedPlay.erf(P, R), [0.0], convention="pike", saturation=6.0
            )
        )
    with pytest.raises(TypeError, match="ReversalCurves"):
        hysteresis_parameters([1, 2])


def test_summary_rounding():
    from analysis.cli._identify_batch import rounded

    assert rounded(4.358170557778533e-06, 2.7e-08) == 4.358e-06  # to the se's 2nd digit
    assert rounded(30.012749999, decimals=2) == 30.01
    assert rounded(1.8609108659932419e-07) == 1.861e-07
    assert rounded("") == "" and rounded(None) is None
