"""Numba kernels of the oscillator coupled to interacting Ising spins (a random-field Ising
lattice: :class:`hysteresis.compiled_spins.CompiledSpins`).

Between events ``q'' + 2ζq' + q = cos φ + C·M`` is linear with ``M`` constant, and the motion
hops in closed form to the next threshold crossing exactly as for relays: the hop, the
switch bookkeeping (sliding test, switch budget, saltation ``δv += C·ΔM/v*·δq``, records) and
the clock are the relay kernel's own (:func:`oscillators.engines._relay_kernels.hop`,
:func:`~oscillators.engines._relay_kernels.settle_switch`), imported, not copied. What differs
is where the thresholds come from and what a switch does.

The plan (spins ``s_i``, local field ``h_i = u + (f_i + J·n_i)``, threshold
``t_i(n) = −(f_i + J·n)``; up iff ``u >= t_i(n_i)`` in a state relaxed at ``u``). Kuntz,
Perković and Sethna's sorted lists: list ``g`` holds the thresholds ``t_g(p) =
−(fsorted[p] + J·nvals[g])`` in the order ``p`` of the fields descending, so ``t_g`` is
non-decreasing along every list. Each spin is *listed* in the one list of its current
neighbour sum, a set bit at its position ``rank[i]`` in that list's hierarchical 64-ary bitset
(the relay kernel's bitset operations). ``ptr[g]`` counts the entries of list ``g`` with
``t <= u``. In a state relaxed at ``u`` a listed entry below ``ptr[g]`` is an up spin and one at
or above it a down spin (that is what relaxed means), so::

    next up trigger   = min_g t_g(first set bit of list g at or after ptr[g])
    next down trigger = max_g t_g(last set bit of list g before ptr[g])

— O(G·log₆₄ N) per event, whatever the spins did before (no trial run, no sweep). An event at
the up trigger ``t*`` relaxes at ``u = t*`` (falling: at the largest float below ``t*``, the
relay convention ``u < β``): every list's pointer moves to ``u`` (O(entries passed), in memory
order), every listed down spin whose entry the pointer passed starts an avalanche
(:func:`hysteresis._rfim_kernels.avalanche`, breadth first, each spin at most once), and the
neighbours of the flipped spins are re-listed by their new neighbour sums. The event is one jump
``ΔM`` of the oscillator, ``n_events`` grows by the spins flipped. Spins whose triggers coincide
exactly flip in the same event (their entries lie in the range passed), and ferromagnetic ``J``
makes the final state independent of the order — it is the state
:meth:`hysteresis.rfim.RandomFieldIsing.apply` reaches at that input.

State slots: the relay kernel's float/int state layouts (``st``, ``ist``) with ``S_U`` (the
input the spins are relaxed at) and ``I_NUP`` (up spins) in slots the relay tables use for
their weight sums.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hysteresis._rfim_kernels import _degree, _neighbours, _spin, avalanche
from oscillators.engines._relay_kernels import (
    _CONTRACT,
    I_MAXSW,
    I_N,
    I_NSW,
    I_UP,
    ORDER,
    P_T,
    S_COS,
    S_DN,
    S_IM,
    S_M,
    S_MV,
    S_PJ,
    S_PQ,
    S_Q,
    S_SIN,
    S_TAU,
    S_UP,
    S_V,
    _bs_clear,
    _bs_set,
    _ctz,
    _wrap,
    hop,
    hop_coefficients,
    settle_switch,
)

__all__ = ["S_U", "I_NUP", "bitset_layout", "build_lists", "refresh", "switch", "run_spins"]

#: the input the spins are relaxed at / the number of up spins (slots unused by spins)
S_U = S_M
I_NUP = I_UP

_U0 = np.uint64(0)
_U1 = np.uint64(1)
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)


def bitset_layout(n: int, lists: int) -> tuple[np.ndarray, int, int]:
    """(level offsets ``lay[g·levels + lv]``, levels, words) of ``lists`` hierarchical 64-ary
    bitsets over ``n`` positions; every level has one zero word of padding, so a search may read
    one word past a level's end."""
    sizes = [max(1, -(-n // 64))]
    while sizes[-1] > 1:
        sizes.append(-(-sizes[-1] // 64))
    lay = np.empty(lists * len(sizes), dtype=np.int64)
    at = 0
    for g in range(lists):
        for lv, size in enumerate(sizes):
            lay[g * len(sizes) + lv] = at
            at += size + 1
    return lay, len(sizes), at


@njit(cache=True, inline="always")
def _msb(x):  # pragma: no cover - compiled
    """Index of the highest set bit of a non-zero uint64."""
    x |= x >> np.uint64(1)
    x |= x >> np.uint64(2)
    x |= x >> np.uint64(4)
    x |= x >> np.uint64(8)
    x |= x >> np.uint64(16)
    x |= x >> np.uint64(32)
    return _ctz(x ^ (x >> _U1))


@njit(cache=True, inline="always")
def _next_set(sets, lay, base, levels, p, n):  # pragma: no cover - compiled
    """Smallest set position ``>= p`` of the bitset at ``lay[base:base+levels]``, or -1."""
    if p >= n:
        return -1
    idx = p
    lv = 0
    while True:
        w = sets[lay[base + lv] + (idx >> 6)] & (_ALL << np.uint64(idx & 63))
        if w != _U0:
            idx = (idx & ~63) + _ctz(w)
            break
        if lv + 1 == levels:
            return -1
        idx = (idx >> 6) + 1  # the next word of this level, a bit one level up
        lv += 1
    while lv > 0:
        lv -= 1
        idx = idx * 64 + _ctz(sets[lay[base + lv] + idx])
    return idx


@njit(cache=True, inline="always")
def _prev_set(sets, lay, base, levels, p):  # pragma: no cover - compiled
    """Largest set position ``<= p`` of the bitset at ``lay[base:base+levels]``, or -1."""
    if p < 0:
        return -1
    idx = p
    lv = 0
    while True:
        w = sets[lay[base + lv] + (idx >> 6)] & (_ALL >> np.uint64(63 - (idx & 63)))
        if w != _U0:
            idx = (idx & ~63) + _msb(w)
            break
        if lv + 1 == levels or (idx >> 6) == 0:
            return -1
        idx = (idx >> 6) - 1
        lv += 1
    while lv > 0:
        lv -= 1
        idx = idx * 64 + _msb(sets[lay[base + lv] + idx])
    return idx


@njit(cache=True)
def build_lists(
    nup, lat, offsets, max_degree, gidx, rank, listed, sets, lay, levels
):  # pragma: no cover
    """List every spin in the list of its neighbour sum ``2·nup − degree``."""
    for i in range(nup.size):
        g = gidx[2 * nup[i] - _degree(i, lat, offsets) + max_degree]
        listed[i] = g
        _bs_set(sets, lay, g * levels, levels, rank[i])


@njit(cache=True)
def candidates(fsorted, jn, sets, lay, levels, ptr, cand, ctr):  # pragma: no cover
    """The candidates of every list from its pointer ``ptr[g]`` (the entries with ``t <= u``):
    ``cand[g]`` its first set bit at or after the pointer (``N``: none), ``cand[G + g]`` its
    last set bit before it (``-1``: none), their thresholds in ``ctr`` (``±inf``: none)."""
    ng = jn.size
    for g in range(ng):
        _set_hi(g, ptr[g], fsorted, jn, sets, lay, levels, cand, ctr)
        _set_lo(g, ptr[g] - 1, fsorted, jn, sets, lay, levels, cand, ctr)


@njit(cache=True, inline="always")
def _set_hi(g, p, fsorted, jn, sets, lay, levels, cand, ctr):  # pragma: no cover
    """``cand[g]`` = the first set bit of list ``g`` at or after ``p`` (and its threshold)."""
    n = fsorted.size
    r = _next_set(sets, lay, g * levels, levels, p, n)
    if r >= 0:
        cand[g] = r
        ctr[g] = -(fsorted[r] + jn[g])
    else:
        cand[g] = n
        ctr[g] = np.inf


@njit(cache=True, inline="always")
def _set_lo(g, p, fsorted, jn, sets, lay, levels, cand, ctr):  # pragma: no cover
    """``cand[G + g]`` = the last set bit of list ``g`` at or before ``p`` (and its threshold)."""
    ng = jn.size
    r = _prev_set(sets, lay, g * levels, levels, p)
    cand[ng + g] = r
    ctr[ng + g] = -(fsorted[r] + jn[g]) if r >= 0 else -np.inf


@njit(cache=True, inline="always")
def _triggers(ctr, ng):  # pragma: no cover - compiled
    """(next up trigger, next down trigger): the least up candidate, the greatest down one."""
    up = ctr[0]
    down = ctr[ng]
    for g in range(1, ng):
        if ctr[g] < up:
            up = ctr[g]
        if ctr[ng + g] > down:
            down = ctr[ng + g]
    return up, down


@njit(cache=True)
def refresh(st, jn, ctr):  # pragma: no cover - compiled
    """The next triggers into ``st[S_UP]``, ``st[S_DN]``."""
    st[S_UP], st[S_DN] = _triggers(ctr, jn.size)


@njit(cache=True, inline="always")
def _relist(queue, t0, tail, u, fields, fsorted, coupling, jn, nup, listed, sets, lay, levels,
            rank, gidx, lat, offsets, adj, max_degree, cand, ctr, buf):  # pragma: no cover  # fmt: skip
    """Move the neighbours of the spins ``queue[t0:tail]`` to the lists of their new sums,
    keeping every list's candidates (consecutive set bits around ``u``) up to date."""
    ng = jn.size
    for q in range(t0, tail):
        deg = _neighbours(queue[q], lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            g = gidx[2 * nup[m] - _degree(m, lat, offsets) + max_degree]
            old = listed[m]
            if g != old:
                r = rank[m]
                _bs_clear(sets, lay, old * levels, levels, r)
                _bs_set(sets, lay, g * levels, levels, r)
                listed[m] = g
                if cand[old] == r:
                    _set_hi(old, r + 1, fsorted, jn, sets, lay, levels, cand, ctr)
                elif cand[ng + old] == r:
                    _set_lo(old, r - 1, fsorted, jn, sets, lay, levels, cand, ctr)
                if cand[ng + g] < r < cand[g]:  # between the candidates: it becomes one
                    t = -(fields[m] + jn[g])
                    if t <= u:
                        cand[ng + g] = r
                        ctr[ng + g] = t
                    else:
                        cand[g] = r
                        ctr[g] = t


@njit(cache=True, inline="always")
def _event(
    direction, st, ist, fields, fsorted, order, rank, jn, gidx, lat, offsets, adj, max_degree,
    coupling, bits, nup, listed, queue, sets, lay, levels, cand, ctr, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """The avalanche at the current trigger in ``direction`` (module docstring); returns
    ``(ΔM, spins flipped)`` and leaves the next triggers and ``M`` in ``st``."""
    rising = direction > 0
    u = st[S_UP] if rising else np.nextafter(st[S_DN], -np.inf)
    want = 0 if rising else 1
    n = fields.size
    ng = jn.size
    tail = 0
    for g in range(ng):
        if rising:
            while ctr[g] <= u:  # pass the entry: it is the last one with t <= u so far
                r = cand[g]
                cand[ng + g] = r
                ctr[ng + g] = ctr[g]
                _set_hi(g, r + 1, fsorted, jn, sets, lay, levels, cand, ctr)
                i = order[r]
                if _spin(bits, i) == want:
                    t0 = tail
                    tail = avalanche(
                        i, rising, u, bits, nup, fields, coupling, lat, offsets, adj, queue, tail,
                        buf,
                    )  # fmt: skip
                    _relist(queue, t0, tail, u, fields, fsorted, coupling, jn, nup, listed,
                            sets, lay, levels, rank, gidx, lat, offsets, adj, max_degree, cand,
                            ctr, buf)  # fmt: skip
        else:
            while ctr[ng + g] > u:  # pass the entry: it is the first one with t > u so far
                r = cand[ng + g]
                cand[g] = r
                ctr[g] = ctr[ng + g]
                _set_lo(g, r - 1, fsorted, jn, sets, lay, levels, cand, ctr)
                i = order[r]
                if _spin(bits, i) == want:
                    t0 = tail
                    tail = avalanche(
                        i, rising, u, bits, nup, fields, coupling, lat, offsets, adj, queue, tail,
                        buf,
                    )  # fmt: skip
                    _relist(queue, t0, tail, u, fields, fsorted, coupling, jn, nup, listed,
                            sets, lay, levels, rank, gidx, lat, offsets, adj, max_degree, cand,
                            ctr, buf)  # fmt: skip
    n_up = ist[I_NUP] + (tail if rising else -tail)
    ist[I_NUP] = n_up
    m_old = st[S_MV]
    st[S_MV] = (2 * n_up - n) / n  # the operator's own formula: the same float
    st[S_U] = u
    st[S_UP], st[S_DN] = _triggers(ctr, ng)
    return st[S_MV] - m_old, tail


@njit(cache=True)
def switch(
    direction, st, ist, fields, fsorted, order, rank, jn, gidx, lat, offsets, adj, max_degree,
    coupling, bits, nup, listed, queue, sets, lay, levels, cand, ctr,
):  # pragma: no cover - compiled  # fmt: skip
    """One event outside the loop (a slide's exit, a trial on a copy): :func:`_event`."""
    buf = np.empty(max(max_degree, 1), np.int64)
    return _event(
        direction, st, ist, fields, fsorted, order, rank, jn, gidx, lat, offsets, adj,
        max_degree, coupling, bits, nup, listed, queue, sets, lay, levels, cand, ctr, buf,
    )  # fmt: skip


@njit(cache=True, fastmath=_CONTRACT)
def _advance(
    par, st, ist, tau_stop, tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count, fields, fsorted,
    order, rank, jn, gidx, lat, offsets, adj, max_degree, coupling, bits, nup, listed, queue,
    sets, lay, levels, cand, ctr, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.advance_table` with the spins' plan: advance
    to period time ``tau_stop``; the same statuses."""
    q, v, tau, c, s = st[S_Q], st[S_V], st[S_TAU], st[S_COS], st[S_SIN]
    up, down, mv = st[S_UP], st[S_DN], st[S_MV]
    nsw = ist[I_NSW]
    nsw_max = ist[I_MAXSW]
    integral = st[S_IM]
    a0, a1, a2 = y[0, 0], y[0, 1], y[0, 2]
    b0, b1, b2 = y[1, 0], y[1, 1], y[1, 2]
    f0, f1, f2 = y[2, 0], y[2, 1], y[2, 2]
    status = 0
    prev_q = st[S_PQ]
    prev_jump = st[S_PJ]
    while tau_stop - tau > 0.0:
        direction, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral = hop(
            par, coefs, mp, e, q, v, tau, c, s, up, down, mv, tau_stop, tan_on, ntan,
            a0, a1, a2, b0, b1, b2, f0, f1, f2, integral,
        )  # fmt: skip
        if direction == 0:
            break
        jump, flips = _event(
            direction, st, ist, fields, fsorted, order, rank, jn, gidx, lat, offsets, adj,
            max_degree, coupling, bits, nup, listed, queue, sets, lay, levels, cand, ctr, buf,
        )  # fmt: skip
        up, down, mv = st[S_UP], st[S_DN], st[S_MV]
        nsw += flips  # n_events counts spin flips
        status, b0, b1, b2, prev_q, prev_jump = settle_switch(
            par, st, ist, q, v, c, tau, mv, jump, direction, nsw, nsw_max, prev_q, prev_jump,
            tan_on, ntan, a0, a1, a2, b0, b1, b2, rec_on, sw, sw_count,
        )  # fmt: skip
        if status != 0:
            break
    st[S_Q], st[S_V], st[S_TAU], st[S_COS], st[S_SIN] = q, v, tau, c, s
    st[S_IM] = integral
    st[S_PQ] = prev_q
    st[S_PJ] = prev_jump
    ist[I_NSW] = nsw
    if tan_on:
        y[0, 0], y[0, 1], y[0, 2] = a0, a1, a2
        y[1, 0], y[1, 1], y[1, 2] = b0, b1, b2
    return status


@njit(cache=True)
def run_spins(
    par, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw, sw_count, tan_on, y, ntan, mp,
    fields, fsorted, order, rank, jn, gidx, lat, offsets, adj, max_degree, coupling, bits, nup,
    listed, queue, sets, lay, levels, cand, ctr,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.run_table` with the spins' plan: advance through
    the targets (period index, period time) from ``i_start``; row i of ``out`` (if it has rows)
    gets (q, v, M) at target i. Returns (status, next target index)."""
    e = np.empty(ORDER + 1)
    coefs = hop_coefficients(mp)
    buf = np.empty(max(max_degree, 1), np.int64)
    sample = out.shape[0] > 0
    for i in range(i_start, tgt_n.shape[0]):
        while ist[I_N] < tgt_n[i]:
            status = _advance(
                par, st, ist, par[P_T], tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count,
                fields, fsorted, order, rank, jn, gidx, lat, offsets, adj, max_degree,
                coupling, bits, nup, listed, queue, sets, lay, levels, cand, ctr, buf,
            )  # fmt: skip
            if status != 0:
                return status, i
            _wrap(par, st, ist)
        status = _advance(
            par, st, ist, tgt_tau[i], tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count,
            fields, fsorted, order, rank, jn, gidx, lat, offsets, adj, max_degree, coupling,
            bits, nup, listed, queue, sets, lay, levels, cand, ctr, buf,
        )  # fmt: skip
        if status != 0:
            return status, i
        if sample:
            out[i, 0] = st[S_Q]
            out[i, 1] = st[S_V]
            out[i, 2] = st[S_MV]
    return 0, tgt_n.shape[0]
