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
−(fsorted[p] + J·n_g)`` in the order ``p`` of the fields descending, so ``t_g`` is
non-decreasing along every list. Each spin is *listed* in the one list of its current
neighbour sum: a set bit at its position ``rank[i]`` in that list's hierarchical 64-ary bitset.
In a state relaxed at ``u`` a listed entry with ``t <= u`` is an up spin and one with ``t > u``
a down spin (that is what relaxed means), so every list has two *candidates*, consecutive set
bits: ``hi[g]``, its first set bit with ``t > u``, and ``lo[g]``, the last with ``t <= u``, and::

    next up trigger   = min_g t_g(hi[g])        next down trigger = max_g t_g(lo[g])

The candidates and their thresholds are kept, not searched for: an event at the up trigger
``t*`` relaxes at ``u = t*`` (falling: at the largest float below ``t*``, the relay convention
``u < β``); in every list the entries from ``hi[g]`` on with ``t <= u`` are passed (``lo = hi``,
``hi`` = the next set bit: one bitset search), and each down spin among them starts an
avalanche (breadth first, each spin at most once). Every flip changes the neighbour sums of the
spin's neighbours by ``±2`` (kept in their records) and a neighbour flips if its threshold has
crossed ``u`` (the same test as ``u + (f + J·n) >= 0``: a rounded sum has the sign of the exact
one, and ``J·n`` is rounded once, outside, as ``jn[g]``, so no fused multiply-add can change a
threshold); after the avalanche each neighbour whose sum changed is moved once to the list of
its new sum (clear one bit, set one bit), a candidate it was is replaced by the next set bit (a
search), and if its new position falls between the candidates of its new list it becomes one
(``lo`` if its threshold is ``<= u``, else ``hi``). Spins whose triggers
coincide exactly flip in the same event (passed in the same pass), and ferromagnetic ``J``
makes the final state independent of the order — it is the state
:meth:`hysteresis.rfim.RandomFieldIsing.apply` reaches at that input. The cost of an event is
O(G + z·flips) plus a bitset search (O(log₆₄ N), usually one word) per passed entry and per
replaced candidate — no sweep over the lists, no search per list.

Layout, for few cache misses per flip (the lattice is far larger than the caches and an
avalanche's spins are scattered over the sorted lists): per spin one 16-byte record in site
order (``recf[2i]`` = ``f_i``, ``reci[4i + 2]`` = ``rank[i]``, ``reci[4i + 3]`` = its list ``g``
(bits 0–12; bits 13–25 the list of its current sum) and, on a lattice, flags of the faces the
site lies on (bits 26–31), so its neighbours need no division; two views of one buffer, each
slot read through one view), so a neighbour's field, position and list share a cache line;
the lists' bitsets interleaved (word ``w`` of level ``lv`` of list ``g`` at
``lay[lv] + w·stride + g``, ``stride = 8`` for up to 8 lists: one aligned 64-byte line holds the
word of every list), so moving a spin between lists touches one line. The spins themselves
are the packed bits the operator's states hold.

State slots: the relay kernel's float/int state layouts (``st``, ``ist``) with ``S_U`` (the
input the spins are relaxed at) and ``I_NUP`` (up spins) in slots the relay tables use for
their weight sums.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hysteresis._rfim_kernels import _flip, _spin
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
    _ctz,
    _wrap,
    hop,
    hop_coefficients,
    settle_switch,
)

__all__ = [
    "I_NUP",
    "FACES",
    "MAX_LISTS",
    "PL_BITS",
    "S_U",
    "bitset_layout",
    "boundary_flags",
    "build_lists",
    "refresh",
    "run_spins",
    "switch",
]

#: the input the spins are relaxed at / the number of up spins (slots unused by spins)
S_U = S_M
I_NUP = I_UP
#: the plan tuple: (recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj, max_degree,
#: bits, queue, sets, lay, stride, levels, cand, ctr); ``bits`` (the spins) at ``PL_BITS``
PL_BITS = 11

_U0 = np.uint64(0)
_U1 = np.uint64(1)
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)


def bitset_layout(n: int, lists: int) -> tuple[np.ndarray, int, int, int]:
    """(level offsets ``lay[lv]``, stride, levels, words) of ``lists`` interleaved hierarchical
    64-ary bitsets over ``n`` positions (word ``w`` of level ``lv`` of list ``g`` at
    ``lay[lv] + w·stride + g``); every level has one zero row of padding, so a search may read
    one row past a level's end."""
    stride = 8 if lists <= 8 else lists
    sizes = [max(1, -(-n // 64))]
    while sizes[-1] > 1:
        sizes.append(-(-sizes[-1] // 64))
    lay = np.empty(len(sizes), dtype=np.int64)
    at = 0
    for lv, size in enumerate(sizes):
        lay[lv] = at
        at += (size + 1) * stride
    return lay, stride, len(sizes), at


#: ``reci[4i + 3]``: bits 0–12 the list the spin is listed in, bits 13–25 the list of its
#: current neighbour sum (they differ only inside an avalanche), bits 26–31 on a lattice the
#: faces the site lies on: bit ``2a`` at coordinate 0 of axis ``a``, bit ``2a + 1`` at ``L_a − 1``
_LIST = 0x1FFF
_SUM = 13
FACES = 26
#: the most lists (neighbour-sum values) a list index in 13 bits allows
MAX_LISTS = _LIST + 1


def boundary_flags(lat: np.ndarray, n: int) -> np.ndarray:
    """The face flags (``reci[4i + 3] >> 26``) of the ``n`` sites of lattice ``lat``."""
    flags = np.zeros(n, dtype=np.int32)
    site = np.arange(n, dtype=np.int64)
    for a in range(int(lat[0])):
        length, stride = int(lat[1 + a]), int(lat[4 + a])
        c = (site // stride) % length
        flags |= (c == 0).astype(np.int32) << (2 * a)
        flags |= (c == length - 1).astype(np.int32) << (2 * a + 1)
    return flags


@njit(cache=True, inline="always")
def _neighbours(i, reci, lat, offsets, adj, buf):  # pragma: no cover - compiled
    """Write the neighbours of ``i`` into ``buf`` (the order of
    :func:`hysteresis._rfim_kernels._neighbours`; on a lattice from the face flags, no
    division); returns their number."""
    nd = lat[0]
    if nd > 0:
        flags = reci[4 * i + 3] >> FACES
        k = 0
        for a in range(nd):
            stride = lat[4 + a]
            span = (lat[1 + a] - 1) * stride
            buf[k] = i - span if (flags >> (2 * a + 1)) & 1 else i + stride
            buf[k + 1] = i + span if (flags >> (2 * a)) & 1 else i - stride
            k += 2
        return k
    start = offsets[i]
    stop = offsets[i + 1]
    for k in range(stop - start):
        buf[k] = adj[start + k]
    return stop - start


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
def _next_set(sets, lay, stride, g, levels, p, n):  # pragma: no cover - compiled
    """Smallest set position ``>= p`` of list ``g``'s bitset, or -1."""
    if p >= n:
        return -1
    idx = p
    lv = 0
    while True:
        w = sets[lay[lv] + (idx >> 6) * stride + g] & (_ALL << np.uint64(idx & 63))
        if w != _U0:
            idx = (idx & ~63) + _ctz(w)
            break
        if lv + 1 == levels:
            return -1
        idx = (idx >> 6) + 1  # the next word of this level, a bit one level up
        lv += 1
    while lv > 0:
        lv -= 1
        idx = idx * 64 + _ctz(sets[lay[lv] + idx * stride + g])
    return idx


@njit(cache=True, inline="always")
def _prev_set(sets, lay, stride, g, levels, p):  # pragma: no cover - compiled
    """Largest set position ``<= p`` of list ``g``'s bitset, or -1."""
    if p < 0:
        return -1
    idx = p
    lv = 0
    while True:
        w = sets[lay[lv] + (idx >> 6) * stride + g] & (_ALL >> np.uint64(63 - (idx & 63)))
        if w != _U0:
            idx = (idx & ~63) + _msb(w)
            break
        if lv + 1 == levels or (idx >> 6) == 0:
            return -1
        idx = (idx >> 6) - 1
        lv += 1
    while lv > 0:
        lv -= 1
        idx = idx * 64 + _msb(sets[lay[lv] + idx * stride + g])
    return idx


@njit(cache=True, inline="always")
def _bs_set(sets, lay, stride, g, levels, idx):  # pragma: no cover - compiled
    for lv in range(levels):
        pos = lay[lv] + (idx >> 6) * stride + g
        w = sets[pos]
        sets[pos] = w | (_U1 << np.uint64(idx & 63))
        if w != _U0:
            return  # the summary bits above are set already
        idx >>= 6


@njit(cache=True, inline="always")
def _bs_clear(sets, lay, stride, g, levels, idx):  # pragma: no cover - compiled
    for lv in range(levels):
        pos = lay[lv] + (idx >> 6) * stride + g
        w = sets[pos] & ~(_U1 << np.uint64(idx & 63))
        sets[pos] = w
        if w != _U0:
            return  # the word still holds a set bit: the summary bit above stays
        idx >>= 6


@njit(cache=True)
def build_lists(reci, gidx, nvals, nup, lat, offsets, max_degree, sets, lay, stride, levels):
    # pragma: no cover - compiled
    """List every spin in the list of its neighbour sum ``2·nup − degree``: ``reci[4i + 3]``
    and a set bit at ``reci[4i + 2]`` (its rank) in that list."""
    for i in range(nup.size):
        deg = 2 * lat[0] if lat[0] > 0 else offsets[i + 1] - offsets[i]
        g = gidx[2 * nup[i] - deg + max_degree]
        reci[4 * i + 3] |= g | (g << _SUM)
        _bs_set(sets, lay, stride, g, levels, reci[4 * i + 2])


@njit(cache=True, inline="always")
def _set_hi(g, p, fsorted, jn, sets, lay, stride, levels, cand, ctr):  # pragma: no cover
    """``hi[g] = cand[g]`` := the first set bit of list ``g`` at or after ``p`` (``N``: none),
    its threshold into ``ctr[g]`` (``+inf``: none)."""
    n = fsorted.size
    r = _next_set(sets, lay, stride, g, levels, p, n)
    if r >= 0:
        cand[g] = r
        ctr[g] = -(fsorted[r] + jn[g])
    else:
        cand[g] = n
        ctr[g] = np.inf


@njit(cache=True, inline="always")
def _set_lo(g, p, fsorted, jn, sets, lay, stride, levels, cand, ctr):  # pragma: no cover
    """``lo[g] = cand[G + g]`` := the last set bit of list ``g`` at or before ``p`` (``-1``:
    none), its threshold into ``ctr[G + g]`` (``-inf``: none)."""
    ng = jn.size
    r = _prev_set(sets, lay, stride, g, levels, p)
    cand[ng + g] = r
    ctr[ng + g] = -(fsorted[r] + jn[g]) if r >= 0 else -np.inf


@njit(cache=True)
def candidates(fsorted, jn, sets, lay, stride, levels, ptr, cand, ctr):  # pragma: no cover
    """Every list's candidates from its pointer ``ptr[g]`` (the number of its entries with
    ``t <= u``)."""
    for g in range(jn.size):
        _set_hi(g, ptr[g], fsorted, jn, sets, lay, stride, levels, cand, ctr)
        _set_lo(g, ptr[g] - 1, fsorted, jn, sets, lay, stride, levels, cand, ctr)


@njit(cache=True, inline="always")
def _triggers(ctr, ng):  # pragma: no cover - compiled
    """(next up trigger, next down trigger): the least ``hi`` threshold, the greatest ``lo``."""
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
def _avalanche(
    i, rising, u, recf, reci, jn, nvals, gidx, lat, offsets, adj, max_degree, bits, queue, tail,
    buf,
):  # pragma: no cover - compiled  # fmt: skip
    """Flip spin ``i`` (up if ``rising``) and every spin that becomes unstable at input ``u``
    (breadth first, each at most once; appended to the queue from ``tail``), keeping every
    spin's current list (its neighbour sum) in its record; returns the new tail (flips = new
    tail − tail). The lists' bitsets are brought up to date afterwards (:func:`_relist`)."""
    want = 0 if rising else 1  # the spins that may follow: down ones rising, up ones falling
    dn = 2 if rising else -2  # the change of a neighbour's sum
    _flip(bits, i)
    queue[tail] = i
    head = tail
    tail += 1
    while head < tail:
        j = queue[head]
        head += 1
        deg = _neighbours(j, reci, lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            word = reci[4 * m + 3]
            old = (word >> _SUM) & _LIST
            g = gidx[nvals[old] + dn + max_degree]
            reci[4 * m + 3] = word + ((g - old) << _SUM)
            if _spin(bits, m) == want and (-(recf[2 * m] + jn[g]) <= u) == rising:
                _flip(bits, m)
                queue[tail] = m
                tail += 1
    return tail


@njit(cache=True, inline="always")
def _relist(
    t0, tail, u, recf, reci, fsorted, jn, lat, offsets, adj, queue, sets, lay, stride, levels,
    cand, ctr, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """Move the neighbours of the spins ``queue[t0:tail]`` whose sums changed to the lists of
    their new sums (once each, however many of their neighbours flipped), keeping the
    candidates (module docstring)."""
    ng = jn.size
    for q in range(t0, tail):
        deg = _neighbours(queue[q], reci, lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            word = reci[4 * m + 3]
            old = word & _LIST
            g = (word >> _SUM) & _LIST
            if g == old:
                continue
            reci[4 * m + 3] = word + (g - old)
            r = reci[4 * m + 2]
            _bs_clear(sets, lay, stride, old, levels, r)
            _bs_set(sets, lay, stride, g, levels, r)
            if cand[old] == r:
                _set_hi(old, r + 1, fsorted, jn, sets, lay, stride, levels, cand, ctr)
            elif cand[ng + old] == r:
                _set_lo(old, r - 1, fsorted, jn, sets, lay, stride, levels, cand, ctr)
            if cand[ng + g] < r < cand[g]:  # between the candidates of its list: one of them
                t = -(recf[2 * m] + jn[g])
                if t <= u:  # up in the state relaxed at u
                    cand[ng + g] = r
                    ctr[ng + g] = t
                else:
                    cand[g] = r
                    ctr[g] = t


@njit(cache=True, inline="always")
def _event(
    direction, st, ist, recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj, max_degree,
    bits, queue, sets, lay, stride, levels, cand, ctr, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """The avalanche at the current trigger in ``direction`` (module docstring); returns
    ``(ΔM, spins flipped)`` and leaves the next triggers and ``M`` in ``st``."""
    rising = direction > 0
    u = st[S_UP] if rising else np.nextafter(st[S_DN], -np.inf)
    want = 0 if rising else 1
    n = fsorted.size
    ng = jn.size
    tail = 0
    for g in range(ng):
        if rising:
            while ctr[g] <= u:  # pass hi[g]: now the last entry with t <= u
                r = cand[g]
                cand[ng + g] = r
                ctr[ng + g] = ctr[g]
                _set_hi(g, r + 1, fsorted, jn, sets, lay, stride, levels, cand, ctr)
                i = order[r]
                if _spin(bits, i) == want:
                    t0 = tail
                    tail = _avalanche(
                        i, rising, u, recf, reci, jn, nvals, gidx, lat, offsets, adj, max_degree,
                        bits, queue, tail, buf,
                    )  # fmt: skip
                    _relist(
                        t0, tail, u, recf, reci, fsorted, jn, lat, offsets, adj, queue, sets, lay,
                        stride, levels, cand, ctr, buf,
                    )  # fmt: skip
        else:
            while ctr[ng + g] > u:  # pass lo[g]: now the first entry with t > u
                r = cand[ng + g]
                cand[g] = r
                ctr[g] = ctr[ng + g]
                _set_lo(g, r - 1, fsorted, jn, sets, lay, stride, levels, cand, ctr)
                i = order[r]
                if _spin(bits, i) == want:
                    t0 = tail
                    tail = _avalanche(
                        i, rising, u, recf, reci, jn, nvals, gidx, lat, offsets, adj, max_degree,
                        bits, queue, tail, buf,
                    )  # fmt: skip
                    _relist(
                        t0, tail, u, recf, reci, fsorted, jn, lat, offsets, adj, queue, sets, lay,
                        stride, levels, cand, ctr, buf,
                    )  # fmt: skip
    n_up = ist[I_NUP] + (tail if rising else -tail)
    ist[I_NUP] = n_up
    m_old = st[S_MV]
    st[S_MV] = (2 * n_up - n) / n  # the operator's own formula: the same float
    st[S_U] = u
    st[S_UP], st[S_DN] = _triggers(ctr, ng)
    return st[S_MV] - m_old, tail


@njit(cache=True)
def switch(direction, st, ist, plan):  # pragma: no cover - compiled
    """One event outside the loop (a slide's exit, a trial on a copy): :func:`_event`."""
    (recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj, max_degree, bits, queue,
     sets, lay, stride, levels, cand, ctr) = plan  # fmt: skip
    buf = np.empty(max(max_degree, 1), np.int64)
    return _event(
        direction, st, ist, recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj,
        max_degree, bits, queue, sets, lay, stride, levels, cand, ctr, buf,
    )  # fmt: skip


@njit(cache=True, fastmath=_CONTRACT)
def _advance(
    par, st, ist, tau_stop, tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count, plan, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.advance_table` with the spins' plan: advance
    to period time ``tau_stop``; the same statuses."""
    (recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj, max_degree, bits, queue,
     sets, lay, stride, levels, cand, ctr) = plan  # fmt: skip
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
            direction, st, ist, recf, reci, fsorted, order, jn, nvals, gidx, lat, offsets, adj,
            max_degree, bits, queue, sets, lay, stride, levels, cand, ctr, buf,
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
    par, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw, sw_count, tan_on, y, ntan, mp, plan
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.run_table` with the spins' plan: advance through
    the targets (period index, period time) from ``i_start``; row i of ``out`` (if it has rows)
    gets (q, v, M) at target i. Returns (status, next target index)."""
    e = np.empty(ORDER + 1)
    coefs = hop_coefficients(mp)
    buf = np.empty(max(plan[10], 1), np.int64)
    sample = out.shape[0] > 0
    for i in range(i_start, tgt_n.shape[0]):
        while ist[I_N] < tgt_n[i]:
            status = _advance(
                par, st, ist, par[P_T], tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count,
                plan, buf,
            )  # fmt: skip
            if status != 0:
                return status, i
            _wrap(par, st, ist)
        status = _advance(
            par, st, ist, tgt_tau[i], tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count,
            plan, buf,
        )  # fmt: skip
        if status != 0:
            return status, i
        if sample:
            out[i, 0] = st[S_Q]
            out[i, 1] = st[S_V]
            out[i, 2] = st[S_MV]
    return 0, tgt_n.shape[0]
