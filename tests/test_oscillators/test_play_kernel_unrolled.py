"""The play kernel's wall steps are the plain RK8 step over the full table, bit for bit.

Truth: ``_table_step`` below, the textbook loop over the full Dormand–Prince table (whose order
conditions ``test_dop853.py`` checks) with the kernel's right-hand side. The kernel's steps leave
out the zero coefficients (``_rk8_qv`` also carries (q, v) in scalars, ``_rk8`` reuses the δq
sums for δw and keeps δφ); adding ``0·K`` changes no bit of a finite sum, so they must agree
exactly, for every shape kind, both walls, any step length and with tangent columns — and whole
runs with and without tangent columns must give the same trajectory bits. Bit identity holds
because neither the play kernels nor ``_table_step`` allow fused multiply-add (numba emits no
``contract`` flag without ``fastmath``); compiling the play kernels with ``fastmath`` would
change bits and must replace these assertions by a bound.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from hysteresis import GeneralizedPlay, PlayOperator
from oscillators.engines import _play_kernels as k_
from oscillators.engines import play
from oscillators.system import ForcedOscillator


@njit(cache=False)
def _table_step(par, side, t, y, h, k):
    n = y.shape[0]
    K = np.zeros((k_.RK_A.shape[0], n))
    tmp = np.empty(n)
    for i in range(k_.RK_A.shape[0]):
        for r in range(n):
            acc = 0.0
            for j in range(i):
                acc += k_.RK_A[i, j] * K[j, r]
            tmp[r] = y[r] + h * acc
        k_._rhs(par, side, t + k_.RK_C[i] * h, tmp, K[i], k)
    out = np.empty(n)
    for r in range(n):
        acc = 0.0
        for i in range(k_.RK_A.shape[0]):
            acc += k_.RK_B[i] * K[i, r]
        out[r] = y[r] + h * acc
    return out


def _tanh_play():
    return GeneralizedPlay(2.0, np.tanh, lambda w: 1.0 / np.cosh(np.clip(w, -350, 350)) ** 2)


@pytest.mark.parametrize(
    "operator",
    [GeneralizedPlay.erf(2.0, 1.0), PlayOperator(2.0), _tanh_play()],
    ids=["erf", "identity", "table"],
)
def test_wall_steps_equal_the_full_table_loop_bit_for_bit(operator):
    # C = 0.8: below the identity play's positive-feedback bound C·slope < 1 (no warning)
    par = play.make_parameters(ForcedOscillator(operator, 0.8), phi0=0.3)
    rng = np.random.default_rng(11)
    columns = 3
    n = 2 + 4 * columns
    K = np.zeros((k_._N_STAGES, n))
    out = np.empty(n)
    tmp = np.empty(n)
    for _ in range(2000):
        side = rng.choice([-1.0, 1.0])
        t = rng.uniform(0.0, 1e3)
        y = rng.normal(0.0, 3.0, n)
        q, v = y[0], y[1]
        # step lengths of the wall loop (h_out), of the last partial step and of the reversal
        # search (down to tiny trial lengths)
        h_out = par[k_.P_H_OUT]
        h = float(rng.choice([h_out, rng.uniform(0.0, h_out), 10.0 ** rng.uniform(-14, -2)]))
        truth = _table_step(par, side, t, y, h, columns)
        k_._rk8(par, side, t, y, h, out, K, tmp, columns)
        assert np.array_equal(out, truth)
        q1, v1 = k_._rk8_qv(par, side, t, q, v, h, k_._accel(par, side, t, q, v))
        assert (q1, v1) == (truth[0], truth[1])


def test_tangent_columns_leave_the_trajectory_bits_unchanged():
    # the wall step with tangent columns goes through _rk8, without them through _rk8_qv: a
    # run with 4 columns and a plain run must give the same trajectory bits
    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 2.92)
    par = play.make_parameters(system)
    times = 2.0 * math.pi * np.arange(1, 41)
    rows = []
    for columns in (0, 4):
        st, _ = play._initial_state(par, 0.4, -1.1, None, None)
        T = np.eye(4)[:, :columns].copy()
        out = np.empty((times.size, 3))
        k_.sample_kernel(
            par,
            st,
            times,
            out,
            T,
            np.zeros(4),
            np.empty((0, 5)),
            np.zeros(1, dtype=np.int64),
            np.array([1, 0]),
            k_.make_work(columns),
        )
        rows.append(out)
    assert np.array_equal(rows[0], rows[1])
