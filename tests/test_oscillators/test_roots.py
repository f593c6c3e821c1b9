"""The kernels' one safeguarded Newton root finder (oscillators/engines/_roots.py).

Truth: roots known in closed form, and SciPy's ``brentq`` (an independent bracketing method) run
to its own rounding-level tolerance. The finder's contract: the returned point lies in the
bracket and within ``ROOT_RTOL·max(1, scale)`` (its stopping tolerance; a step of that size is
the distance still to go for a simple root, three times it for a triple root, where Newton
contracts by 2/3 per step) of the root.
"""

from __future__ import annotations

import math

import pytest
from numba import njit
from scipy.optimize import brentq

from oscillators.engines._roots import ROOT_MAX_ITER, ROOT_RTOL, find_root, secant_start


@njit(cache=False)
def _cubic(x, args):
    # x³ − c: a simple root c^(1/3)
    (c,) = args
    return x * x * x - c, 3.0 * x * x


@njit(cache=False)
def _kepler(x, args):
    # Kepler's equation E − e sin E − M (simple root, no closed form: brentq is the truth)
    e, m = args
    return x - e * math.sin(x) - m, 1.0 - e * math.cos(x)


@njit(cache=False)
def _falling_cos(x, args):
    # −cos x on [0, π]: g(0) = −1 < 0 <= g(π); root π/2 (a time-like root far from 0)
    (shift,) = args
    return -math.cos(x - shift), math.sin(x - shift)


@njit(cache=False)
def _triple(x, args):
    # (x − r)³: a root where g' = 0 too (tangent), Newton only linear there
    (r,) = args
    d = x - r
    return d * d * d, 3.0 * d * d


@njit(cache=False)
def _linear_end(x, args):
    # x(1 + x) − a(1 + a): root x = a, put at a bracket end by the caller
    (a,) = args
    return x * (1.0 + x) - a * (1.0 + a), 1.0 + 2.0 * x


@njit(cache=False)
def _sign_only(x, args):
    # a sign change without a derivative (g' = 0 asks for bisection): sin(x − r)
    (r,) = args
    return math.sin(x - r), 0.0


@njit(cache=False)
def _solve(fn, args, lo, hi, x0, scale):
    return find_root(fn, args, lo, hi, x0, scale)


def _tol(scale):
    return ROOT_RTOL * max(1.0, scale)


@pytest.mark.parametrize("c", [0.5, 2.0, 7.9])
def test_simple_root_in_closed_form(c):
    lo, hi = 0.0, 2.0
    x0 = secant_start(lo, hi, -c, 8.0 - c)
    x = _solve(_cubic, (c,), lo, hi, x0, 1.0)
    assert abs(x - c ** (1.0 / 3.0)) <= _tol(1.0)


@pytest.mark.parametrize("e, m", [(0.1, 0.3), (0.7, 2.0), (0.95, 0.05)])
def test_agrees_with_brentq(e, m):
    lo, hi = 0.0, math.pi
    x = _solve(_kepler, (e, m), lo, hi, 0.5 * (lo + hi), 1.0)
    # brentq's own tolerance: |truth − root| <= xtol + rtol·|truth| (rtol at its floor 4ε)
    rtol = 4.0 * math.ulp(1.0)
    truth = brentq(lambda s: s - e * math.sin(s) - m, lo, hi, xtol=1e-16, rtol=rtol)
    assert abs(x - truth) <= _tol(1.0) + 1e-16 + rtol * truth
    assert lo <= x <= hi


def test_scale_is_the_clock_the_root_is_added_to():
    # a root near 1e4 (an event late in a run): located to ROOT_RTOL of the clock, not of 1
    shift = 1e4
    lo, hi = shift, shift + math.pi
    x = _solve(_falling_cos, (shift,), lo, hi, lo + 1.0, hi)
    assert abs(x - (shift + 0.5 * math.pi)) <= _tol(hi) + math.ulp(hi)


def test_root_at_the_right_bracket_end():
    a = 0.75
    x = _solve(_linear_end, (a,), 0.0, a, 0.3, 1.0)
    assert x == a or abs(x - a) <= _tol(1.0)


def test_root_at_the_left_bracket_end():
    # g(lo) = 0 breaks g(lo) < 0 only at the end point: every iterate has g > 0, the bracket
    # closes on lo
    x = _solve(_linear_end, (0.0,), 0.0, 1.0, 0.5, 1.0)
    assert 0.0 <= x <= _tol(1.0)


@pytest.mark.parametrize("r", [0.3, 1.0 / 3.0, 0.9])
def test_tangent_triple_root(r):
    # Newton contracts by 2/3 per step; it stops when its step (a third of the distance left)
    # is below the tolerance, so it ends within 3 tolerances, inside the iteration limit
    # (log(tol/1)/log(2/3) ≈ 85 < ROOT_MAX_ITER)
    assert math.log(_tol(1.0)) / math.log(2.0 / 3.0) < ROOT_MAX_ITER
    x = _solve(_triple, (r,), 0.0, 1.0, 0.5 if r != 0.5 else 0.6, 1.0)
    assert abs(x - r) <= 3.0 * _tol(1.0)


@pytest.mark.parametrize("r", [0.1234, 0.5, 0.987654321])
def test_no_derivative_bisects_to_the_sign_change(r):
    x = _solve(_sign_only, (r,), 0.0, 1.0, 0.5, 1.0)
    assert abs(x - r) <= _tol(1.0)


def test_secant_start_lies_in_the_bracket():
    assert secant_start(0.0, 1.0, -1.0, 1.0) == 0.5
    assert secant_start(0.0, 1.0, -1.0, 3.0) == 0.25
    # no sign change (or a flat secant): the midpoint
    assert secant_start(0.0, 2.0, -1.0, -1.0) == 1.0
    assert secant_start(0.0, 2.0, 1.0, 0.5) == 1.0
