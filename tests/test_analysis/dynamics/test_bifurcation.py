"""Bifurcation diagram of one dimer (paper fig:bif_0): grazing at C = 9 and period adding below.

Independent truth: on the sheet M = −1 the oscillator is linear, q'' + 0.1 q' + q = cos t − C,
with the periodic solution q = −C + A sin t, A = 1/(2ζ) = 10 (Ω = 1): the section point is
(q, v) = (−C, 10) and both exponents are −ζ. The orbit touches the dimer's upper threshold
α = J − b1 = 1 when −C + A = α, i.e. at the grazing coupling C_g = A − α = 9. Below C_g the
paper reports a period-adding cascade.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.bifurcation import bifurcation_diagram, distinct_points, orbit_period

ZETA = 0.05
AMPLITUDE = 1.0 / (2.0 * ZETA)  # resonance amplitude at Ω = 1
ALPHA = 2.0 - 1.0  # J − b1
C_GRAZING = AMPLITUDE - ALPHA  # = 9


def _diagram(couplings, n_periods, transient, lyapunov_t_end):
    from hysteresis.spin_dimers import SpinDimerEnsemble
    from oscillators import ForcedOscillator

    dimer = SpinDimerEnsemble(fields=[[1.0, -1.0]], spin_coupling=2.0)
    return bifurcation_diagram(
        lambda c: ForcedOscillator(dimer, c, damping_ratio=ZETA, frequency=1.0),
        couplings,
        n_periods,
        transient,
        lyapunov=True,
        lyapunov_t_end=lyapunov_t_end,
        progress=False,
    )


def _plateaus(values, periods):
    """(period, first C, length) of runs of equal positive period along the sweep."""
    runs = []
    for c, p in zip(values, periods, strict=True):
        if runs and runs[-1][0] == p:
            runs[-1][2] += 1
        else:
            runs.append([p, c, 1])
    return [(p, c, n) for p, c, n in runs if p > 0 and n >= 2]


def _check_grazing_and_adding(d, min_plateaus):
    c = d.values
    periods = d.periods(1e-6)
    above = c > C_GRAZING + 1e-9
    # above grazing: the closed-form period-1 orbit on the sheet M = -1
    assert np.all(periods[above] == 1)
    assert np.allclose(d.q[above], -c[above, None], atol=1e-6)
    assert np.allclose(d.v[above], AMPLITUDE, atol=1e-6)
    assert np.all(d.M[above] == -1.0)
    assert np.allclose(d.exponents[above], -ZETA, atol=2e-3)
    # just below grazing the orbit switches the dimer: long periods, both sheets visited
    first_below = np.nonzero(~above)[0][1]  # skip C = 9 itself (the grazing orbit)
    assert distinct_points(d.q[first_below], d.v[first_below]) > 10
    assert set(np.unique(d.M[first_below])) == {-1.0, 1.0}
    # period adding: the periods of the primary windows grow as C approaches C_g from below,
    # by one (or two, where a narrow window of the intermediate period falls between grid
    # points) per window; narrow combination windows (period ~ sum of two neighbours, e.g. 41
    # between 14 and 13) sit between them and are set aside
    plateaus = [p for p, c0, _ in _plateaus(c, periods) if p > 1 and c0 < C_GRAZING - 0.3]
    primary = []
    for p in plateaus:
        if not primary or p < primary[-1]:
            primary.append(p)
    assert len(primary) >= min_plateaus
    assert len(plateaus) - len(primary) <= len(plateaus) // 3
    steps = -np.diff(primary)
    assert np.all((steps == 1) | (steps == 2)), primary
    on_windows = np.isin(periods, plateaus)
    assert np.all(d.max_exponent[on_windows] < 0)


def test_period_adding_below_grazing_fast():
    couplings = np.round(np.arange(9.5, 6.0, -0.05), 6)
    d = _diagram(couplings, n_periods=80, transient=300, lyapunov_t_end=1000.0)
    _check_grazing_and_adding(d, min_plateaus=6)


@pytest.mark.slow
def test_bifurcation_diagram_full_range():
    # the paper's sweep, C from 10 down to 0.5: the period-adding cascade below C = 9 (stable
    # orbits down to C = 6) and chaotic windows (λ_max > 0) only at smaller coupling
    couplings = np.round(np.arange(10.0, 0.5, -0.01), 6)
    d = _diagram(couplings, n_periods=120, transient=300, lyapunov_t_end=4000.0)
    sub = d.values >= 6.0
    from analysis.dynamics.bifurcation import BifurcationDiagram

    upper = BifurcationDiagram(
        d.parameter,
        d.values[sub],
        d.q[sub],
        d.v[sub],
        d.M[sub],
        d.max_exponent[sub],
        d.exponents[sub],
        d.final_states,
    )
    _check_grazing_and_adding(upper, min_plateaus=10)
    chaotic = d.values[d.max_exponent > 0.005]
    assert chaotic.size > 0 and chaotic.max() < 6.0


def test_distinct_points_and_orbit_period():
    q = np.tile([0.1, 0.5, -0.2], 10) + 1e-9
    v = np.tile([1.0, 2.0, 3.0], 10)
    assert distinct_points(q, v, 1e-6) == 3
    assert orbit_period(q, v, 1e-6) == 3
    assert distinct_points(q, None, 1e-6) == 3
    # two points equal in q but not in v are distinct
    assert distinct_points([0.0, 0.0], [0.0, 1.0], 1e-6) == 2
    rng = np.random.default_rng(0)
    x = rng.uniform(size=50)
    assert distinct_points(x, None, 1e-9) == 50 and orbit_period(x, None, 1e-9) == 0


def test_continuation_passes_the_state_on():
    # without transient the first section point is the start: with continuation the second
    # value starts at the first value's final state, without it at (q0, v0) = (-1, 0.1)
    from hysteresis.spin_dimers import SpinDimerEnsemble
    from oscillators import ForcedOscillator

    dimer = SpinDimerEnsemble(fields=[[1.0, -1.0]], spin_coupling=2.0)
    kw = dict(n_periods=5, transient_periods=0, lyapunov=False, progress=False)
    cont = bifurcation_diagram(lambda c: ForcedOscillator(dimer, c), [9.5, 9.4], **kw)
    assert cont.q[1, 0] == cont.final_states[0].q and cont.v[1, 0] == cont.final_states[0].v
    assert cont.q[1, 0] != -1.0
    fresh = bifurcation_diagram(
        lambda c: ForcedOscillator(dimer, c), [9.5, 9.4], continuation=False, **kw
    )
    assert fresh.q[1, 0] == -1.0 and fresh.v[1, 0] == 0.1
    assert np.all(np.isnan(fresh.max_exponent))
