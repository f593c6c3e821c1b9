"""A Gaussian width law narrower than the compiled engine's fixed step resolves runs on the
generic adaptive engine, and says so (it was 1e-5 off the erf-play limit on the compiled one)."""

from __future__ import annotations

import numpy as np
import pytest

from hysteresis import ContinuousPreisachModel, GeneralizedPlay
from hysteresis.preisach.continuous import MIN_COMPILED_WIDTH_SPREAD
from oscillators import ForcedOscillator
from oscillators.engines import CompiledContinuousEngine, ContinuousEngine, GenericEngineWarning


def test_narrow_width_law_runs_adaptive_and_approaches_the_erf_limit():
    narrow = ContinuousPreisachModel.gaussian(2.0, 1.0, 1e-6)
    with pytest.warns(GenericEngineWarning, match="width_spread 1e-06"):
        system = ForcedOscillator(narrow, coupling=1.0)
    assert system.engine_class is ContinuousEngine
    limit = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), coupling=1.0)
    # the model differs from its σ_r → 0 limit by O(σ_r²) ~ 1e-12 in E; what remains is the
    # integrators' error over ~20 events at rtol 1e-11 (measured 1e-8)
    gap = np.max(np.abs(system.trajectory(30.0).q - limit.trajectory(30.0).q))
    assert gap < 1e-7


def test_resolved_width_laws_stay_compiled():
    wide = ContinuousPreisachModel.gaussian(2.0, 1.0, MIN_COMPILED_WIDTH_SPREAD)
    assert wide.uncompiled_reason is None
    assert ForcedOscillator(wide, coupling=1.0).engine_class is CompiledContinuousEngine


def test_stiff_damping_is_refused_by_the_compiled_continuous_engine_in_one_line():
    """ζ = 1e6 (the oscillator's limit) would cost ~2e8 explicit RK8 steps per period: refused
    when the system is built, naming the limit, instead of hanging."""
    from hysteresis import PrandtlIshlinskii

    pi = PrandtlIshlinskii([0.0, 1.0], [0.3, 0.3])
    with pytest.raises(ValueError, match=r"damping_ratio must be <= 10000") as info:
        ForcedOscillator(pi, coupling=1.0, damping_ratio=1e6)
    assert "\n" not in str(info.value)
    ForcedOscillator(pi, coupling=1.0, damping_ratio=1e4)  # the limit itself is accepted
