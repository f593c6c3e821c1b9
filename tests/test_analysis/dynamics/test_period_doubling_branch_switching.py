"""Branch switching at a period doubling (:func:`period_doubled_orbit`) on the paper's
period-5 window (C = 3.80–3.88, ζ = 0.05, Ω = 1): the erf play, and the continuous Gaussian
Preisach model close to it (σ_r = 0.05), where it failed — its staircase points are NaN-padded
(the orbit's own extrema vary along it), so the check "the two halves differ" read NaN and
never passed, and the doubled orbit lies ~0.01 from the period-5 one at the default offset,
out of reach of the old single amplitude 1e-3 (Newton went back to the period-5 orbit).

Independent checks of the period-10 orbit: it closes after 10 periods and not after 5 by
direct integration (not Newton's residual), and its distance from the period-5 orbit grows
like sqrt(|C − C_pd|) (the flip normal form ``y → −(1 + a·δ)y + c·y³``): quadrupling the
offset doubles the halves' separation (to O(δ), relative)."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit, period_doubled_orbit
from analysis.dynamics.periodic_orbits import OrbitNotFoundError, find_periodic_orbit
from analysis.experiments.models import build_operator
from hysteresis import ContinuousPreisachModel
from oscillators import ForcedOscillator


def _period_doubling(operator):
    system = ForcedOscillator(operator, 3.85)
    orbit = find_periodic_orbit(system)
    assert orbit.period == 5
    branch = continue_orbit(system, orbit, 3.85, 3.90, step=0.005, max_points=200, symmetric=True)
    pds = [e for e in branch.events if e.kind == "period-doubling"]
    assert len(pds) == 1, [(e.kind, e.parameter) for e in branch.events]
    pd = pds[0]
    assert 3.80 < pd.parameter < 3.81
    assert abs(np.min(pd.point.active_multipliers.real) + 1.0) < 1e-3
    return system, pd


def _separation(orbit) -> float:
    return float(np.max(np.abs(orbit.points[:5, :2] - orbit.points[5:, :2])))


def _closes(system, orbit) -> tuple[float, float]:
    """``|x(5T) − x(0)|`` and ``|x(10T) − x(0)|`` in (q, v) by direct integration."""
    eng = system.engine(orbit.start)
    out = []
    for n in (5, 10):
        eng.advance(np.array([n * system.period]))
        s = eng.state()
        out.append(max(abs(s.q - orbit.start.q), abs(s.v - orbit.start.v)))
    return out[0], out[1]


def _check_doubled(system, pd):
    offset = 1e-5
    lam, doubled = period_doubled_orbit(system, pd, offset=offset)
    assert doubled.period == 10 and abs(lam - pd.parameter) == pytest.approx(offset)
    # a flip of a stable period-5 orbit: the period-10 multiplier near +1 (μ_5² -> 1)
    assert abs(doubled.max_abs_multiplier - 1.0) < 0.1
    at = ForcedOscillator(system.operator, lam)
    five, ten = _closes(at, doubled)
    # integration error ~1e-9 over 10 periods; the halves differ by ~1e-2
    assert ten < 1e-6 and five > 1e-3, (five, ten)
    first = float(np.max(np.abs(doubled.points[5, :2] - doubled.points[0, :2])))
    assert five == pytest.approx(first, rel=1e-3, abs=1e-6)
    # sqrt scaling: 4 × the offset (on the side found) doubles the separation
    lam4, doubled4 = period_doubled_orbit(system, pd, offset=4 * offset)
    assert np.sign(lam4 - pd.parameter) == np.sign(lam - pd.parameter)
    ratio = _separation(doubled4) / _separation(doubled)
    assert ratio == pytest.approx(2.0, rel=0.02), ratio


def test_erf_play_period_doubling_gives_the_period_10_orbit():
    system, pd = _period_doubling(build_operator("erf-play"))
    _check_doubled(system, pd)


@pytest.mark.slow
def test_gaussian_preisach_period_doubling_gives_the_period_10_orbit():
    # ~40 s: the staircase continuation over the window
    system, pd = _period_doubling(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.05))
    _check_doubled(system, pd)


def test_failure_says_what_newton_found():
    # amplitudes far below the doubled orbit's size (1e-2): every start goes back to the
    # period-5 orbit, and the error says so in one sentence
    system, pd = _period_doubling(build_operator("erf-play"))
    with pytest.raises(OrbitNotFoundError, match=r"converged back to the period-5 orbit") as e:
        period_doubled_orbit(system, pd, offset=1e-5, amplitude=1e-9)
    assert "\n" not in str(e.value)
