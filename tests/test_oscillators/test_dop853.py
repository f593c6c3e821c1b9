"""The Dormand–Prince 8 coefficients carried in oscillators/_dop853.py (independent checks)."""

from __future__ import annotations

import math

import numpy as np

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
