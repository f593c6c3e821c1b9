"""The play kernel's unrolled wall step (``_rk8_qv``) is the generic RK8 step, bit for bit.

Truth: :func:`oscillators.engines._play_kernels._rk8`, the plain loop over the full Dormand–Prince
table (whose order conditions ``test_dop853.py`` checks). The unrolled step leaves out the zero
coefficients and carries (q, v) in scalars; adding ``0·K`` changes no bit of a finite sum, so
the two must agree exactly, for every shape kind, both walls and any step length — and so must
whole trajectories of the old layout, which a full run exercises through the tangent-free and the
tangent paths (the same (q, v) bits with and without tangent columns).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hysteresis import GeneralizedPlay, PlayOperator
from oscillators.engines import _play_kernels as k
from oscillators.engines import play
from oscillators.system import ForcedOscillator


def _tanh_play():
    return GeneralizedPlay(2.0, np.tanh, lambda w: 1.0 / np.cosh(np.clip(w, -350, 350)) ** 2)


@pytest.mark.parametrize(
    "operator",
    [GeneralizedPlay.erf(2.0, 1.0), PlayOperator(2.0), _tanh_play()],
    ids=["erf", "identity", "table"],
)
def test_unrolled_step_equals_the_table_loop_bit_for_bit(operator):
    par = play.make_parameters(ForcedOscillator(operator, 2.92), phi0=0.3)
    rng = np.random.default_rng(11)
    K = np.zeros((k._N_STAGES, 2))
    out = np.empty(2)
    tmp = np.empty(2)
    for _ in range(2000):
        side = rng.choice([-1.0, 1.0])
        t = rng.uniform(0.0, 1e3)
        q, v = rng.normal(0.0, 3.0, 2)
        # step lengths of the wall loop (h_out), of the last partial step and of the reversal
        # search (down to tiny trial lengths)
        h = float(rng.choice([par[7], rng.uniform(0.0, par[7]), 10.0 ** rng.uniform(-14, -2)]))
        k._rk8(par, side, t, np.array([q, v]), h, out, K, tmp, 0)
        a0 = k._accel(par, side, t, q, v)
        assert a0 == K[0, 1]
        q1, v1 = k._rk8_qv(par, side, t, q, v, h, a0)
        assert (q1, v1) == (out[0], out[1])


def test_tangent_columns_leave_the_trajectory_bits_unchanged():
    # the wall step with tangent columns goes through _rk8, without through _rk8_qv: the
    # section of a Lyapunov-style run (4 columns) and of a plain run must be the same bits
    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 2.92)
    par = play.make_parameters(system)
    times = 2.0 * math.pi * np.arange(1, 41)
    rows = []
    for columns in (0, 4):
        st, _ = play._initial_state(par, 0.4, -1.1, None, None)
        T = np.eye(4)[:, :columns].copy()
        out = np.empty((times.size, 3))
        k.sample_kernel(
            par,
            st,
            times,
            out,
            T,
            np.zeros(4),
            np.empty((0, 5)),
            np.zeros(1, dtype=np.int64),
            np.array([1, 0]),
            k.make_work(columns),
        )
        rows.append(out)
    assert np.array_equal(rows[0], rows[1])
