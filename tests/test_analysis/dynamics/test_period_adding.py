"""The period-adding detector on hand-made sweeps whose onset, windows and steps are known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.period_adding import period_adding


def _grid(n: int) -> np.ndarray:
    """n couplings stepped down from 9.5 by 0.1 (the sweep order of fig:bif_0)."""
    return 9.5 - 0.1 * np.arange(n)


def test_a_clean_cascade():
    # period 1 (no switch) at 9.5 .. 9.2, unresolved right below, then 31, 31, 29, 29, ...
    periods = [1, 1, 1, 1, 0, 0, 31, 31, 29, 29, 27, 27, 25, 25]
    cs = _grid(len(periods))
    m = period_adding(cs, periods)
    assert m.onset == pytest.approx(0.5 * (9.2 + 9.1))
    assert m.no_switch_end == pytest.approx(9.2)
    assert m.grid_step == pytest.approx(0.1)
    assert [p for _, p in m.below] == periods[4:]
    assert m.below[0][0] == pytest.approx(9.1)
    assert m.windows == ((0, 2), (31, 2), (29, 2), (27, 2), (25, 2))
    assert m.wide == (31, 29, 27, 25)
    assert m.narrow == ()
    assert m.steps == (-2, -2, -2)
    assert m.long_near_onset


def test_narrow_windows_are_told_from_wide_ones():
    periods = [1, 1, 0, 45, 31, 31, 3, 29, 29, 30, 27, 27]
    m = period_adding(_grid(len(periods)), periods)
    assert m.wide == (31, 29, 27)
    assert m.narrow == (45, 3, 30)
    assert m.steps == (-2, -2)
    # wider windows: with min_width 3 none is wide
    assert period_adding(_grid(len(periods)), periods, min_width=3).wide == ()


def test_a_sweep_that_is_not_period_adding():
    # windows of growing period away from the onset, short periods next to it
    periods = [1, 1, 3, 3, 5, 5, 7, 7, 9, 9]
    m = period_adding(_grid(len(periods)), periods)
    assert m.wide == (3, 5, 7, 9)
    assert m.steps == (2, 2, 2)
    assert not m.long_near_onset  # 3, 3, 5, 5, 7: none unresolved nor >= 20
    assert period_adding(_grid(len(periods)), periods, long_period=7).long_near_onset


def test_long_near_onset_looks_at_the_first_values_below_the_onset_only():
    periods = [1, 3, 3, 5, 5, 7, 25, 25]  # the long period is the 6th value below the onset
    assert not period_adding(_grid(8), periods).long_near_onset
    assert period_adding(_grid(8), periods, near=6).long_near_onset


def test_no_onset():
    # never leaves the period-1 orbit: no onset, nothing below it
    m = period_adding(_grid(6), [1] * 6)
    assert math.isnan(m.onset)
    assert m.no_switch_end == pytest.approx(9.0)
    assert m.below == () and m.windows == () and m.wide == () and m.steps == ()
    assert not m.long_near_onset
    # starts off the orbit: no value above the onset, so none can be placed; all is "below"
    m = period_adding(_grid(6), [0, 0, 5, 5, 1, 1])
    assert math.isnan(m.onset)
    assert len(m.below) == 6 and m.wide == (5,)
    assert m.no_switch_end == pytest.approx(9.0)  # the last value with period 1, anywhere
    # an empty sweep and a single value
    empty = period_adding([], [])
    assert math.isnan(empty.onset) and math.isnan(empty.no_switch_end)
    assert empty.grid_step == math.inf
    assert period_adding([9.0], [1]).grid_step == math.inf


def test_mismatched_inputs_are_refused():
    with pytest.raises(ValueError, match="couplings and periods"):
        period_adding([9.0, 8.9], [1])
