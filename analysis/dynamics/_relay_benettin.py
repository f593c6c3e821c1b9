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
from oscillators.engines import _relay_lanes as lanes_mod
from oscillators.engines.base import SWITCH_BUDGET_FLOOR, SWITCHES_PER_RELAY_AND_TIME

__all__ = ["LANES", "qr_intervals", "qr_intervals_lanes"]

#: systems side by side in :func:`qr_intervals_lanes`
LANES = lanes_mod.LANES


@njit(cache=True, inline="always")
def _targets(t_now, target, sd, period, times, tgt_n, tgt_tau):
    """The interval's targets (the step ``t = t_now + (target − t_now)`` of
    :meth:`TangentStepper.step_to`, the sample times ``sd·k`` strictly inside ``(t_now, t)``,
    then ``t``) into ``times[:m]`` and their clock readings
    (:func:`oscillators.engines.base.split_times`); returns m, 0 if they do not fit."""
    t = t_now + (target - t_now)
    m = 0
    if sd > 0.0:
        tol = 1e-9 * sd
        k0 = math.floor((t_now + tol) / sd) + 1
        k1 = math.ceil((t - tol) / sd) - 1
        if k1 - k0 + 2 > times.shape[0]:
            return 0
        for kk in range(k0, k1 + 1):
            times[m] = sd * float(kk)
            m += 1
    times[m] = t
    m += 1
    for j in range(m):
        n = math.floor(times[j] / period)
        tau = times[j] - n * period
        if tau >= period:
            n, tau = n + 1, 0.0
        elif tau < 0.0:
            tau = 0.0
        tgt_n[j] = n
        tgt_tau[j] = tau
    return m


@njit(cache=True, inline="always")
def _budget(nsw, n_now, tau_now, n_end, tau_end, period, n_relays, omega, floor_, per_relay):
    """The switch count at which the kernel stops on the way to the clock reading ``(n_end,
    tau_end)`` (:meth:`RelayKernelEngine._run_targets
    <oscillators.engines.relay.RelayKernelEngine>`'s budget)."""
    span = (n_end - n_now) * period + (tau_end - tau_now)
    b = floor_ + per_relay * max(1, n_relays) * max(1.0, omega) * max(span, 0.0)
    return nsw + int(min(b, 2.0**62))


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
        m = _targets(t_now, target, sd, period, times, tgt_n, tgt_tau)
        if m == 0 or n_rows + m > rows.shape[0]:
            break
        t = times[m - 1]
        ist[kern.I_MAXSW] = _budget(
            ist[kern.I_NSW], ist[kern.I_N], st[kern.S_TAU], tgt_n[m - 1], tgt_tau[m - 1], period,
            n_relays, omega, floor_, per_relay,
        )  # fmt: skip
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


# -- the same loop over several systems side by side (oscillators/engines/_relay_lanes.py) ------
@njit(cache=True)
def _lane_start(j, par, period, w, iw, n_relays, omega, floor_, per_relay, t_now, i_at,
                n_steps, transient, dt, window, sd, times, tgt_n, tgt_tau, n_tgt, jt, n_rows,
                rows_cap, w0, iw0):  # fmt: skip
    """Lane ``j`` into interval ``i_at[j]``: its targets, its switch budget and the interval's
    snapshot (as :func:`_intervals` before its kernel call); False if the Python loop must run
    it (too many targets or rows)."""
    lanes = lanes_mod.LANES
    i = i_at[j]
    target = transient + (window if i == n_steps - 1 else (i + 1) * dt)
    m = _targets(t_now[j], target, sd, period, times[j], tgt_n[j], tgt_tau[j])
    if m == 0 or n_rows[j] + m > rows_cap:
        return False
    iw[lanes_mod.MAXSW * lanes + j] = _budget(
        iw[lanes_mod.NSW * lanes + j], iw[lanes_mod.PERIOD * lanes + j],
        w[lanes_mod.TAU * lanes + j], tgt_n[j, m - 1], tgt_tau[j, m - 1], period, n_relays[j],
        omega, floor_, per_relay,
    )  # fmt: skip
    n_tgt[j] = m
    jt[j] = 0
    for r in range(lanes_mod.N_ROWS):
        w0[r * lanes + j] = w[r * lanes + j]
    for r in range(lanes_mod.N_IROWS):
        iw0[r * lanes + j] = iw[r * lanes + j]
    _lane_stop(j, period, w, iw, tgt_n, tgt_tau, jt)
    return True


@njit(cache=True)
def _lane_stop(j, period, w, iw, tgt_n, tgt_tau, jt):
    """Lane ``j``'s next stop (run_table: the period end until the target's period, then the
    target's time) and resume it."""
    lanes = lanes_mod.LANES
    if iw[lanes_mod.PERIOD * lanes + j] < tgt_n[j, jt[j]]:
        w[lanes_mod.STOP * lanes + j] = period
    else:
        w[lanes_mod.STOP * lanes + j] = tgt_tau[j, jt[j]]
    w[lanes_mod.ACT * lanes + j] = 1.0


@njit(cache=True)
def _lane_intervals(par, mp, tf, w, iw, n_lanes, n_relays, omega, period, bound, floor_,
                    per_relay, t_now, i_at, n_steps, transient, dt, window, sd, lsum, marks,
                    hist, rows, n_rows):  # fmt: skip
    """:func:`_intervals` for ``n_lanes`` systems side by side (``lanes_mod.advance_lanes``):
    every lane from interval ``i_at[j]`` until ``n_steps`` or an interval the Python loop must
    run (the lane restored to that interval's start); per lane the same targets, budget, kernel
    path, divergence test, QR and log sums, so the same bits. ``i_at``, ``t_now``, ``n_rows``:
    per lane, where it stands (updated)."""
    lanes = lanes_mod.LANES
    k = 2
    max_targets = 2 + (int(dt / sd) if sd > 0.0 else 0) + 1
    times = np.empty((lanes, max_targets))
    tgt_n = np.empty((lanes, max_targets), dtype=np.int64)
    tgt_tau = np.empty((lanes, max_targets))
    out = np.empty((lanes, max_targets, 3))
    n_tgt = np.zeros(lanes, dtype=np.int64)
    jt = np.zeros(lanes, dtype=np.int64)
    w0 = w.copy()
    iw0 = iw.copy()
    e = np.empty(kern.ORDER + 1)
    c_wrap = math.cos(par[kern.P_PHI0])
    s_wrap = math.sin(par[kern.P_PHI0])
    rows_cap = rows.shape[1]
    running = 0
    for j in range(lanes):
        w[lanes_mod.ACT * lanes + j] = 0.0
        iw[lanes_mod.EVENT * lanes + j] = 0
        if j < n_lanes and i_at[j] < n_steps and _lane_start(
            j, par, period, w, iw, n_relays, omega, floor_, per_relay, t_now, i_at, n_steps,
            transient, dt, window, sd, times, tgt_n, tgt_tau, n_tgt, jt, n_rows, rows_cap, w0,
            iw0,
        ):  # fmt: skip
            running += 1
    while running > 0:
        lanes_mod.advance_lanes(par, mp, tf, w, iw, e)
        for j in range(n_lanes):
            event = iw[lanes_mod.EVENT * lanes + j]
            if event == 0:
                continue
            iw[lanes_mod.EVENT * lanes + j] = 0
            ok = event == lanes_mod.AT_STOP
            if ok and iw[lanes_mod.PERIOD * lanes + j] < tgt_n[j, jt[j]]:
                # the period's end (kern._wrap)
                w[lanes_mod.TAU * lanes + j] = 0.0
                w[lanes_mod.COS * lanes + j] = c_wrap
                w[lanes_mod.SIN * lanes + j] = s_wrap
                iw[lanes_mod.PERIOD * lanes + j] += 1
                _lane_stop(j, period, w, iw, tgt_n, tgt_tau, jt)
                continue
            if ok:
                # a target: sample it; the interval goes on to its next target
                out[j, jt[j], 0] = w[lanes_mod.Q * lanes + j]
                out[j, jt[j], 1] = w[lanes_mod.V * lanes + j]
                out[j, jt[j], 2] = w[lanes_mod.MV * lanes + j]
                jt[j] += 1
                if jt[j] < n_tgt[j]:
                    _lane_stop(j, period, w, iw, tgt_n, tgt_tau, jt)
                    continue
                # the interval's end: divergence test, QR, log sums (as _intervals)
                m = n_tgt[j]
                for jj in range(m):
                    if not (abs(out[j, jj, 0]) <= bound and abs(out[j, jj, 1]) <= bound):
                        ok = False
                y = np.empty((k, k))
                y[0, 0] = w[lanes_mod.A0 * lanes + j]
                y[0, 1] = w[lanes_mod.A1 * lanes + j]
                y[1, 0] = w[lanes_mod.B0 * lanes + j]
                y[1, 1] = w[lanes_mod.B1 * lanes + j]
                q, diag, finite = householder_qr(y)
                ok = ok and finite
            if not ok:  # the Python loop runs this interval (and raises or handles it)
                for r in range(lanes_mod.N_ROWS):
                    w[r * lanes + j] = w0[r * lanes + j]
                for r in range(lanes_mod.N_IROWS):
                    iw[r * lanes + j] = iw0[r * lanes + j]
                w[lanes_mod.ACT * lanes + j] = 0.0
                running -= 1
                continue
            _accumulate_logs(diag, k, k, lsum[j])
            w[lanes_mod.A0 * lanes + j] = q[0, 0]
            w[lanes_mod.A1 * lanes + j] = q[0, 1]
            w[lanes_mod.B0 * lanes + j] = q[1, 0]
            w[lanes_mod.B1 * lanes + j] = q[1, 1]
            base = n_rows[j]
            for jj in range(m):
                rows[j, base + jj, 0] = times[j, jj]
                rows[j, base + jj, 1] = out[j, jj, 0]
                rows[j, base + jj, 2] = out[j, jj, 1]
                rows[j, base + jj, 3] = out[j, jj, 2]
            n_rows[j] = base + m
            i = i_at[j]
            if marks[i]:
                hist[j, i, :] = lsum[j]
            t_now[j] = times[j, m - 1]
            i_at[j] = i + 1
            if i + 1 >= n_steps or not _lane_start(
                j, par, period, w, iw, n_relays, omega, floor_, per_relay, t_now, i_at, n_steps,
                transient, dt, window, sd, times, tgt_n, tgt_tau, n_tgt, jt, n_rows, rows_cap,
                w0, iw0,
            ):  # fmt: skip
                running -= 1


#: the engine's float and int state entries each lane row mirrors
_W_STATE = (
    (lanes_mod.Q, kern.S_Q), (lanes_mod.V, kern.S_V), (lanes_mod.TAU, kern.S_TAU),
    (lanes_mod.COS, kern.S_COS), (lanes_mod.SIN, kern.S_SIN), (lanes_mod.UP, kern.S_UP),
    (lanes_mod.DN, kern.S_DN), (lanes_mod.MV, kern.S_MV), (lanes_mod.IM, kern.S_IM),
    (lanes_mod.PQ, kern.S_PQ), (lanes_mod.PJ, kern.S_PJ),
)  # fmt: skip
_IW_STATE = (
    (lanes_mod.K, kern.I_K), (lanes_mod.NSW, kern.I_NSW), (lanes_mod.MAXSW, kern.I_MAXSW),
    (lanes_mod.PERIOD, kern.I_N),
)  # fmt: skip
_Y_STATE = ((lanes_mod.A0, 0, 0), (lanes_mod.A1, 0, 1), (lanes_mod.B0, 1, 0), (lanes_mod.B1, 1, 1))


def _lane_arrays(stepper: Any) -> tuple | None:
    """The stepper's kernel arrays if it can run as a lane: a nested table whose next down
    threshold never lies above its next up one (the lanes' threshold select), two tangent
    columns."""
    arrays = stepper.engine.kernel_arrays()
    if arrays is None or arrays[0] != kern.KIND_NESTED or arrays[9] != 2:
        return None
    tf, lay = arrays[2], arrays[5]
    g = int(lay[0])
    if g > 1 and not np.all(tf[g : 2 * g - 1] <= tf[1:g]):
        return None
    return arrays


def qr_intervals_lanes(
    steppers: list,
    i0: int,
    n_steps: int,
    transient: float,
    dt: float,
    window: float,
    lsums: list[np.ndarray],
    marks: np.ndarray,
    hists: list[np.ndarray],
) -> list[tuple[int, np.ndarray] | None]:
    """:func:`qr_intervals` for several steppers at once, up to ``LANES`` of them side by side
    in the vector units (:mod:`oscillators.engines._relay_lanes`), each bit for bit as alone.

    Steppers on nested relay tables with two tangent columns, the same kernel parameters and
    hop tables (the same ζ, Ω, C) and the same ``sample_dt`` share lanes; any other, and one
    left alone in its group, gets ``None`` (run it alone). Returns ``(intervals done, rows)``
    per stepper in lanes, as :func:`qr_intervals`; each then stands after its last interval.
    """
    lanes = lanes_mod.LANES
    results: list[tuple[int, np.ndarray] | None] = [None] * len(steppers)
    groups: list[list[tuple[int, tuple]]] = []  # (stepper index, its kernel arrays)
    for idx, stepper in enumerate(steppers):
        arrays = _lane_arrays(stepper)
        if arrays is None:
            continue
        for group in groups:
            other = group[0][1]
            if (len(group) < lanes and steppers[group[0][0]].sample_dt == stepper.sample_dt
                    and np.array_equal(other[1], arrays[1])
                    and np.array_equal(other[10], arrays[10])):  # fmt: skip
                group.append((idx, arrays))
                break
        else:
            groups.append([(idx, arrays)])
    for group in groups:
        if len(group) < 2:
            continue  # one system alone: the scalar loop (no lane round for seven idle lanes)
        members = [idx for idx, _ in group]
        ran = _run_lanes(
            [steppers[i] for i in members], [arrays for _, arrays in group], i0, n_steps,
            transient, dt, window, [lsums[i] for i in members], marks,
            [hists[i] for i in members],
        )  # fmt: skip
        for idx, res in zip(members, ran, strict=True):
            results[idx] = res
    return results


def _run_lanes(steppers, arrays_list, i0, n_steps, transient, dt, window, lsums, marks, hists):
    """The lanes of one group (same parameters and hop tables, ``arrays_list`` their kernel
    arrays): copied into the lane arrays, run, copied back (as :func:`qr_intervals`)."""
    lanes = lanes_mod.LANES
    n = len(steppers)
    w = np.zeros(lanes_mod.N_ROWS * lanes)
    iw = np.zeros(lanes_mod.N_IROWS * lanes, dtype=np.int64)
    n_relays = np.zeros(lanes, dtype=np.int64)
    off = 0
    for j, arrays in enumerate(arrays_list):
        st, ist, y, tf, lay = arrays[6], arrays[7], arrays[8], arrays[2], arrays[5]
        for row, col in _W_STATE:
            w[row * lanes + j] = st[col]
        for row, col in _IW_STATE:
            iw[row * lanes + j] = ist[col]
        for row, a, b in _Y_STATE:
            w[row * lanes + j] = y[a, b]
        iw[lanes_mod.OFF * lanes + j] = off
        iw[lanes_mod.GROUPS * lanes + j] = int(lay[0])
        off += tf.size
        n_relays[j] = arrays[13]
    first = arrays_list[0]
    par, mp, omega, period = first[1], first[10], float(first[14]), float(first[15])
    bound = float(steppers[0].engine.system.divergence_bound)
    sd = 0.0 if steppers[0].sample_dt is None else float(steppers[0].sample_dt)
    per = 2 + (int(dt / sd) if sd > 0.0 else 0) + 1
    rows = np.empty((lanes, (n_steps - i0) * per, 4))
    t_now = np.zeros(lanes)
    t_now[:n] = [float(s.elapsed) for s in steppers]
    i_at = np.full(lanes, i0, dtype=np.int64)
    n_rows = np.zeros(lanes, dtype=np.int64)
    lsum = np.zeros((lanes, 2))
    lsum[:n] = lsums
    hist = np.zeros((lanes, n_steps, 2))
    _lane_intervals(
        par, mp, np.concatenate([a[2] for a in arrays_list]), w, iw, n, n_relays, omega, period,
        bound, SWITCH_BUDGET_FLOOR, SWITCHES_PER_RELAY_AND_TIME, t_now, i_at, int(n_steps),
        float(transient), float(dt), float(window), sd, lsum, marks, hist, rows, n_rows,
    )  # fmt: skip
    out = []
    for j, (stepper, arrays) in enumerate(zip(steppers, arrays_list, strict=True)):
        done = int(i_at[j] - i0)
        if done:
            st, ist, y = arrays[6], arrays[7], arrays[8]
            for row, col in _W_STATE:
                st[col] = w[row * lanes + j]
            for row, col in _IW_STATE:
                ist[col] = iw[row * lanes + j]
            for row, a, b in _Y_STATE:
                y[a, b] = w[row * lanes + j]
            lsums[j][:] = lsum[j]
            marked = i0 + np.flatnonzero(marks[i0 : i_at[j]])
            hists[j][marked] = hist[j, marked]
            stepper.engine.kernel_moved()
            stepper.moved_to(float(t_now[j]), rows[j, : n_rows[j]].copy())
        out.append((done, rows[j, : n_rows[j]].copy()))
    return out
