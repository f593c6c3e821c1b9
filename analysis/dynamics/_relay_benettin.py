"""The Benettin QR loop of :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum` compiled for
the relay kernel engine: many QR intervals in one call, bit for bit the Python loop.

Why: for the paper's disorder ensembles one QR interval (8 forcing periods) of a small ensemble
costs less in the kernel than the Python around it (the stepper's sample times, the engine's
clock and switch budget, the divergence check, the QR call, the observer): about a tenth of
``hyst paper --full`` (benchmarks/bench_ensemble.py).

What it does per interval ``i``, in the Python loop's order and floating-point operations:
the target ``transient + (i+1)·Δt`` (``window`` for the last), the step ``t = t_now +
(target − t_now)`` (:meth:`TangentStepper.step_to`), the sample times ``sd·k`` strictly inside
``(t_now, t)`` and ``t`` (:meth:`TangentStepper.step`), their clock readings
(:func:`oscillators.engines.base.split_times`), the switch budget
(:meth:`RelayKernelEngine._run_targets <oscillators.engines.relay.RelayKernelEngine>`), the
kernel run, the divergence test, the QR (:func:`~analysis.dynamics._householder.householder_qr`,
the same compiled function) with full rank and the log sums. Anything else — a kernel status
other than "done" (a slide, a grazing switch, the budget), a divergence, a non-finite tangent
flow, full sample buffers — restores the engine's arrays to the interval's start and returns:
the caller runs that interval through the Python loop (which raises or handles it) and may go
on here after it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from analysis.dynamics._householder import _accumulate_logs, householder_qr
from oscillators.engines import _relay_kernels as kern
from oscillators.engines.base import SWITCH_BUDGET_FLOOR, SWITCHES_PER_RELAY_AND_TIME

__all__ = ["qr_intervals"]


@njit(cache=True)
def _intervals(
    kind, par, tf, ti, bits, lay, st, ist, y, ntan, mp, sw, cnt, n_relays, omega, period,
    bound, floor_, per_relay, t_now, i0, n_steps, transient, dt, window, sd, lsum, marks, hist,
    rows, first, rec_on, tan_on,
):  # fmt: skip
    """Intervals ``i0 ..`` until ``n_steps`` or the first one the Python loop must run; returns
    (intervals done, t_now after them, rows written).

    ``first, rec_on, tan_on`` are the kernel call's target index 0, no switch records and the
    tangent flow on, handed in from Python (int, bool, bool): written as constants here, numba
    would type them as literals and compile a second specialisation of the whole relay event
    loop (``run_nested``/``run_heap`` down to ``advance_table``, ~15 s on a fresh machine)
    instead of reusing the one the engine compiled for the same arguments."""
    k = ntan
    max_targets = 2 + (int(dt / sd) if sd > 0.0 else 0) + 1
    times = np.empty(max_targets)
    tgt_n = np.empty(max_targets, dtype=np.int64)
    tgt_tau = np.empty(max_targets)
    out = np.empty((max_targets, 3))
    st0, ist0, bits0, y0 = st.copy(), ist.copy(), bits.copy(), y.copy()
    n_rows = 0
    i = i0
    while i < n_steps:
        target = transient + (window if i == n_steps - 1 else (i + 1) * dt)
        t = t_now + (target - t_now)
        m = 0
        if sd > 0.0:
            tol = 1e-9 * sd
            k0 = math.floor((t_now + tol) / sd) + 1
            k1 = math.ceil((t - tol) / sd) - 1
            if k1 - k0 + 2 > max_targets:
                break
            for kk in range(k0, k1 + 1):
                times[m] = sd * float(kk)
                m += 1
        times[m] = t
        m += 1
        if n_rows + m > rows.shape[0]:
            break
        for j in range(m):
            n = math.floor(times[j] / period)
            tau = times[j] - n * period
            if tau >= period:
                n, tau = n + 1, 0.0
            elif tau < 0.0:
                tau = 0.0
            tgt_n[j] = n
            tgt_tau[j] = tau
        span = (tgt_n[m - 1] - ist[kern.I_N]) * period + (tgt_tau[m - 1] - st[kern.S_TAU])
        b = floor_ + per_relay * max(1, n_relays) * max(1.0, omega) * max(span, 0.0)
        ist[kern.I_MAXSW] = ist[kern.I_NSW] + int(min(b, 2.0**62))
        st0[:] = st
        ist0[:] = ist
        bits0[:] = bits
        y0[:, :] = y
        cnt[0] = 0
        # the two entry points keep the table kind a compile-time constant in the hot loop
        if kind == kern.KIND_NESTED:
            status, _ = kern.run_nested(
                par, tf, ti, bits, lay, st, ist, tgt_n[:m], tgt_tau[:m], first, out[:m], rec_on,
                sw, cnt, tan_on, y, ntan, mp,
            )  # fmt: skip
        else:
            status, _ = kern.run_heap(
                par, tf, ti, bits, lay, st, ist, tgt_n[:m], tgt_tau[:m], first, out[:m], rec_on,
                sw, cnt, tan_on, y, ntan, mp,
            )  # fmt: skip
        ok = status == 0
        for j in range(m):
            if not (abs(out[j, 0]) <= bound and abs(out[j, 1]) <= bound):
                ok = False
        q, diag, finite = householder_qr(y[:k, :k].copy())
        if not (ok and finite):  # the Python loop runs this interval (and raises or handles it)
            st[:] = st0
            ist[:] = ist0
            bits[:] = bits0
            y[:, :] = y0
            break
        _accumulate_logs(diag, k, k, lsum)
        y[:k, :k] = q
        for j in range(m):
            rows[n_rows + j, 0] = times[j]
            rows[n_rows + j, 1] = out[j, 0]
            rows[n_rows + j, 2] = out[j, 1]
            rows[n_rows + j, 3] = out[j, 2]
        n_rows += m
        if marks[i]:
            hist[i, :] = lsum
        t_now = t
        i += 1
    return i - i0, t_now, n_rows


def qr_intervals(
    stepper: Any,
    i0: int,
    n_steps: int,
    transient: float,
    dt: float,
    window: float,
    lsum: np.ndarray,
    marks: np.ndarray,
    hist: np.ndarray,
) -> tuple[int, np.ndarray]:
    """Run QR intervals ``i0 ..`` of the Benettin loop in the kernel, as far as it can go.

    ``stepper`` a :class:`~analysis.dynamics.lyapunov.TangentStepper` (exactly that class) on a
    relay kernel engine, neither sliding nor collapsed (else nothing is done); ``lsum`` the log
    sums (updated), ``hist[i]`` receives them after interval ``i`` where ``marks[i]``. Returns
    the number of intervals done and their sample rows ``(t, q, v, M)`` (as
    :attr:`TangentStepper.samples` of each, concatenated); the stepper then stands after the
    last of them, its :attr:`~TangentStepper.samples` those rows.
    """
    eng = stepper.engine
    arrays = eng.kernel_arrays()
    if arrays is None:
        return 0, np.empty((0, 4))
    sd = stepper.sample_dt
    sd = 0.0 if sd is None else float(sd)
    per = 2 + (int(dt / sd) if sd > 0.0 else 0) + 1
    rows = np.empty(((n_steps - i0) * per, 4))
    done, t_now, n_rows = _intervals(
        *arrays, float(eng.system.divergence_bound), SWITCH_BUDGET_FLOOR,
        SWITCHES_PER_RELAY_AND_TIME, float(stepper.elapsed), int(i0), int(n_steps),
        float(transient), float(dt), float(window), sd, lsum, marks, hist, rows, 0, False, True,
    )  # fmt: skip
    if done:
        eng.kernel_moved()
        stepper.moved_to(float(t_now), rows[:n_rows])
    return done, rows[:n_rows]
