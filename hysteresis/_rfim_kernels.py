"""Numba kernels of the zero-temperature random-field Ising model (:mod:`hysteresis.rfim`).

Spins ``s_i = ±1`` on a graph, random fields ``f_i``, ferromagnetic coupling ``J >= 0``; with
``n_i = Σ_{j ~ i} s_j`` the local field is ``h_i = u + (f_i + J·n_i)``. A down spin flips up
once ``h_i >= 0``, an up spin flips down once ``h_i < 0`` (the relay convention). Every spin
therefore has one *threshold* ``t_i(n) = −(f_i + J·n)`` that depends on its neighbours only
through ``n``: it is up in a stable state at input ``u`` iff ``u >= t_i(n_i)``. (The float
tests ``u + (f_i + J·n) >= 0`` and ``−(f_i + J·n) <= u`` agree exactly: a rounded sum of two
doubles has the sign of the exact sum, and negation is exact; the dimers' kernel forms the
same ``f_i + J·n``.)

Sorted lists (Kuntz, Perković and Sethna's idea): for every value ``n`` of the neighbour sum
the thresholds ``t_i(n)`` are ordered by ``−f_i`` whatever ``n`` is, so one permutation
``order`` (fields descending) sorts them all; list ``g`` is that order read with
``n = nvals[g]``. In a state relaxed at ``u`` every entry of list ``g`` with ``t <= u`` is
*passed*: if its spin has ``n_i = nvals[g]`` it is up. A binary search per list gives the
pointers at any ``u``, so the pointers are derived from ``(u, direction)``, never stored in a
state.

A rising sweep from ``u`` to ``u1``, plain-Python reading of :func:`sweep`::

    ptr[g] = number of entries of list g with t <= u            (binary search)
    loop:
        g = the list whose next entry has the least t            (merge of the lists)
        if t > u1: stop
            i = order[ptr[g]]; ptr[g] += 1
        if s_i == +1 or n_i != nvals[g]: continue                (not this spin's threshold)
        u = t                                                    (the avalanche's trigger)
        flip i up; stack = [i]
        while stack:                                             (relaxed completely at u)
            j = stack.pop()
            for every down neighbour m of j with u + (f_m + J n_m) >= 0: flip m up, push m
    u = u1

Without a record of the avalanches (:func:`sweep` with ``record`` false) the lists are not
merged: each list's passed entries are read in turn and every eligible one starts an avalanche
relaxed at the target input itself — the same final state (below), and the merge, a comparison
of G heads with an unpredictable winner per entry, was most of a sweep's time.

Skipped entries are never needed later: during a rising sweep ``n_i`` only grows, and a spin
whose ``n_i`` reaches a list it was skipped in is a neighbour of a spin that just flipped, so
the avalanche tests it. Every spin flips once per monotone sweep and each list is passed once:
O(flips + G·(entries passed)) with G lists (a 3-D lattice: G = 7). A falling sweep is the
mirror image: the lists are read downwards, the next trigger is the greatest ``t`` of an
up spin, and the avalanche happens at the largest float below it (``u < t``). Spins whose
triggers coincide exactly flip at one input: they count as one avalanche. Ferromagnetic ``J``
makes the final state of an avalanche independent of the order of the flips (and of how the
input got from ``u`` to ``u1``), so relaxing at each trigger gives the state at ``u1`` too.

Spins are stored as packed bits (``uint8``, little-endian within a byte, ``1`` = up): 1/8 byte
per spin. The kernels also keep ``nup[i]``, the number of up neighbours of every spin (derived
from the bits by :func:`count_up_neighbours`, then updated at every flip), so that a threshold
test reads two bytes, and ``fsorted = fields[order]``, so that the lists are read in memory
order. The graph is either a periodic hypercubic lattice (``lat = [ndim, L0, L1, L2, s0, s1,
s2]``, neighbours by index arithmetic, nothing stored) or compressed rows (``offsets``, ``adj``;
``lat[0] = 0``).

:func:`reference_sweep` is an independent plain-Python implementation (a heap of the down/up
spins' current thresholds with stale entries skipped) that the tests compare with.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import njit

__all__ = [
    "avalanche",
    "count_up_neighbours",
    "next_trigger",
    "reference_sweep",
    "stable",
    "sweep",
    "undo",
]

#: :func:`sweep` status: every input done / the event buffer is full (call again from ``k``)
DONE, FULL = 0, 1


@njit(cache=True, inline="always")
def _spin(bits, i):  # pragma: no cover - compiled
    return (bits[i >> 3] >> (i & 7)) & 1


@njit(cache=True, inline="always")
def _flip(bits, i):  # pragma: no cover - compiled
    bits[i >> 3] ^= np.uint8(1 << (i & 7))


@njit(cache=True, inline="always")
def _neighbours(i, lat, offsets, adj, buf):  # pragma: no cover - compiled
    """Write the neighbours of ``i`` into ``buf``; returns their number."""
    nd = lat[0]
    if nd > 0:
        k = 0
        for a in range(nd):
            length = lat[1 + a]
            stride = lat[4 + a]
            c = (i // stride) % length
            buf[k] = i + stride if c < length - 1 else i - (length - 1) * stride
            buf[k + 1] = i - stride if c > 0 else i + (length - 1) * stride
            k += 2
        return k
    start = offsets[i]
    stop = offsets[i + 1]
    for k in range(stop - start):
        buf[k] = adj[start + k]
    return stop - start


@njit(cache=True, inline="always")
def _degree(i, lat, offsets):  # pragma: no cover - compiled
    return 2 * lat[0] if lat[0] > 0 else offsets[i + 1] - offsets[i]


@njit(cache=True)
def count_up_neighbours(bits, lat, offsets, adj, max_degree, nup):  # pragma: no cover
    """``nup[i]`` = number of up neighbours of spin ``i`` (the cached part of the neighbour
    sum ``n_i = 2 nup_i − deg_i``)."""
    buf = np.empty(max(max_degree, 1), np.int64)
    for i in range(nup.size):
        deg = _neighbours(i, lat, offsets, adj, buf)
        up = 0
        for k in range(deg):
            up += _spin(bits, buf[k])
        nup[i] = up


@njit(cache=True)
def _pointers(fsorted, coupling, nvals, u, rising, ptr, heads):  # pragma: no cover
    """Pointers and head thresholds of every list at input ``u``: rising, the first entry with
    ``t > u``; falling, the last entry with ``t <= u`` (binary search: t grows along a list)."""
    size = fsorted.size
    for g in range(nvals.size):
        n = nvals[g]
        lo, hi = 0, size  # the count of entries with t <= u lies in [lo, hi]
        while lo < hi:
            mid = (lo + hi) >> 1
            if -(fsorted[mid] + coupling * n) <= u:
                lo = mid + 1
            else:
                hi = mid
        if rising:
            ptr[g] = lo
            heads[g] = -(fsorted[lo] + coupling * n) if lo < size else np.inf
        else:
            ptr[g] = lo - 1
            heads[g] = -(fsorted[lo - 1] + coupling * n) if lo > 0 else -np.inf


@njit(cache=True, inline="always")
def _advance(fsorted, coupling, nvals, ptr, heads, g, rising):  # pragma: no cover
    """Pass the head entry of list ``g``."""
    if rising:
        ptr[g] += 1
        m = ptr[g]
        heads[g] = -(fsorted[m] + coupling * nvals[g]) if m < fsorted.size else np.inf
    else:
        ptr[g] -= 1
        m = ptr[g]
        heads[g] = -(fsorted[m] + coupling * nvals[g]) if m >= 0 else -np.inf


@njit(cache=True, inline="always")
def _best(heads, rising):  # pragma: no cover - compiled
    """The list whose head comes next: least threshold rising, greatest falling."""
    g = 0
    for k in range(1, heads.size):
        if (heads[k] < heads[g]) if rising else (heads[k] > heads[g]):
            g = k
    return g


@njit(cache=True, inline="always")
def _eligible(i, n, want, bits, nup, lat, offsets):  # pragma: no cover - compiled
    """Spin ``i`` points the way that may flip (``want``) and its neighbour sum is ``n``."""
    return _spin(bits, i) == want and 2 * nup[i] - _degree(i, lat, offsets) == n


@njit(cache=True)
def avalanche(
    i, rising, u, bits, nup, fields, coupling, lat, offsets, adj, queue, tail, buf
):  # pragma: no cover - compiled
    """Flip spin ``i`` (up if ``rising``) and every spin that becomes unstable at input ``u``
    (breadth first; each spin flips at most once), appending them to ``queue`` from ``tail``
    and keeping ``nup`` up to date; returns the new tail (flips = new tail − tail)."""
    want = 0 if rising else 1  # the spins that may follow: down ones rising, up ones falling
    step = 1 if rising else -1
    _flip(bits, i)
    queue[tail] = i
    head = tail
    tail += 1
    while head < tail:
        j = queue[head]
        head += 1
        deg = _neighbours(j, lat, offsets, adj, buf)
        for k in range(deg):
            m = buf[k]
            nup[m] += step
            if _spin(bits, m) != want:
                continue
            nm = 2 * nup[m] - _degree(m, lat, offsets)
            h = u + (fields[m] + coupling * nm)
            if (h >= 0.0) if rising else (h < 0.0):
                _flip(bits, m)
                queue[tail] = m
                tail += 1
    return tail


@njit(cache=True)
def undo(bits, nup, queue, count, rising, lat, offsets, adj, max_degree):  # pragma: no cover
    """Flip back the spins ``queue[:count]`` flipped by a ``rising`` sweep (``nup`` too)."""
    buf = np.empty(max(max_degree, 1), np.int64)
    step = -1 if rising else 1
    for q in range(count):
        j = queue[q]
        _flip(bits, j)
        deg = _neighbours(j, lat, offsets, adj, buf)
        for k in range(deg):
            nup[buf[k]] += step


@njit(cache=True)
def sweep(
    bits, nup, n_up, u, inputs, k0, fields, fsorted, order, coupling, nvals, lat, offsets, adj,
    max_degree, queue, out, ev_input, ev_size, record,
):  # pragma: no cover - compiled  # fmt: skip
    """Follow ``inputs[k0:]`` from the state ``bits`` (with its up-neighbour counts ``nup``)
    relaxed at ``u`` (module docstring), every avalanche relaxed at its trigger input; ``out[k]``
    is ``M`` after input ``k``. The spins flipped by the last input are ``queue[:flips]``.

    With ``record`` each avalanche's trigger input (rising: the threshold; falling: the largest
    float below it) and size go to ``ev_input``/``ev_size``; when they are full the sweep stops
    before the next avalanche and returns ``FULL`` with the input ``u`` it stopped at (the
    state is relaxed there): call again from ``k``. Returns
    ``(status, k, u, n_up, n_events, flips)``.
    """
    n = fields.size
    ng = nvals.size
    ptr = np.empty(ng, np.int64)
    heads = np.empty(ng)
    buf = np.empty(max(max_degree, 1), np.int64)
    direction = 0  # the pointers hold for (u, direction); 0: not computed yet
    n_ev = 0
    tail = 0
    for k in range(k0, inputs.size):
        target = inputs[k]
        last = np.nan  # trigger input of the avalanche being counted (ties join it)
        tail = 0  # one monotone step flips every spin at most once
        if target != u:
            rising = target > u
            want = 0 if rising else 1
            if direction != (1 if rising else -1):
                _pointers(fsorted, coupling, nvals, u, rising, ptr, heads)
                direction = 1 if rising else -1
            if not record:
                # no trigger inputs wanted: relax at the target list by list, no merge (the
                # final state depends neither on the order of the flips nor on the path)
                for g in range(ng):
                    p = ptr[g]
                    jn = nvals[g]
                    while (
                        (p < n and -(fsorted[p] + coupling * jn) <= target)
                        if rising
                        else (p >= 0 and target < -(fsorted[p] + coupling * jn))
                    ):
                        i = order[p]
                        if _eligible(i, jn, want, bits, nup, lat, offsets):
                            new_tail = avalanche(
                                i, rising, target, bits, nup, fields, coupling, lat, offsets, adj,
                                queue, tail, buf,
                            )  # fmt: skip
                            n_up += new_tail - tail if rising else tail - new_tail
                            tail = new_tail
                        p += 1 if rising else -1
                    ptr[g] = p
                    inside = p < n if rising else p >= 0
                    heads[g] = (
                        -(fsorted[p] + coupling * jn) if inside else (np.inf if rising else -np.inf)
                    )
                u = target
                out[k] = (2 * n_up - n) / n
                continue
            while True:
                g = _best(heads, rising)
                t = heads[g]
                if not ((t <= target) if rising else (target < t)):
                    break
                i = order[ptr[g]]
                if _eligible(i, nvals[g], want, bits, nup, lat, offsets):
                    at = t if rising else np.nextafter(t, -np.inf)
                    if record and at != last:
                        if n_ev == ev_size.size:
                            return FULL, k, u, n_up, n_ev, tail
                        ev_input[n_ev] = at
                        ev_size[n_ev] = 0
                        n_ev += 1
                        last = at
                    u = at
                    new_tail = avalanche(
                        i, rising, u, bits, nup, fields, coupling, lat, offsets, adj, queue,
                        tail, buf,
                    )  # fmt: skip
                    c = new_tail - tail
                    tail = new_tail
                    n_up += c if rising else -c
                    if record:
                        ev_size[n_ev - 1] += c
                _advance(fsorted, coupling, nvals, ptr, heads, g, rising)
            u = target
        out[k] = (2 * n_up - n) / n
    return DONE, inputs.size, u, n_up, n_ev, tail


@njit(cache=True)
def next_trigger(
    bits, nup, u, rising, fsorted, order, coupling, nvals, lat, offsets
):  # pragma: no cover
    """The next switching input of the state ``bits`` relaxed at ``u``: rising, the least
    threshold of a down spin (``+inf`` if none); falling, the greatest threshold of an up spin
    (``-inf`` if none; the output jumps once the input falls below it)."""
    ng = nvals.size
    ptr = np.empty(ng, np.int64)
    heads = np.empty(ng)
    want = 0 if rising else 1
    _pointers(fsorted, coupling, nvals, u, rising, ptr, heads)
    while True:
        g = _best(heads, rising)
        t = heads[g]
        if not math.isfinite(t):
            return t
        if _eligible(order[ptr[g]], nvals[g], want, bits, nup, lat, offsets):
            return t
        _advance(fsorted, coupling, nvals, ptr, heads, g, rising)


@njit(cache=True)
def stable(bits, u, fields, coupling, lat, offsets, adj, max_degree):  # pragma: no cover
    """Index of the first spin that is unstable at input ``u`` (``-1``: the state is stable)."""
    buf = np.empty(max(max_degree, 1), np.int64)
    for i in range(fields.size):
        deg = _neighbours(i, lat, offsets, adj, buf)
        up = 0
        for k in range(deg):
            up += _spin(bits, buf[k])
        h = u + (fields[i] + coupling * (2 * up - deg))
        if (h >= 0.0) != (_spin(bits, i) == 1):
            return i
    return -1


# -- the plain-Python reference ------------------------------------------------------------------
def reference_sweep(
    spins: np.ndarray,
    u: float,
    inputs: np.ndarray,
    fields: np.ndarray,
    neighbours: list[list[int]],
    coupling: float,
) -> tuple[np.ndarray, np.ndarray, list[tuple[float, int]]]:
    """Plain-Python reading of :func:`sweep` with another data structure: per monotone stretch
    a heap of the current thresholds ``−(f_i + J·n_i)`` of the spins that may flip (stale
    entries skipped when popped). ``spins`` (±1, relaxed at ``u``) is not modified. Returns
    the outputs, the final spins and the avalanches ``(trigger input, size)``."""
    s = np.array(spins, dtype=np.int64)
    n = s.size
    out = np.empty(len(inputs))
    events: list[tuple[float, int]] = []

    def threshold(i: int) -> float:
        return -(fields[i] + coupling * sum(int(s[j]) for j in neighbours[i]))

    for k, target in enumerate(inputs):
        target = float(target)
        last = None  # trigger input of the avalanche being counted (ties join it)
        if target != u:
            sign = 1 if target > u else -1  # the orientation the flips give
            heap = [(sign * threshold(i), i) for i in range(n) if s[i] == -sign]
            heapq.heapify(heap)
            while heap:
                key, i = heap[0]
                t = sign * key
                if s[i] == sign or t != threshold(i):
                    heapq.heappop(heap)  # stale: flipped, or its neighbours changed
                    continue
                if not (t <= target if sign > 0 else target < t):
                    break
                at = t if sign > 0 else math.nextafter(t, -math.inf)
                u = at
                size = 0
                todo = [i]
                while todo:
                    j = todo.pop()
                    h = u + (fields[j] + coupling * sum(int(s[m]) for m in neighbours[j]))
                    if s[j] == sign or (h >= 0.0) != (sign > 0):
                        continue
                    s[j] = sign
                    size += 1
                    for m in neighbours[j]:
                        if s[m] == -sign:
                            todo.append(m)
                            heapq.heappush(heap, (sign * threshold(m), m))
                if at == last:
                    events[-1] = (at, events[-1][1] + size)
                else:
                    events.append((at, size))
                    last = at
            u = target
        out[k] = (2 * int(np.sum(s == 1)) - n) / n
    return out, s, events
