"""The relay kernel's fast short hop (``fast_hop``, ``fast_propagator``) on its own, against the
exact solution of ``q'' + 2ζq' + q = cos φ + F`` (``oscillators.linear.exact_step``) and the
exact homogeneous propagator (``hom_matrix``).

An accepted hop must land on the threshold: the exact q at the returned time equals θ to the
round-off of the exact solution's evaluation, and the returned v, cos φ, sin φ are the exact
ones at that time. The hop must refuse (``ok`` False) past the horizon, past its length limit
``h_small`` and when q is not monotone on the hop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from oscillators.engines import _relay_kernels as kern
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes


@njit(cache=True)
def _fast(coefs, omega, h_small, q, v, c, s, force, gap, horizon):
    return kern.fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon)


@njit(cache=True)
def _prop(coefs, h):
    return kern.fast_propagator(coefs, h)


def _coefs(zeta: float, omega: float) -> tuple:
    return kern.hop_coefficients(kern.taylor_matrix_coefficients(zeta, omega))


@pytest.mark.parametrize("zeta, omega", [(0.05, 1.0), (0.0, 1.3), (0.5, 0.3), (1.0, 2.0)])
def test_accepted_hops_land_on_the_threshold(zeta, omega):
    rng = np.random.default_rng(3)
    coefs = _coefs(zeta, omega)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    h_small = kern.make_params(zeta, omega, 1.0, 0.0, amp_a, amp_b, 0.0, fast_hop=3e-3)[kern.P_HS]
    accepted = 0
    for _ in range(400):
        q, v, force = rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-4, 4)
        phi = rng.uniform(0, 2 * math.pi)
        c, s = math.cos(phi), math.sin(phi)
        gap = math.copysign(rng.uniform(0, 0.9) * h_small * abs(v), v)
        ok, h, v1, c1, s1 = _fast(coefs, omega, h_small, q, v, c, s, force, gap, 1.0)
        if not ok:
            continue
        accepted += 1
        assert 0.0 < h < h_small
        # the exact rotation of the given (cos φ, sin φ) and the exact solution from there
        ch, sh = math.cos(omega * h), math.sin(omega * h)
        ce, se = c * ch - s * sh, s * ch + c * sh
        qe, ve = exact_step(q, v, c, s, ce, se, force, h, zeta, omega, amp_a, amp_b)
        # exact_step takes off the particular solution (size |A| + |B| + |F|), propagates and
        # adds it back: a few roundings of the state's and those sizes (the hop's own error
        # is below 1e-17 by its acceptance test)
        eps = np.finfo(float).eps
        scale = 8.0 * eps * (abs(q) + abs(v) + abs(force) + abs(amp_a) + abs(amp_b) + 1.0)
        assert abs(qe - (q + gap)) <= scale
        assert abs(ve - v1) <= scale
        assert abs(ce - c1) <= 8 * eps
        assert abs(se - s1) <= 8 * eps
        # the tangent propagator: Φ(h) = [[g' + 2ζg, g], [-g, g']]
        g, gd = _prop(coefs, h)
        m00, m01, m10, m11 = hom_matrix(h, zeta)
        for got, want in ((gd + 2 * zeta * g, m00), (g, m01), (-g, m10), (gd, m11)):
            assert abs(got - want) <= 4 * eps
    assert accepted > 300  # the hops drawn are short: the fast path takes nearly all


def test_refusals():
    zeta, omega = 0.05, 1.0
    coefs = _coefs(zeta, omega)
    h_small = 3e-3
    q, v, c, s, force = 0.3, 1.2, 1.0, 0.0, 0.5
    gap = 0.5 * h_small * v
    ok, h, *_ = _fast(coefs, omega, h_small, q, v, c, s, force, gap, 1.0)
    assert ok and 0.0 < h < h_small
    # the stop comes first
    assert not _fast(coefs, omega, h_small, q, v, c, s, force, gap, 0.5 * h)[0]
    # longer than the fast hop's reach
    assert not _fast(coefs, omega, 0.4 * h, q, v, c, s, force, gap, 1.0)[0]
    # the threshold lies behind (q moving away from it): no positive time
    assert not _fast(coefs, omega, h_small, q, v, c, s, force, -gap, 1.0)[0]
    # q turns before the threshold: v = 1e-4 against q'' ~ cos φ + F - q ~ 1.2 (not monotone)
    v_small = 1e-4
    assert not _fast(coefs, omega, h_small, q, v_small, c, s, force, 0.9 * h_small * v_small,
                     1.0)[0]  # fmt: skip


def _fast_step(coefs, zeta, omega, h_small, q, v, c, s, force, gap, horizon, a0, a1, b0, b1):
    ok, h, v1, c1, s1 = kern.fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon)
    na0, na1, nb0, nb1 = kern.fast_tangent(coefs, zeta, h, a0, a1, b0, b1)
    sb0, sb1 = kern.saltation(2.9, 0.37, v1, na0, na1, nb0, nb1)
    slide = kern.slides(zeta, 2.9, 0.5, q, v, c, force, 0.37, 1, q, -0.37)
    return ok, h, v1, c1, s1, na0, na1, nb0, nb1, sb0, sb1, slide


# the same source compiled with fused multiply-adds allowed (as the event loop is) and without:
# inlined, the callee's arithmetic takes the caller's flags
_fast_contract = njit(fastmath={"contract"})(_fast_step)
_fast_plain = njit(_fast_step)


@pytest.mark.parametrize("zeta, omega", [(0.05, 1.0), (0.5, 0.3)])
def test_fast_path_rounds_alike_with_and_without_contraction(zeta, omega):
    """Every multiply-add of the fast path is an explicit fma and no sum has a plain product
    as an operand, so the compiler has nothing left to fuse: the event loop (compiled with
    ``contract``) and the lanes of the vectorized loop round alike. Independent truth: the same
    source compiled without ``contract``, which LLVM may not fuse at all."""
    rng = np.random.default_rng(11)
    coefs = _coefs(zeta, omega)
    h_small = 3e-3
    for _ in range(2000):
        q, v, force = rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-4, 4)
        phi = rng.uniform(0, 2 * math.pi)
        gap = math.copysign(rng.uniform(0, 0.9) * h_small * abs(v), v)
        args = (coefs, zeta, omega, h_small, q, v, math.cos(phi), math.sin(phi), force, gap,
                1.0, *rng.normal(size=4))  # fmt: skip
        got, want = _fast_contract(*args), _fast_plain(*args)
        assert got == want  # tuples of floats and bools, compared bit for bit (no nan here)
