"""The compiled Bouc–Wen and Jiles–Atherton right-hand sides against independent truths: the
Langevin function against 50-digit decimal arithmetic, the output map against its defining
equation, and every analytic partial against central differences."""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest

from hysteresis import JilesAtherton
from hysteresis._duhem_kernels import (
    DELTA_M_NATURAL,
    bouc_wen_slope,
    jiles_atherton_magnetization,
    jiles_atherton_margins,
    jiles_atherton_rhs,
    jiles_atherton_slope,
    jiles_atherton_slope_bound,
    langevin,
)

STEEL = (1.6e6, 1100.0, 400.0, 0.2, 1.6e-3)  # ms, a, k, c, alpha (SI, a transformer steel)
UNIT = (1.0, 0.5, 0.4, 0.2, 0.3)


def _decimal_langevin(x: float) -> tuple[float, float, float]:
    """``L, L', L''`` in 100-digit arithmetic: ``coth`` from ``exp``, the derivatives by
    differences with step 1e-15 (truncation ~1e-30, rounding ~1e-100/1e-30)."""
    with localcontext() as ctx:
        ctx.prec = 100

        def lang(t):
            e = (2 * t).exp()
            return (e + 1) / (e - 1) - 1 / t

        t, h = Decimal(x), Decimal("1e-15")
        lo, mid, hi = lang(t - h), lang(t), lang(t + h)
        return float(mid), float((hi - lo) / (2 * h)), float((hi - 2 * mid + lo) / (h * h))


@pytest.mark.parametrize("x", [1e-6, 1e-3, 0.3, 0.999, 1.0, 1.001, 3.0, 30.0, -0.7, -2.0])
def test_langevin_matches_high_precision(x):
    for got, exact in zip(langevin(x), _decimal_langevin(x), strict=True):
        # series below 1 and closed form above: a few ulps (module docstring: <= 15ε in L'')
        assert got == pytest.approx(exact, rel=2e-14, abs=1e-300)


def test_langevin_far_out_does_not_overflow():
    value, slope, curvature = langevin(800.0)
    assert value == pytest.approx(1.0 - 1.0 / 800.0, rel=1e-15)
    assert slope == pytest.approx(1.0 / 800.0**2, rel=1e-15)
    assert curvature == pytest.approx(-2.0 / 800.0**3, rel=1e-15)


@pytest.mark.parametrize("params", [STEEL, UNIT])
@pytest.mark.parametrize("point", [(0.1, 0.2), (-0.8, -0.9), (0.3, 0.7), (2.0, -0.3)])
def test_magnetization_solves_its_equation_with_exact_partials(params, point):
    ms, a, _, c, alpha = params
    h, m_irr = point[0] * a * 3.0, point[1] * ms
    m, m_h, m_i = jiles_atherton_magnetization(h, m_irr, ms, a, c, alpha)
    x = (h + alpha * m) / a
    assert m == pytest.approx((1 - c) * m_irr + c * ms * (1 / math.tanh(x) - 1 / x), abs=1e-14 * ms)
    dh, di = 1e-5 * a, 1e-6 * ms  # central differences: truncation ~step², rounding ~ε/step
    fd_h = (
        jiles_atherton_magnetization(h + dh, m_irr, ms, a, c, alpha)[0]
        - jiles_atherton_magnetization(h - dh, m_irr, ms, a, c, alpha)[0]
    ) / (2 * dh)
    fd_i = (
        jiles_atherton_magnetization(h, m_irr + di, ms, a, c, alpha)[0]
        - jiles_atherton_magnetization(h, m_irr - di, ms, a, c, alpha)[0]
    ) / (2 * di)
    assert m_h == pytest.approx(fd_h, rel=1e-7, abs=1e-9 * ms / a)
    assert m_i == pytest.approx(fd_i, rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("params", [STEEL, UNIT])
@pytest.mark.parametrize(("field", "d"), [(0.1, 1.0), (-0.4, 1.0), (0.6, -1.0), (2.0, 1.0)])
def test_jiles_atherton_slope_partials_match_central_differences(params, field, d):
    ms, a, k, c, alpha = params
    h = field * a
    # M_irr lagging the anhysteretic curve by 5 % of ms (δ_M = 1, well-posed); c = 1 makes the
    # output map the anhysteretic magnetisation
    m_irr = jiles_atherton_magnetization(h, 0.0, ms, a, 1.0, alpha)[0] - d * 0.05 * ms
    g, g_h, g_i, ok = jiles_atherton_slope(h, m_irr, d, ms, a, k, c, alpha)
    assert ok and g > 0.0  # δ_M = 1 at these points (M_irr lags M_an)
    dh, di = 1e-5 * a, 1e-6 * ms
    fd_h = (
        jiles_atherton_slope(h + dh, m_irr, d, ms, a, k, c, alpha)[0]
        - jiles_atherton_slope(h - dh, m_irr, d, ms, a, k, c, alpha)[0]
    ) / (2 * dh)
    fd_i = (
        jiles_atherton_slope(h, m_irr + di, d, ms, a, k, c, alpha)[0]
        - jiles_atherton_slope(h, m_irr - di, d, ms, a, k, c, alpha)[0]
    ) / (2 * di)
    assert g_h == pytest.approx(fd_h, rel=1e-6)
    assert g_i == pytest.approx(fd_i, rel=1e-6)


def test_jiles_atherton_slope_formula_and_pole():
    """``g = χ_irr/(1 − αχ)`` written out with c = 0 (``M = M_irr``), and ``ok`` False past
    the pole ``α(M_an − M_irr)/k = 1``."""
    ms, a, k, alpha = 1.0, 1.0, 0.1, 0.2
    m_irr = -0.2  # α(M_an − M_irr)/k = 0.57
    x = (0.3 + alpha * m_irr) / a
    gap = (1 / math.tanh(x) - 1 / x) - m_irr
    g, _, _, ok = jiles_atherton_slope(0.3, m_irr, 1.0, ms, a, k, 0.0, alpha)
    assert ok and g == pytest.approx((gap / k) / (1 - alpha * gap / k), rel=1e-14)
    assert jiles_atherton_slope(0.3, -0.9, 1.0, ms, a, k, 0.0, alpha)[3] is False
    assert jiles_atherton_slope(0.3, m_irr, -1.0, ms, a, k, 0.0, alpha)[:3] == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("n", [1.0, 1.5, 3.0])
@pytest.mark.parametrize(("z", "d"), [(0.4, 1.0), (0.4, -1.0), (-0.7, 1.0), (-0.2, -1.0)])
def test_bouc_wen_slope_and_partial(n, z, d):
    A, beta, gamma = 1.0, 0.5, 0.3
    g, dg = bouc_wen_slope(z, d, A, beta, gamma, n)
    assert g == pytest.approx(A - abs(z) ** n * (beta * d * math.copysign(1, z) + gamma), rel=1e-15)
    step = 1e-6
    fd = (
        bouc_wen_slope(z + step, d, A, beta, gamma, n)[0]
        - bouc_wen_slope(z - step, d, A, beta, gamma, n)[0]
    ) / (2 * step)
    assert dg == pytest.approx(fd, rel=1e-8)
    # at the kink: one-sided, the side the branch enters (sign z := d)
    right = (bouc_wen_slope(d * step, d, A, beta, gamma, 1.0)[0] - A) / (d * step)
    assert bouc_wen_slope(0.0, d, A, beta, gamma, 1.0)[1] == pytest.approx(right, rel=1e-9)


@pytest.mark.parametrize("params", [STEEL, UNIT, (1.0, 0.2, 0.05, 0.9, 0.66)])
def test_one_solve_from_any_guess_gives_both_functions(params):
    """``jiles_atherton_rhs`` from any warm start (inside or outside ``[−ms, ms]``, NaN) is the
    output map and the slope: the root to a few ulps of ms (module docstring: Newton stopped
    at ``K·Δ² <= ε·ms``), the slope to the rounding of the gap it is proportional to."""
    ms, a, k, c, alpha = params
    # M carries the rounding of F, a few ε·ms/F' with F' >= D_min = 1 − αc·ms/(3a)
    d_min = 1.0 - alpha * c * ms / (3.0 * a)
    rng = np.random.default_rng(3)
    for _ in range(200):
        h, m_irr = rng.uniform(-4, 4) * a, rng.uniform(-0.95, 0.95) * ms
        d = float(rng.choice([-1.0, 1.0]))
        m, m_h, m_i = jiles_atherton_magnetization(h, m_irr, ms, a, c, alpha)
        slope = jiles_atherton_slope(h, m_irr, d, ms, a, k, c, alpha)
        for guess in (math.nan, m + rng.normal() * 0.1 * ms, 3.0 * ms, -ms):
            got = jiles_atherton_rhs(h, m_irr, d, DELTA_M_NATURAL, ms, a, k, c, alpha, guess)
            assert got[0] == pytest.approx(m, abs=8e-16 * ms / d_min)
            assert got[1:3] == pytest.approx((m_h, m_i), rel=1e-13 / d_min**2, abs=1e-15 * ms / a)
            assert got[6] == slope[3]
            if slope[3]:
                assert got[3:6] == pytest.approx(slope[:3], rel=1e-9, abs=1e-13 * ms / k / a)
        # δ_M imposed: 0 gives no slope; 1 the formula that holds where the gap is open
        assert jiles_atherton_rhs(h, m_irr, d, 0.0, ms, a, k, c, alpha, m)[3:6] == (0, 0, 0)
        gap = ms * langevin((h + alpha * m) / a)[0] - m_irr
        if d * gap > 0:
            on = jiles_atherton_rhs(h, m_irr, d, 1.0, ms, a, k, c, alpha, m)
            assert on[6] == slope[3] and (not on[6] or on[3] == pytest.approx(slope[0], rel=1e-9))


@pytest.mark.parametrize("params", [STEEL, UNIT])
@pytest.mark.parametrize(
    ("field", "d", "lag"), [(0.1, 1.0, 0.05), (-0.4, -1.0, 0.02), (1.5, 1.0, -0.03)]
)
def test_margins_formulas_and_partials(params, field, d, lag):
    """``G = d·(M_an − M_irr)`` and ``w = 1 − α((1−c)G/k + c·M_an')`` written out, partials
    against central differences."""
    ms, a, k, c, alpha = params
    h = field * a
    m_irr = jiles_atherton_magnetization(h, 0.0, ms, a, 1.0, alpha)[0] - d * lag * ms

    def margins(hh, mi):
        return jiles_atherton_margins(hh, mi, d, ms, a, k, c, alpha, math.nan)

    m, big_g, g_h, g_i, w, w_h, w_i = margins(h, m_irr)
    x = (h + alpha * m) / a
    lv, l1, _ = langevin(x)
    assert big_g == pytest.approx(d * (ms * lv - m_irr), rel=1e-12, abs=1e-15 * ms)
    chi = (1 - c) * big_g / k + c * ms / a * l1
    assert w == pytest.approx(1 - alpha * chi, rel=1e-12)
    dh, di = 1e-5 * a, 1e-6 * ms
    for got, j in ((g_h, 1), (w_h, 4)):
        fd = (margins(h + dh, m_irr)[j] - margins(h - dh, m_irr)[j]) / (2 * dh)
        assert got == pytest.approx(fd, rel=1e-6, abs=1e-9 / a)
    for got, j in ((g_i, 1), (w_i, 4)):
        fd = (margins(h, m_irr + di)[j] - margins(h, m_irr - di)[j]) / (2 * di)
        assert got == pytest.approx(fd, rel=1e-6, abs=1e-9 / ms)


@pytest.mark.parametrize("params", [UNIT, (1.0, 0.2, 0.05, 0.1, 0.2), STEEL])
def test_slope_bound_holds_on_loops_and_is_none_where_the_pole_is_near(params):
    """``dM/dH`` by differences along minor and major loops from the initial state stays below
    :func:`jiles_atherton_slope_bound` (the gap of a branch never exceeds ``k·ms/(3a)``)."""
    ms, a, k, c, alpha = params
    ja = JilesAtherton(ms, a, k, c, alpha)
    far = 8.0 * (a + k)
    t = np.linspace(0.0, 1.0, 40001)
    u = far * np.sin(2 * np.pi * 5 * t) * (1.2 - t)
    start = ja.initial_state(0.0)
    m, _ = ja.apply(u, start)
    du = np.diff(u)
    moving = np.abs(du) > 1e-9 * far
    steepest = np.max(np.diff(m)[moving] / du[moving])
    bound = jiles_atherton_slope_bound(0.0, start.z, ms, a, k, c, alpha)
    assert bound is not None and steepest <= bound
    assert steepest > 0.3 * bound  # and not vacuous
    # the demagnetised state of the ill-posed model (α·ms/(3a) = 2): no bound
    assert jiles_atherton_slope_bound(0.0, 0.0, 1.0, 1.0, 1e-3, 0.0, 6.0) is None
