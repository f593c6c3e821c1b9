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
non-decreasing along every list; spin ``i`` sits at position ``rank[i]`` of every list and is a
*member* of the list of its current neighbour sum. Two things are kept:

* the lists themselves as one *membership word* per position, ``memb[p] = 2·list + up`` of
  the spin at ``p`` (one byte up to 127 lists), so that moving a spin between lists is one
  store (and two counts: per list and block of 64 positions its members, so that a search
  skips empty blocks), and the next member of a list is found 8 positions at a time (a
  zero-byte test on 64-bit words);
* per list two *candidates*: ``hi[g]``, its first member with ``t > u``, and ``lo[g]``, its
  last member with ``t <= u`` (consecutive members; in a state relaxed at ``u`` every member
  up to ``lo`` is up and every one from ``hi`` on down: that is what relaxed means), with their
  thresholds, so that::

    next up trigger   = min_g t_g(hi[g])        next down trigger = max_g t_g(lo[g])

An event at the up trigger ``t*`` relaxes at ``u = t*`` (falling: at the largest float below
``t*``, the relay convention ``u < β``): first every list's candidates move to ``u`` (each
member with ``t <= u`` passed: ``lo = hi``, ``hi`` = the next member, a search), then every
passed member that is down starts an avalanche (breadth first, each spin at most once). Every
flip changes its neighbours' sums by ``±2``: each neighbour's record and membership word
change, a candidate it was is replaced by the next member (a search), and its flip test needs
no threshold unless it lands between the candidates of its new list: below ``lo`` it is at
``t <= u``, above ``hi`` at ``t > u`` (``t`` is monotone along a list); between them it
becomes one of them, by its threshold compared with ``u`` — the same float test as
``u + (f + J·n) >= 0`` (a rounded sum has the sign of the exact one, and ``J·n`` is rounded
once, outside, as ``jn[g]``, so no fused multiply-add moves a threshold). Spins whose
triggers coincide exactly flip in the same event, and ferromagnetic ``J`` makes the final
state independent of the order — it is the state
:meth:`hysteresis.rfim.RandomFieldIsing.apply` reaches at that input. The cost of an event is
O(G + members passed + z·flips) plus a search per replaced candidate; no entry that is not a
member is read one at a time, no spin is relisted in a bitset.

Layout: per spin one record in site order, ``rank << shift | 2·list | up`` (uint32 on a lattice,
``shift`` 5: 4 MB for 10⁶ spins; int64 for more than 16 lists or 2²⁷ spins) and on a lattice a
byte of the faces the site lies on (so that its neighbours need no division); the membership
words in rank order (1 byte per spin); the sorted fields and ``order`` are the operator's own
arrays, read along the lists. The spins are also kept as the packed bits the operator's states
hold. The event loop is compiled without reference counting where numba allows it (the relay
kernel's ``_LOOP_OPTIONS``).

State slots: the relay kernel's float/int state layouts (``st``, ``ist``) with ``S_U`` (the
input the spins are relaxed at) and ``I_NUP`` (up spins) in slots the relay tables use for
their weight sums.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hysteresis._rfim_kernels import _flip
from oscillators.engines._relay_kernels import (
    _CONTRACT,
    _LOOP_OPTIONS,
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
    "LARGE_SHIFT",
    "MAX_LISTS",
    "PL_BITS",
    "S_U",
    "record_layout",
    "SMALL_SHIFT",
    "boundary_flags",
    "records",
    "refresh",
    "run_spins",
    "switch",
]

#: the input the spins are relaxed at / the number of up spins (slots unused by spins)
S_U = S_M
I_NUP = I_UP
#: the plan tuple: (recs, shift, memb, mw (memb as uint64 words), cnt, fsorted, order, jn, nxt,
#: faces, lat, offsets, adj, max_degree, bits, queue, start, end (scratch), cand, ctr);
#: ``bits`` (the spins) at ``PL_BITS``
PL_BITS = 14

#: a spin's record: bit 0 up, bits 1 to ``shift − 1`` its list, the rest its rank (uint32 with
#: ``shift`` 5 for up to 16 lists and 2²⁷ spins, else int64 with ``shift`` 14); the low
#: ``shift`` bits are its membership word ``2·list + up``
SMALL_SHIFT = 5
LARGE_SHIFT = 14
#: the most lists (neighbour-sum values) a list index in 13 bits allows
MAX_LISTS = 1 << (LARGE_SHIFT - 1)


def boundary_flags(lat: np.ndarray, n: int) -> np.ndarray:
    """The faces the ``n`` sites of lattice ``lat`` lie on (uint8: bit ``2a`` at coordinate 0
    of axis ``a``, ``2a + 1`` at ``L_a − 1``; empty for a graph), so that a site's neighbours
    need no division."""
    flags = np.zeros(n if lat[0] > 0 else 0, dtype=np.uint8)
    site = np.arange(flags.size, dtype=np.int64)
    for a in range(int(lat[0])):
        length, stride = int(lat[1 + a]), int(lat[4 + a])
        c = (site // stride) % length
        flags |= (c == 0).astype(np.uint8) << (2 * a)
        flags |= (c == length - 1).astype(np.uint8) << (2 * a + 1)
    return flags


def record_layout(n: int, lists: int) -> tuple[type, int]:
    """(dtype, shift) of the spins' records: uint32 when ``lists`` and ``n`` fit, else int64."""
    if lists <= 1 << (SMALL_SHIFT - 1) and n <= 1 << (32 - SMALL_SHIFT):
        return np.uint32, SMALL_SHIFT
    return np.int64, LARGE_SHIFT


@njit(cache=True)
def records(recs, shift, rank, memb, cnt, bits, nup, gidx, lat, offsets, max_degree):
    # pragma: no cover - compiled
    """Every spin's record (rank ``rank[i]``, the list of its neighbour sum ``2·nup − degree``,
    up), membership word and, with ``cnt`` (lists × blocks of 64 positions), its block's
    count of members of its list."""
    for i in range(recs.size):
        deg = 2 * lat[0] if lat[0] > 0 else offsets[i + 1] - offsets[i]
        g = gidx[2 * nup[i] - deg + max_degree]
        up = (bits[i >> 3] >> (i & 7)) & 1
        recs[i] = (rank[i] << shift) | (2 * g + up)
        memb[rank[i]] = 2 * g + up
        if cnt.size:
            cnt[g, rank[i] >> 6] += 1


@njit(cache=True, inline="always")
def _neighbours(i, faces, lat, offsets, adj, buf):  # pragma: no cover - compiled
    """Write the neighbours of ``i`` into ``buf`` (the order of
    :func:`hysteresis._rfim_kernels._neighbours`; on a lattice from the face flags, no
    division); returns their number."""
    nd = lat[0]
    if nd > 0:
        flags = faces[i]
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


_U0 = np.uint64(0)
_U1 = np.uint64(1)
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)
_LO = np.uint64(0x0101010101010101)
_HI = np.uint64(0x8080808080808080)
_EVEN = np.uint64(0xFEFEFEFEFEFEFEFE)


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
def _members(word, g):  # pragma: no cover - compiled
    """Bit 7 of every byte of ``word`` (8 membership bytes) that is a member of list ``g``
    (byte ``2g`` or ``2g + 1``): with bit 0 cleared the bytes are even, so the zero-byte test
    ``(x − 0x01…) & ~x & 0x80…`` has no false positives."""
    x = (word ^ (np.uint64(2 * g) * _LO)) & _EVEN
    return (x - _LO) & ~x & _HI


@njit(cache=True, inline="always")
def _next_member(memb, mw, cnt, g, p, n):  # pragma: no cover - compiled
    """The first position ``>= p`` and ``< n`` of a member of list ``g`` (``n``: none): the
    rest of ``p``'s block 8 entries at a time, the blocks without a member of ``g`` skipped by
    their counts, then the first block with one."""
    if p >= n:
        return n
    if mw.size == 0:  # two-byte membership words: one at a time
        while p < n and memb[p] >> 1 != g:
            p += 1
        return p
    last = (n - 1) >> 3
    w = p >> 3
    z = _members(mw[w], g) & (_ALL << np.uint64(8 * (p & 7)))
    while z == _U0:
        if w >= last:
            return n
        w += 1
        if w & 7 == 0:  # a new block: skip the blocks without a member
            blk = w >> 3
            while cnt[g, blk] == 0:
                blk += 1
                if 8 * blk > last:
                    return n
            w = 8 * blk
        z = _members(mw[w], g)
    q = 8 * w + (_ctz(z) >> 3)
    return q if q < n else n


@njit(cache=True, inline="always")
def _prev_member(memb, mw, cnt, g, p, stop):  # pragma: no cover - compiled
    """The last position ``<= p`` and ``>= stop >= 0`` of a member of list ``g`` (``-1``:
    none)."""
    if p < stop:
        return -1
    if mw.size == 0:
        while p >= stop and memb[p] >> 1 != g:
            p -= 1
        return p if p >= stop else -1
    w = p >> 3
    z = _members(mw[w], g) & (_ALL >> np.uint64(8 * (7 - (p & 7))))
    first = stop >> 3
    while z == _U0:
        if w <= first:
            return -1
        w -= 1
        if w & 7 == 7:  # a new block (from its end): skip the blocks without a member
            blk = w >> 3
            while cnt[g, blk] == 0:
                if 8 * blk <= first:
                    return -1
                blk -= 1
            w = min(w, 8 * blk + 7)
        z = _members(mw[w], g)
    q = 8 * w + (_msb(z) >> 3)
    return q if q >= stop else -1


@njit(cache=True, inline="always")
def _set_hi(g, p, memb, mw, cnt, fsorted, jn, cand, ctr):  # pragma: no cover - compiled
    """``hi[g] = cand[g]`` := the first member of list ``g`` at or after ``p`` (``N``: none),
    its threshold into ``ctr[g]`` (``+inf``: none)."""
    n = fsorted.size
    r = _next_member(memb, mw, cnt, g, p, n)
    cand[g] = r
    ctr[g] = -(fsorted[r] + jn[g]) if r < n else np.inf


@njit(cache=True, inline="always")
def _set_lo(g, p, memb, mw, cnt, fsorted, jn, cand, ctr):  # pragma: no cover - compiled
    """``lo[g] = cand[G + g]`` := the last member of list ``g`` at or before ``p`` (``-1``:
    none), its threshold into ``ctr[G + g]`` (``-inf``: none)."""
    ng = jn.size
    r = _prev_member(memb, mw, cnt, g, p, 0)
    cand[ng + g] = r
    ctr[ng + g] = -(fsorted[r] + jn[g]) if r >= 0 else -np.inf


@njit(cache=True)
def candidates(memb, mw, cnt, fsorted, jn, bound, cand, ctr):  # pragma: no cover - compiled
    """Every list's candidates from its boundary ``bound[g]`` (the number of its entries with
    ``t <= u``)."""
    for g in range(jn.size):
        _set_hi(g, bound[g], memb, mw, cnt, fsorted, jn, cand, ctr)
        _set_lo(g, bound[g] - 1, memb, mw, cnt, fsorted, jn, cand, ctr)


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
def refresh(st, ctr, ng):  # pragma: no cover - compiled
    """The next triggers into ``st[S_UP]``, ``st[S_DN]``."""
    st[S_UP], st[S_DN] = _triggers(ctr, ng)


@njit(cache=True, inline="always")
def _avalanche(
    i, rising, u, recs, shift, memb, mw, cnt, fsorted, jn, nxt, cand, ctr, faces, lat, offsets,
    adj, bits, queue, tail, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """Flip spin ``i`` (up if ``rising``) and every spin that becomes unstable at input ``u``
    (breadth first, each at most once; appended to the queue from ``tail``), keeping every
    spin's list (its neighbour sum) in its record and membership byte and the lists'
    candidates (current at ``u``); returns the new tail (flips = new tail − tail)."""
    ng = jn.size
    want = 0 if rising else 1  # the spins that may follow: down ones rising, up ones falling
    row = 0 if rising else 1  # nxt[row, g]: the list after a neighbour's flip
    low = (1 << shift) - 1
    r = recs[i] ^ 1
    recs[i] = r
    memb[r >> shift] ^= 1
    _flip(bits, i)
    queue[tail] = i
    head = tail
    tail += 1
    nd = lat[0]
    s0, s1, s2 = lat[4], lat[5], lat[6]  # a lattice's strides and wrap-arounds, in registers
    w0, w1, w2 = (lat[1] - 1) * s0, (lat[2] - 1) * s1, (lat[3] - 1) * s2
    while head < tail:
        j = queue[head]
        head += 1
        if nd == 3:
            fl = faces[j]
            buf[0] = j - w0 if fl & 2 else j + s0
            buf[1] = j + w0 if fl & 1 else j - s0
            buf[2] = j - w1 if fl & 8 else j + s1
            buf[3] = j + w1 if fl & 4 else j - s1
            buf[4] = j - w2 if fl & 32 else j + s2
            buf[5] = j + w2 if fl & 16 else j - s2
            deg = 6
        else:
            deg = _neighbours(j, faces, lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            r = recs[m]
            g = (r & low) >> 1
            g2 = nxt[row, g]
            r += (g2 - g) << 1
            rank = r >> shift
            # t <= u? Below lo or above hi of the new list by position (t is monotone along
            # it), between them by the threshold itself (then it becomes a candidate)
            between = cand[ng + g2] < rank < cand[g2]
            t = -(fsorted[rank] + jn[g2]) if between else 0.0
            below = t <= u if between else rank < cand[ng + g2]
            if (r & 1) == want and below == rising:
                r ^= 1
                _flip(bits, m)
                queue[tail] = m
                tail += 1
            recs[m] = r
            memb[rank] = r & low
            if cnt.size:  # the blocks' member counts
                cnt[g, rank >> 6] -= 1
                cnt[g2, rank >> 6] += 1
            # the candidates: the spin leaves list g (one of its candidates: the next member
            # replaces it) and joins list g2 (between its candidates: it becomes one)
            if cand[g] == rank:
                _set_hi(g, rank + 1, memb, mw, cnt, fsorted, jn, cand, ctr)
            elif cand[ng + g] == rank:
                _set_lo(g, rank - 1, memb, mw, cnt, fsorted, jn, cand, ctr)
            if between:
                if below:
                    cand[ng + g2] = rank
                    ctr[ng + g2] = t
                else:
                    cand[g2] = rank
                    ctr[g2] = t
    return tail


@njit(cache=True, inline="always")
def _event(
    direction, st, ist, recs, shift, memb, mw, cnt, fsorted, order, jn, nxt, faces, lat, offsets,
    adj, bits, queue, start, end, cand, ctr, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """The avalanche at the current trigger in ``direction`` (module docstring); returns
    ``(ΔM, spins flipped)`` and leaves the next triggers and ``M`` in ``st``."""
    rising = direction > 0
    u = st[S_UP] if rising else np.nextafter(st[S_DN], -np.inf)
    n = fsorted.size
    ng = jn.size
    for g in range(ng):  # every list's candidates at u (before any flip test): members passed
        if rising:
            start[g] = cand[g]
            while ctr[g] <= u:  # hi[g] passed: now the last member with t <= u
                r = cand[g]
                cand[ng + g] = r
                ctr[ng + g] = ctr[g]
                _set_hi(g, r + 1, memb, mw, cnt, fsorted, jn, cand, ctr)
            end[g] = cand[ng + g]
        else:
            end[g] = cand[ng + g]
            while ctr[ng + g] > u:  # lo[g] passed: now the first member with t > u
                r = cand[ng + g]
                cand[g] = r
                ctr[g] = ctr[ng + g]
                _set_lo(g, r - 1, memb, mw, cnt, fsorted, jn, cand, ctr)
            start[g] = cand[g]
    want = 0 if rising else 1
    tail = 0
    for g in range(ng):  # the passed members that are unstable start avalanches
        p = start[g]
        stop = end[g] + 1
        while p < stop:
            if memb[p] == 2 * g + want:
                tail = _avalanche(
                    order[p], rising, u, recs, shift, memb, mw, cnt, fsorted, jn, nxt, cand, ctr,
                    faces, lat, offsets, adj, bits, queue, tail, buf,
                )  # fmt: skip
            p = _next_member(memb, mw, cnt, g, p + 1, stop)
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
    (recs, shift, memb, mw, cnt, fsorted, order, jn, nxt, faces, lat, offsets, adj, max_degree,
     bits, queue, start, end, cand, ctr) = plan  # fmt: skip
    buf = np.empty(max(max_degree, 1), np.int64)
    return _event(
        direction, st, ist, recs, shift, memb, mw, cnt, fsorted, order, jn, nxt, faces, lat,
        offsets, adj, bits, queue, start, end, cand, ctr, buf,
    )  # fmt: skip


@njit(cache=True, fastmath=_CONTRACT, **_LOOP_OPTIONS)
def _advance(
    par, st, ist, tau_stop, tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count, plan, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.advance_table` with the spins' plan: advance
    to period time ``tau_stop``; the same statuses."""
    (recs, shift, memb, mw, cnt, fsorted, order, jn, nxt, faces, lat, offsets, adj, max_degree,
     bits, queue, start, end, cand, ctr) = plan  # fmt: skip
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
            direction, st, ist, recs, shift, memb, mw, cnt, fsorted, order, jn, nxt, faces, lat,
            offsets, adj, bits, queue, start, end, cand, ctr, buf,
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
    buf = np.empty(max(plan[13], 1), np.int64)
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
