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
non-decreasing along every list, and spin ``i`` sits at position ``rank[i]`` of every list; it
is a *member* of the list of its current neighbour sum. Per list one boundary ``B[g]`` = the
number of entries with ``t <= u`` (found by comparing thresholds: exact). Then a member of
list ``g`` at ``p < B[g]`` is up, one at ``p >= B[g]`` down (that is what relaxed means), and
a threshold test is an integer comparison: a spin whose sum becomes ``n_g`` is unstable at
``u`` iff ``rank < B[g]`` (it is down) or ``rank >= B[g]`` (it is up) — the same decision as
``u + (f + J·n) >= 0`` (a rounded sum has the sign of the exact one, and ``J·n`` is rounded
once, outside, as ``jn[g]``, so no fused multiply-add moves a threshold) because ``t_g`` is
monotone in ``p``. No spin is ever moved between lists: its membership is its sum, kept in
its record.

An event at the up trigger ``T`` relaxes at ``u = T`` (falling: at the largest float below
``T``, the relay convention ``u < β``): every ``B[g]`` moves over the entries it passes (a
sequential read of the sorted fields), then every passed entry that is a down member starts
an avalanche (breadth first, each spin at most once, the flip test above; ferromagnetic ``J``
makes the final state independent of the order: it is the state
:meth:`hysteresis.rfim.RandomFieldIsing.apply` reaches at that input). Then the two triggers:

* in the event's direction (rising: the least threshold of a down spin) by a merge of the
  lists from their boundaries, the head with the least threshold first, non-members skipped;
  the skipped entries lie below the trigger, so the next event passes them: every entry is
  read O(1) times per monotone stretch (Kuntz–Perković–Sethna);
* against it (rising: the greatest threshold of an up spin, ``<= u``): ``T`` itself if a
  passed entry at threshold ``T`` is still a member in the new state (the usual case: an
  avalanche's trigger spin whose sum did not change); else the greatest current threshold of
  the spins just flipped and of the spin that held this trigger after the previous event in
  this direction (kept with its list: valid while it is still a member, since during a rising
  stretch sums only grow and up spins' thresholds only fall); only if that spin has left its
  list, a merge of the lists downwards from their boundaries, bounded by the flipped spins'
  greatest threshold. Falling events are the mirror image.

The cost of an event is O(z·flips) for the avalanches plus the entries the merges read:
nothing is relisted, no bitset kept.

Layout: per spin one 8-byte record in site order (bits 0–31 ``rank``, 32–37 on a lattice the
faces the site lies on, so its neighbours need no division, 40–52 its list, bit 56 up), so an
avalanche reads and writes one word per neighbour and 10⁶ spins take 8 MB; the sorted fields
and ``order`` are the operator's own arrays, read along the lists. The spins are also kept as
the packed bits the operator's states hold.

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
    _wrap,
    hop,
    hop_coefficients,
    settle_switch,
)

__all__ = [
    "FACES",
    "I_NUP",
    "LIST",
    "MAX_LISTS",
    "PL_BITS",
    "S_U",
    "UP",
    "boundary_flags",
    "records",
    "refresh",
    "run_spins",
    "switch",
]

#: the input the spins are relaxed at / the number of up spins (slots unused by spins)
S_U = S_M
I_NUP = I_UP
#: the plan tuple: (recs, fsorted, order, jn, nxt, lat, offsets, adj, max_degree, bits, queue,
#: bound, old, heads, pos, cache, cachef); ``bits`` (the spins) at ``PL_BITS``
PL_BITS = 10

#: a spin's record (int64): bits 0–31 its rank, 32–37 on a lattice its faces (bit ``2a`` at
#: coordinate 0 of axis ``a``, ``2a + 1`` at ``L_a − 1``), 40–52 its list, bit 56 up
_RANK = 0xFFFFFFFF
FACES = 32
LIST = 40
_GMASK = 0x1FFF
UP = 1 << 56
#: the most lists (neighbour-sum values) a list index in 13 bits allows
MAX_LISTS = _GMASK + 1


def boundary_flags(lat: np.ndarray, n: int) -> np.ndarray:
    """The face flags (record bits 32–37) of the ``n`` sites of lattice ``lat``."""
    flags = np.zeros(n, dtype=np.int64)
    site = np.arange(n, dtype=np.int64)
    for a in range(int(lat[0])):
        length, stride = int(lat[1 + a]), int(lat[4 + a])
        c = (site // stride) % length
        flags |= (c == 0).astype(np.int64) << (2 * a)
        flags |= (c == length - 1).astype(np.int64) << (2 * a + 1)
    return flags


@njit(cache=True)
def records(recs, memb, bits, nup, gidx, lat, offsets, max_degree):  # pragma: no cover
    """Or the list (the neighbour sum ``2·nup − degree``) and the up bit of every spin into its
    record (rank and faces already there)."""
    for i in range(recs.size):
        deg = 2 * lat[0] if lat[0] > 0 else offsets[i + 1] - offsets[i]
        g = gidx[2 * nup[i] - deg + max_degree]
        up = (bits[i >> 3] >> (i & 7)) & 1
        recs[i] |= (g << LIST) | (up << 56)
        memb[recs[i] & _RANK] = 2 * g + up


@njit(cache=True, inline="always")
def _neighbours(i, rec, lat, offsets, adj, buf):  # pragma: no cover - compiled
    """Write the neighbours of ``i`` (record ``rec``) into ``buf`` (the order of
    :func:`hysteresis._rfim_kernels._neighbours`; on a lattice from the face flags, no
    division); returns their number."""
    nd = lat[0]
    if nd > 0:
        flags = rec >> FACES
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
def _scan(rising, best, spin, lst, memb, fsorted, order, jn, bound, heads, pos):
    # pragma: no cover - compiled
    """The trigger of the spins that flip in direction ``rising`` beyond ``best`` (rising: the
    least threshold of a down spin if below ``best``; falling: the greatest of an up spin if
    above it): a merge of the lists from their boundaries, the nearest head first, entries
    that are not members of their list skipped. Returns ``(threshold, spin, list)``, or
    ``(best, spin, lst)`` as given if none beats ``best``."""
    n = fsorted.size
    ng = jn.size
    for g in range(ng):
        p = bound[g] if rising else bound[g] - 1
        pos[g] = p
        if rising:
            heads[g] = -(fsorted[p] + jn[g]) if p < n else np.inf
        else:
            heads[g] = -(fsorted[p] + jn[g]) if p >= 0 else -np.inf
    want = 0 if rising else 1
    while True:
        g = 0
        for k in range(1, ng):
            if (heads[k] < heads[g]) if rising else (heads[k] > heads[g]):
                g = k
        t = heads[g]
        if not ((t < best) if rising else (t > best)):
            return best, spin, lst
        p = pos[g]
        if memb[p] == 2 * g + want:
            return t, order[p], g
        if rising:
            p += 1
            heads[g] = -(fsorted[p] + jn[g]) if p < n else np.inf
        else:
            p -= 1
            heads[g] = -(fsorted[p] + jn[g]) if p >= 0 else -np.inf
        pos[g] = p


@njit(cache=True)
def refresh(st, memb, fsorted, order, jn, bound, heads, pos, cache):  # pragma: no cover
    """Both triggers of the state relaxed at ``st[S_U]`` (boundaries ``bound`` current) into
    ``st[S_UP]``, ``st[S_DN]``; the kept against-trigger spin forgotten."""
    st[S_UP] = _scan(True, np.inf, -1, -1, memb, fsorted, order, jn, bound, heads, pos)[0]
    st[S_DN] = _scan(False, -np.inf, -1, -1, memb, fsorted, order, jn, bound, heads, pos)[0]
    cache[0] = 0


@njit(cache=True, inline="always")
def _avalanche(i, rising, recs, memb, bound, nxt, lat, offsets, adj, bits, queue, tail, buf):
    # pragma: no cover - compiled
    """Flip spin ``i`` (up if ``rising``) and every spin that becomes unstable at the input the
    boundaries ``bound`` hold (breadth first, each at most once; appended to the queue from
    ``tail``), keeping every spin's list (its neighbour sum) in its record; returns the new
    tail (flips = new tail − tail)."""
    want = 0 if rising else UP  # the spins that may follow: down ones rising, up ones falling
    row = 0 if rising else 1  # nxt[row, g]: the list after a neighbour's flip
    r = recs[i] ^ UP
    recs[i] = r
    memb[r & _RANK] ^= 1
    _flip(bits, i)
    queue[tail] = i
    head = tail
    tail += 1
    while head < tail:
        j = queue[head]
        head += 1
        deg = _neighbours(j, recs[j], lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            r = recs[m]
            g = (r >> LIST) & _GMASK
            g2 = nxt[row, g]
            r += (g2 - g) << LIST
            rank = r & _RANK
            if (r & UP) == want and (rank < bound[g2]) == rising:
                r ^= UP
                _flip(bits, m)
                queue[tail] = m
                tail += 1
            recs[m] = r
            memb[rank] = 2 * g2 + (r >> 56)
    return tail


@njit(cache=True, inline="always")
def _event(
    direction, st, ist, recs, memb, fsorted, order, jn, nxt, lat, offsets, adj, bits, queue,
    bound, old, heads, pos, cache, cachef, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """The avalanche at the current trigger in ``direction`` (module docstring); returns
    ``(ΔM, spins flipped)`` and leaves the next triggers and ``M`` in ``st``."""
    rising = direction > 0
    trig = st[S_UP] if rising else st[S_DN]
    u = trig if rising else np.nextafter(trig, -np.inf)
    n = fsorted.size
    ng = jn.size
    for g in range(ng):  # the boundaries at u (all of them before any flip test)
        jg = jn[g]
        b = bound[g]
        old[g] = b
        if rising:
            while b < n and -(fsorted[b] + jg) <= u:
                b += 1
        else:
            while b > 0 and -(fsorted[b - 1] + jg) > u:
                b -= 1
        bound[g] = b
    want = 0 if rising else 1
    tail = 0
    for g in range(ng):  # the passed entries that are unstable members start avalanches
        lo, hi = (old[g], bound[g]) if rising else (bound[g], old[g])
        for p in range(lo, hi):
            if memb[p] == 2 * g + want:
                tail = _avalanche(order[p], rising, recs, memb, bound, nxt, lat, offsets, adj,
                                  bits, queue, tail, buf)  # fmt: skip
    n_up = ist[I_NUP] + (tail if rising else -tail)
    ist[I_NUP] = n_up
    m_old = st[S_MV]
    st[S_MV] = (2 * n_up - n) / n  # the operator's own formula: the same float
    st[S_U] = u
    # the trigger in this direction: the merge from the boundaries
    fwd = _scan(rising, np.inf if rising else -np.inf, -1, -1, memb, fsorted, order, jn, bound,
                heads, pos)[0]  # fmt: skip
    # the trigger against it: a passed entry at the trigger still a member (flipped: it is on
    # the new side of u), else the flipped spins and the kept spin, else a bounded merge
    flipped = 1 if rising else 0
    back = np.nan
    for g in range(ng):
        jg = jn[g]
        if rising:
            p = bound[g] - 1
            while p >= old[g] and -(fsorted[p] + jg) == trig:
                if memb[p] == 2 * g + flipped:
                    back = trig
                    cache[1] = order[p]
                    cache[2] = g
                    break
                p -= 1
        else:
            p = bound[g]
            while p < old[g] and -(fsorted[p] + jg) == trig:
                if memb[p] == 2 * g + flipped:
                    back = trig
                    cache[1] = order[p]
                    cache[2] = g
                    break
                p += 1
        if back == trig:
            break
    if back != trig:
        best = -np.inf if rising else np.inf
        spin = -1
        lst = -1
        for q in range(tail):
            i = queue[q]
            r = recs[i]
            g = (r >> LIST) & _GMASK
            t = -(fsorted[r & _RANK] + jn[g])
            if (t > best) if rising else (t < best):
                best = t
                spin = i
                lst = g
        c = cache[1]
        if cache[0] == direction and ((recs[c] >> LIST) & _GMASK) == cache[2]:
            if (cachef[0] > best) if rising else (cachef[0] < best):
                best = cachef[0]
                spin = c
                lst = cache[2]
        else:
            best, spin, lst = _scan(not rising, best, spin, lst, memb, fsorted, order, jn, bound,
                                    heads, pos)  # fmt: skip
        back = best
        cache[1] = spin
        cache[2] = lst
    cache[0] = direction if cache[1] >= 0 else 0
    cachef[0] = back
    if rising:
        st[S_UP], st[S_DN] = fwd, back
    else:
        st[S_UP], st[S_DN] = back, fwd
    return st[S_MV] - m_old, tail


@njit(cache=True)
def switch(direction, st, ist, plan):  # pragma: no cover - compiled
    """One event outside the loop (a slide's exit, a trial on a copy): :func:`_event`."""
    (recs, memb, fsorted, order, jn, nxt, lat, offsets, adj, max_degree, bits, queue, bound,
     old, heads, pos, cache, cachef) = plan  # fmt: skip
    buf = np.empty(max(max_degree, 1), np.int64)
    return _event(
        direction, st, ist, recs, memb, fsorted, order, jn, nxt, lat, offsets, adj, bits, queue,
        bound, old, heads, pos, cache, cachef, buf,
    )  # fmt: skip


@njit(cache=True, fastmath=_CONTRACT)
def _advance(
    par, st, ist, tau_stop, tan_on, y, ntan, e, coefs, mp, rec_on, sw, sw_count, plan, buf,
):  # pragma: no cover - compiled  # fmt: skip
    """:func:`oscillators.engines._relay_kernels.advance_table` with the spins' plan: advance
    to period time ``tau_stop``; the same statuses."""
    (recs, memb, fsorted, order, jn, nxt, lat, offsets, adj, max_degree, bits, queue, bound,
     old, heads, pos, cache, cachef) = plan  # fmt: skip
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
            direction, st, ist, recs, memb, fsorted, order, jn, nxt, lat, offsets, adj, bits,
            queue, bound, old, heads, pos, cache, cachef, buf,
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
    buf = np.empty(max(plan[9], 1), np.int64)
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
