"""Tabulated play shapes (hysteresis.shape_table) on the compiled play-limit kernel.

Truths: the closed-form erf kernel (a tabulated erf must reproduce it within the table's
verified error, propagated with a sensitivity measured in the same test), the generic
``solve_ivp`` engine integrating the exact ``tanh`` (through a subclass without a compiled
description), and the decoupled oscillator (``C = 0``: exponents ``−ζ``).
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from scipy.special import erf

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import GeneralizedPlay
from hysteresis.play import CompiledPlay, ErfShape, ErfShapeDerivative
from hysteresis.shape_table import SHAPE_TABLE_RTOL, ShapeTableError, tabulate_shape
from oscillators.engines import ContinuousEngine, PlayEngine
from oscillators.system import ForcedOscillator

ZETA = 0.05
TIGHT = {"rtol": 1e-12, "atol": 1e-12}


def tanh_slope(w):
    # cosh overflows beyond |w| ~ 710, where the slope is 0 in float64 anyway
    return 1.0 / np.cosh(np.clip(np.asarray(w), -350.0, 350.0)) ** 2


def _tanh_play(width=2.0):
    return GeneralizedPlay(width, np.tanh, tanh_slope, name="tanh")


class _GenericOnly(GeneralizedPlay):
    """The same shape without a compiled description: the generic continuous engine."""

    def compiled_play(self):
        return None


def test_shape_table_error_bound_holds_on_a_dense_probe():
    op = _tanh_play()
    table = op.shape_table()
    assert table is op.shape_table()  # built once
    assert table.tolerance == pytest.approx(SHAPE_TABLE_RTOL * 2.0)
    assert table.error <= table.tolerance
    # beyond the verification points (7 per interval) and beyond the knots (saturation)
    rng = np.random.default_rng(4)
    w = np.concatenate([rng.uniform(-30.0, 30.0, 200_000), [-1e300, 1e300, 0.0]])
    value, slope = table.evaluate(w)
    assert np.max(np.abs(value - np.tanh(w))) <= table.tolerance
    # slope: the cubic Hermite bound √3 h³ max|f⁗|/216 with max|tanh⁗| < 4.1 (< 1e-8 here)
    bound = math.sqrt(3.0) * table.step**3 * 4.1 / 216.0
    assert np.max(np.abs(slope - tanh_slope(w))) <= bound + 1e-12
    assert table.knots < 10_000  # a few thousand knots for 1e-10


def test_shape_table_refuses_what_it_cannot_tabulate():
    with pytest.raises(ShapeTableError, match="saturating"):
        tabulate_shape(lambda w: w, np.ones_like, (-np.inf, np.inf))
    # arctan saturates algebraically: 1e-10 of its range needs |w| ~ 3e9, far too many knots
    slow = GeneralizedPlay(1.0, np.arctan, lambda w: 1 / (1 + np.asarray(w) ** 2))
    with pytest.raises(ShapeTableError, match="knots"):
        slow.shape_table()
    assert slow.compiled_play() is None
    assert ForcedOscillator(slow, 1.0, ZETA, 1.0).engine_class is ContinuousEngine


def test_tabulated_erf_reproduces_the_erf_kernel_within_the_bound():
    coupling, width, spread = 2.0, 2.0, 1.0
    exact = ForcedOscillator(GeneralizedPlay.erf(width, spread), coupling, ZETA, 1.0)
    tab_op = GeneralizedPlay(width, ErfShape(spread), ErfShapeDerivative(spread))
    tabulated = ForcedOscillator(tab_op, coupling, ZETA, 1.0)
    assert tabulated.engine_class is PlayEngine and tab_op.compiled_play().shape == "table"
    ref = exact.poincare_section(11)
    sec = tabulated.poincare_section(11)
    # first-order propagation: a force perturbation of size C·ε moves the section by at most
    # A·C·ε, with the gain A measured here by perturbing the spread (a known change of the
    # shape); factor 4 because the table's error has another profile than that perturbation
    eta = 1e-7
    moved = ForcedOscillator(GeneralizedPlay.erf(width, spread * (1 + eta)), coupling, ZETA, 1.0)
    alt = moved.poincare_section(11)
    w = np.linspace(-10.0, 10.0, 200_001)
    df = np.max(
        np.abs(erf(w / (math.sqrt(2) * spread * (1 + eta))) - erf(w / (math.sqrt(2) * spread)))
    )
    gain = max(np.max(np.abs(alt.q - ref.q)), np.max(np.abs(alt.v - ref.v))) / (coupling * df)
    tol = 4.0 * gain * coupling * tab_op.shape_table().error
    assert tol < 1e-6  # the bound is informative
    np.testing.assert_allclose(sec.q, ref.q, rtol=0, atol=tol)
    np.testing.assert_allclose(sec.v, ref.v, rtol=0, atol=tol)
    np.testing.assert_allclose(sec.w, ref.w, rtol=0, atol=tol)
    assert sec.n_switches == ref.n_switches


def test_compiled_tanh_play_matches_the_generic_engine():
    coupling = 2.0
    compiled = ForcedOscillator(_tanh_play(), coupling, ZETA, 1.0)
    generic = ForcedOscillator(_GenericOnly(2.0, np.tanh, tanh_slope), coupling, ZETA, 1.0)
    assert compiled.engine_class is PlayEngine and generic.engine_class is ContinuousEngine
    sec = compiled.poincare_section(11)
    ref = generic.poincare_section(11, engine_options=TIGHT)
    # the table's force error C·2e-10 and the generic engine's rtol 1e-12, grown over 10
    # periods: the 1e-8 (measured: 6e-10)
    for name in ("q", "v", "w", "M"):
        np.testing.assert_allclose(getattr(sec, name), getattr(ref, name), rtol=0, atol=1e-8)
    # event records: the same wall hits (kind +1) at the same times; the kernel records the
    # reversals on a wall (kind -1), the generic engine also those inside the play (v = 0
    # there changes its branch), so the kernel's reversals are a subset of the generic ones
    t_end = 10 * compiled.period
    ev = compiled.trajectory(t_end, sample_dt=compiled.period).events
    ev_ref = generic.trajectory(t_end, sample_dt=generic.period, engine_options=TIGHT).events
    hits, hits_ref = ev["time"][ev["kind"] == 1], ev_ref["time"][ev_ref["kind"] == 1]
    assert hits.size == hits_ref.size > 10
    np.testing.assert_allclose(hits, hits_ref, rtol=0, atol=1e-8)
    rev, rev_ref = ev["time"][ev["kind"] == -1], ev_ref["time"][ev_ref["kind"] == -1]
    assert np.all(np.min(np.abs(rev[:, None] - rev_ref[None, :]), axis=1) < 1e-8)


def test_zero_coupling_exponents_are_minus_zeta():
    system = ForcedOscillator(_tanh_play(), 0.0, ZETA, 1.0)
    assert system.engine_class is PlayEngine
    res = lyapunov_spectrum(system, 300.0)
    exps = res.exponents
    assert res.tangent_space == ("q", "v", "w")
    # the decoupled oscillator's complex pair -ζ ± iω_d: both exponents -ζ, with the
    # O(1/T) = O(3e-3) bias of a finite run; w reset at every wall hit: -inf
    np.testing.assert_allclose(exps[:2], -ZETA, atol=0.01)
    assert exps[2] == -np.inf


def test_tabulated_play_pickles():
    op = _tanh_play()
    spec = op.compiled_play()
    assert isinstance(spec, CompiledPlay) and spec.shape == "table"
    back = pickle.loads(pickle.dumps(op))
    assert "_shape_table" not in back.__dict__  # rebuilt, not pickled
    again = back.compiled_play()
    np.testing.assert_array_equal(again.table.values, spec.table.values)
    spec_back = pickle.loads(pickle.dumps(spec))
    np.testing.assert_array_equal(spec_back.table.slopes, spec.table.slopes)
    a = ForcedOscillator(op, 2.0, ZETA, 1.0).poincare_section(3)
    b = ForcedOscillator(back, 2.0, ZETA, 1.0).poincare_section(3)
    np.testing.assert_array_equal(a.q, b.q)
