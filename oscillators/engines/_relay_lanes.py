"""The relay kernel's event loop over several systems side by side, as SIMD lanes: ``LANES``
oscillators that share every parameter (ζ, Ω, C, the forcing phase) but their nested relay
tables, e.g. disorder realizations of one ensemble, with the two (δq, δv) tangent columns on.

Why: in the large ensembles of ``hyst paper --full`` almost every switch is a fast short hop
(97 % at N = 20 000), and the fast hop is branch-free arithmetic
(:func:`~oscillators.engines._relay_kernels.fast_hop`). One system at a time it is not
latency-bound (two systems interleaved in one scalar loop gained nothing); eight side by side
fill the vector units: about 2× per switch at N = 20 000, 1.4× at 5000, nothing at 1000
(``benchmarks/bench_lanes.py``).

Plain reading of :func:`advance_lanes`::

    repeat
        for every lane (one vectorized loop, _round): the fast-hop candidate to the threshold
            ahead and the tangent columns after it (fast_hop, fast_tangent)
        for every active lane, one after the other:
            at its stop (period time w[STOP])    -> report AT_STOP, pause the lane
            accepted candidate                   -> take it
            else                                 -> the full hop (kern.hop): Taylor hop or
                                                    exact flight, to a switch or to the stop
            at a switch: the nested table switch, then as settle_switch: a sliding motion
            (4), the switch budget (3) or a grazing switch (2) report and pause the lane,
            else the saltation of the tangent columns
    until some lane reported

Bit for bit :func:`~oscillators.engines._relay_kernels.advance_table` run on each lane alone
(the same hops, switches, tests and roundings): the candidate's arithmetic has nothing the
compiler could fuse differently in vector and scalar code (its multiply-adds are explicit
``fma``), and the rest is the event loop's own inline functions. The caller (a compiled loop,
e.g. :mod:`analysis.dynamics._relay_benettin`) owns the clock: it wraps a lane's period, sets
its next stop and switch budget, and resumes it by setting ``w[ACT]`` again.

What LLVM needs to vectorize the round (each measured, ``benchmarks/bench_lanes.py``): all lane
data in one flat array at constant offsets (row ``r`` of lane ``j`` at ``r * LANES + j``; one
array per quantity and the vectorizer gives up on the memory checks), both thresholds loaded
before the select, ``&`` rather than ``and``, ``error_model="numpy"``, and inlined helpers that
take and return numbers only.
"""

from __future__ import annotations

from numba import njit

from oscillators.engines import _relay_kernels as kern

__all__ = ["LANES", "advance_lanes", "N_ROWS", "N_IROWS"]

#: systems side by side (8 doubles: two AVX2 or one AVX-512 register per quantity)
LANES = 8

# float rows of the lane array w (lane j of row r at r * LANES + j): the event loop's state
# (kernel names S_*), the tangent columns (a = δq, b = δv), the stop (period time)
Q, V, TAU, COS, SIN, UP, DN, MV, IM, PQ, PJ, A0, A1, B0, B1, STOP = range(16)
# the round's candidate, and whether the lane runs (1.0) or is paused (0.0)
HF, V1, C1, S1, NA0, NA1, NB0, NB1, THETA, OK, ACT = range(16, 27)
N_ROWS = 27
# int rows of iw: nested index k, switches so far, the switch budget (count at which the lane
# stops), the lane's table offset in tf and its number of groups, the period index (the
# caller's), the lane's report (0 none, AT_STOP, or advance_table's status 2, 3, 4)
K, NSW, MAXSW, OFF, GROUPS, PERIOD, EVENT = range(7)
N_IROWS = 7
AT_STOP = 10


# a function of its own (not inlined): its loop then vectorizes on its own, measured
@njit(cache=True, fastmath=kern._CONTRACT, error_model="numpy")
def _round(coefs, zeta, omega, coupling, h_small, w):
    """Every lane's fast-hop candidate into rows HF..OK (no branches: one vectorized loop)."""
    for j in range(LANES):
        q = w[Q * LANES + j]
        v = w[V * LANES + j]
        up = w[UP * LANES + j]
        down = w[DN * LANES + j]
        # the table's next down threshold never lies above its next up one, so max / min
        # select the threshold ahead (as kern.hop's "up if v > 0 else down") from both loaded
        theta = max(up, down) if v > 0.0 else min(up, down)
        gap = theta - q
        horizon = w[STOP * LANES + j] - w[TAU * LANES + j]
        ok, hf, v1, c1, s1 = kern.fast_hop(
            coefs, omega, h_small, q, v, w[COS * LANES + j], w[SIN * LANES + j],
            coupling * w[MV * LANES + j], gap, horizon,
        )  # fmt: skip
        na0, na1, nb0, nb1 = kern.fast_tangent(
            coefs, zeta, hf, w[A0 * LANES + j], w[A1 * LANES + j], w[B0 * LANES + j],
            w[B1 * LANES + j],
        )  # fmt: skip
        # kern.hop's conditions for the fast hop, then its own
        ok = ok & (h_small > 0.0) & (v != 0.0) & (abs(gap) < h_small * abs(v))
        w[HF * LANES + j] = hf
        w[V1 * LANES + j] = v1
        w[C1 * LANES + j] = c1
        w[S1 * LANES + j] = s1
        w[NA0 * LANES + j] = na0
        w[NA1 * LANES + j] = na1
        w[NB0 * LANES + j] = nb0
        w[NB1 * LANES + j] = nb1
        w[THETA * LANES + j] = theta
        w[OK * LANES + j] = 1.0 if ok else 0.0


@njit(cache=True, fastmath=kern._CONTRACT, error_model="numpy", **kern._LOOP_OPTIONS)
def advance_lanes(par, mp, tf, w, iw, e):
    """Advance the running lanes (``w[ACT]`` = 1) until at least one reports (module
    docstring); returns the number of lanes that reported (their ``iw[EVENT]`` set, ``w[ACT]``
    cleared). ``par`` the kernel parameters every lane shares (:func:`kern.make_params`), ``mp``
    the hop tables, ``tf`` the nested tables of the lanes one after the other
    (``iw[OFF]``, ``iw[GROUPS]`` locate each: up | down | mval, as kern.nested_kernel_table),
    ``e`` scratch for the full hop's Taylor coefficients (``ORDER + 1``; compiled without
    reference counting, as the event loop, this function allocates nothing).
    """
    coefs = kern.hop_coefficients(mp)
    zeta = par[kern.P_ZETA]
    omega = par[kern.P_OMEGA]
    coupling = par[kern.P_C]
    h_small = par[kern.P_HS]
    slide = par[kern.P_SL]
    while True:
        _round(coefs, zeta, omega, coupling, h_small, w)
        reports = 0
        for j in range(LANES):
            if w[ACT * LANES + j] == 0.0:
                continue
            stop = w[STOP * LANES + j]
            if stop - w[TAU * LANES + j] <= 0.0:  # advance_table's "horizon <= 0"
                iw[EVENT * LANES + j] = AT_STOP
                w[ACT * LANES + j] = 0.0
                reports += 1
                continue
            mv = w[MV * LANES + j]
            if w[OK * LANES + j] != 0.0:
                d = 1 if w[V * LANES + j] > 0.0 else -1
                q = w[THETA * LANES + j]
                v = w[V1 * LANES + j]
                c = w[C1 * LANES + j]
                s = w[S1 * LANES + j]
                a0 = w[NA0 * LANES + j]
                a1 = w[NA1 * LANES + j]
                b0 = w[NB0 * LANES + j]
                b1 = w[NB1 * LANES + j]
                hf = w[HF * LANES + j]
                im = kern.fma(mv, hf, w[IM * LANES + j])
                tau = w[TAU * LANES + j] + hf
            else:
                d, q, v, tau, c, s, a0, a1, _, b0, b1, _, im = kern.hop(
                    par, coefs, mp, e, w[Q * LANES + j], w[V * LANES + j], w[TAU * LANES + j],
                    w[COS * LANES + j], w[SIN * LANES + j], w[UP * LANES + j], w[DN * LANES + j],
                    mv, stop, True, 2, w[A0 * LANES + j], w[A1 * LANES + j], 0.0,
                    w[B0 * LANES + j], w[B1 * LANES + j], 0.0, 0.0, 0.0, 0.0, w[IM * LANES + j],
                )  # fmt: skip
            w[Q * LANES + j] = q
            w[V * LANES + j] = v
            w[TAU * LANES + j] = tau
            w[COS * LANES + j] = c
            w[SIN * LANES + j] = s
            w[IM * LANES + j] = im
            w[A0 * LANES + j] = a0
            w[A1 * LANES + j] = a1
            w[B0 * LANES + j] = b0
            w[B1 * LANES + j] = b1
            if d == 0:  # the full hop reached the stop
                iw[EVENT * LANES + j] = AT_STOP
                w[ACT * LANES + j] = 0.0
                reports += 1
                continue
            # the nested table switch (as kern._table_switch, kind 0)
            k, w[UP * LANES + j], w[DN * LANES + j], mv_new, jump = kern.nested_switch(
                tf, iw[OFF * LANES + j], iw[GROUPS * LANES + j], iw[K * LANES + j], d
            )
            iw[K * LANES + j] = k
            w[MV * LANES + j] = mv_new
            nsw = iw[NSW * LANES + j] + 1
            iw[NSW * LANES + j] = nsw
            # kern.settle_switch without records: the lane pauses with its status
            status = 0
            if kern.slides(
                zeta, coupling, slide, q, v, c, mv_new, jump, d, w[PQ * LANES + j],
                w[PJ * LANES + j],
            ):  # fmt: skip
                status = 4
            else:
                w[PQ * LANES + j] = q
                w[PJ * LANES + j] = jump
                if nsw >= iw[MAXSW * LANES + j]:
                    status = 3
                elif coupling * jump != 0.0:
                    if v == 0.0:
                        status = 2
                    else:
                        w[B0 * LANES + j], w[B1 * LANES + j] = kern.saltation(
                            coupling, jump, v, a0, a1, b0, b1
                        )
            if status != 0:
                iw[EVENT * LANES + j] = status
                w[ACT * LANES + j] = 0.0
                reports += 1
        if reports:
            return reports
