"""The Dormand–Prince 8 coefficients and the kernels' RK8 step (engines/_dop853_kernel.py)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.engines import _dop853_kernel as dop


def test_quadrature_and_row_sum_conditions():
    # b·c^k = 1/(k+1) for k = 0..7 (quadrature order 8) and the row sums A·1 = c
    for k in range(8):
        assert abs(dop.B @ dop.C**k - 1.0 / (k + 1)) < 1e-14
    np.testing.assert_allclose(dop.A.sum(axis=1), dop.C, atol=1e-14)
    assert np.all(np.triu(dop.A) == 0.0)  # explicit


def test_some_higher_order_tree_conditions():
    # order-3..5 trees: Σ b_i a_ij c_j = 1/6, Σ b_i a_ij c_j^2 = 1/12, Σ b_i c_i a_ij c_j = 1/8,
    # Σ b_i a_ij a_jk c_k = 1/24, Σ b_i a_ij c_j^3 = 1/20
    b, a, c = dop.B, dop.A, dop.C
    assert abs(b @ a @ c - 1 / 6) < 1e-14
    assert abs(b @ a @ c**2 - 1 / 12) < 1e-14
    assert abs((b * c) @ a @ c - 1 / 8) < 1e-14
    assert abs(b @ a @ a @ c - 1 / 24) < 1e-14
    assert abs(b @ a @ c**3 - 1 / 20) < 1e-14


def _integrate(f, y0, t_end, n):
    h = t_end / n
    y = np.array(y0, dtype=float)
    k = np.zeros((dop.N_STAGES, y.size))
    t = 0.0
    for _ in range(n):
        for i in range(dop.N_STAGES):
            k[i] = f(t + dop.C[i] * h, y + h * (dop.A[i, :i] @ k[:i]))
        y = y + h * (dop.B @ k)
        t += h
    return y


def test_global_error_is_of_order_eight():
    # y'' = -y with y(0) = 1, y'(0) = 0: y(t) = cos t. Halving the step divides the error by 2^8.
    def f(t, y):
        return np.array([y[1], -y[0]])

    errs = [abs(_integrate(f, [1.0, 0.0], 10.0, n)[0] - math.cos(10.0)) for n in (20, 40)]
    order = math.log2(errs[0] / errs[1])
    assert 7.3 < order < 8.8, order  # 7.7 measured (higher error terms still visible)


@njit(cache=False)
def _forced_pendulum(t, y, dy, args):
    (c,) = args
    dy[0] = y[1]
    dy[1] = -math.sin(y[0]) - 0.1 * y[1] + c * math.cos(t)
    dy[2] = y[0] * y[1]


@njit(cache=False)
def _textbook_step(t, y, h, c):
    # the plain loop over the full table, zero coefficients included
    n = y.size
    K = np.zeros((dop.N_STAGES, n))
    tmp = np.empty(n)
    for i in range(dop.N_STAGES):
        for r in range(n):
            acc = 0.0
            for j in range(i):
                acc += dop.A[i, j] * K[j, r]
            tmp[r] = y[r] + h * acc
        _forced_pendulum(t + dop.C[i] * h, tmp, K[i], (c,))
    out = np.empty(n)
    for r in range(n):
        acc = 0.0
        for i in range(dop.N_STAGES):
            acc += dop.B[i] * K[i, r]
        out[r] = y[r] + h * acc
    return out


@njit(cache=False)
def _kernel_step(t, y, h, c, first):
    n = y.size
    K = np.zeros((dop.N_STAGES, n))
    if first == 1:
        _forced_pendulum(t, y, K[0], (c,))
    out = np.empty(n)
    tmp = np.empty(n)
    dop.rk8_step(_forced_pendulum, (c,), t, y, h, out, K, tmp, n, first)
    return out


def test_kernel_step_is_the_full_table_step_bit_for_bit():
    # rk8_step sums over the nonzero coefficients only and evaluates stage 0 at (t, y): adding
    # 0·K and c_0·h = 0 change no bit of finite values, so it must equal the textbook loop
    # exactly (the kernels compile without fastmath, so no fused multiply-add reorders either)
    rng = np.random.default_rng(5)
    for _ in range(500):
        t = rng.uniform(0.0, 1e3)
        y = rng.normal(0.0, 2.0, 3)
        h = float(rng.choice([0.05, rng.uniform(0.0, 0.2), 10.0 ** rng.uniform(-14, -2)]))
        truth = _textbook_step(t, y, h, 0.7)
        for first in (0, 1):
            assert np.array_equal(_kernel_step(t, y, h, 0.7, first), truth)


def test_kernel_step_has_order_eight():
    # the compiled step on y'' = -y (as _integrate above): halving h divides the error by ~2^8
    @njit(cache=False)
    def osc(t, y, dy, args):
        dy[0] = y[1]
        dy[1] = -y[0]

    @njit(cache=False)
    def run(n):
        h = 10.0 / n
        y = np.array([1.0, 0.0])
        K = np.zeros((dop.N_STAGES, 2))
        out = np.empty(2)
        tmp = np.empty(2)
        for i in range(n):
            dop.rk8_step(osc, (0.0,), i * h, y, h, out, K, tmp, 2, 0)
            y[:] = out
        return y[0]

    errs = [abs(run(n) - math.cos(10.0)) for n in (20, 40)]
    assert 7.3 < math.log2(errs[0] / errs[1]) < 8.8
