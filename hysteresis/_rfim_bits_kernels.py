"""Numba kernels of the 1-bit-per-spin random-field Ising lattice (:mod:`hysteresis.rfim_bits`).

Spins: bit ``i & 63`` of ``uint64`` word ``i >> 6`` (``1`` up), nothing else per spin. The
lattice has side lengths ``(L0, L1, L2)`` (a 1-D or 2-D lattice is padded with leading 1s; an
axis of length 1 contributes no neighbours), site ``(c0, c1, c2)`` is spin
``(c0·L1 + c1)·L2 + c2``, neighbours by periodic index arithmetic, ``z`` = 2 × (axes of length
>= 3).

Random fields regenerated on demand from a stateless counter-based generator:

    h_i = mix(mix(i·γ + k0) XOR k1)          (mix: SplitMix64's output function, γ its Weyl
                                              constant; k0, k1 from the seed by SplitMix64)
    m_i = h_i >> 12                           (52 bits)
    U_i = (m_i + 1/2)·2⁻⁵²                    (exact; in [2⁻⁵³, 1 − 2⁻⁵³])
    f_i = disorder · Φ⁻¹(U_i)                 (Φ⁻¹: Wichura's AS241 PPND16)

AS241 is a rational approximation of the normal quantile with relative error about 1e-16
(Wichura 1988); the tests measure it against ``scipy.special.ndtri``. ``|Φ⁻¹(U_i)| <= 8.3``.

Relaxation at input ``u`` from a state relaxed at ``u_prev`` (rising: only down spins can flip;
falling: only up spins). A down spin with ``k`` up neighbours (``n = 2k − z``) flips up iff
``u + (f_i + J·n) >= 0``, an up spin flips down iff ``u + (f_i + J·n) < 0`` (the same float
expression as :mod:`hysteresis._rfim_kernels`; ``J·n`` is the table ``jn[k]`` rounded once in
numpy). Plain-Python reading of :func:`relax_serial`::

    for every word (skipped when none of its spins can flip: rising, all up):
        k = up-neighbour counts of its 64 spins, bit-sliced    (six neighbour words, L2 >= 64)
        cand = the down spins whose m_i >= mcut[k_i]          (64 hashes, no branches;
                                                               L2 < 64: mcut[z], then per spin)
        for every spin i in cand (index order):
            if u + (f_i + jn[k]) >= 0: flip i; stack = [i]; relax the avalanche:
                while stack: j = pop; for every down neighbour m of j: same test; flip, push

``mcut[k]`` is a cut on the 52-bit integer ``m`` that is conservative: ``m < mcut[k]`` implies
``Φ⁻¹(U) < x_c < (−u − J·n)/disorder`` with a margin (computed in :mod:`hysteresis.rfim_bits`),
so a rejected spin is stable for certain and the exact float test decides every other one. A
scan costs one hash per spin of a word that has a spin able to flip; Φ⁻¹ is evaluated only near
the threshold. The bit-sliced counts read the neighbours of a word's 64 spins as six 64-bit
windows of the bit array (``±1``, ``±L2``, ``±L1·L2`` away), the spins of a row at the lattice's
edge taking their window from the periodic image; with ``L2 >= 64`` a word spans at most two
rows, so each edge is a mask of at most two runs of bits.

:func:`collect` is the parallel half (``prange`` over chunks of words, the state read only):
per chunk, the spins unstable in the state relaxed at ``u_prev``, in index order, into a bounded
buffer (a chunk that runs out of room stops at a word boundary and says where).
:func:`apply_candidates` then, chunk by chunk, flips them in index order and scans the rest of the
chunk serially. A spin that becomes unstable during a step does so because a neighbour flipped,
and the avalanche tests it then; so the serial scan starts its avalanches at exactly these spins,
in the same order, and both paths give the same spins, flips, avalanche roots and sizes.

Where the time goes (1 core, 3-D, R = 2.6): a scan 1.5 ns per spin (the hashes; words whose
spins all point the new way are skipped); a flip about 240 ns (a popped spin's neighbours: a bit
each, and for those pointing the old way six bits and a hash; Φ⁻¹ near the threshold only).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = [
    "apply_candidates",
    "collect",
    "count_up",
    "hash_fields",
    "ppnd16",
    "relax_serial",
    "up_counts_bitsliced",
]

_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S12 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(12)
_ONE = np.uint64(1)
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)
_TWO_M52 = 2.0**-52

# Wichura (1988), Algorithm AS 241, PPND16
_A = (3.3871328727963666080e0, 1.3314166789178437745e2, 1.9715909503065514427e3,
      1.3731693765509461125e4, 4.5921953931549871457e4, 6.7265770927008700853e4,
      3.3430575583588128105e4, 2.5090809287301226727e3)  # fmt: skip
_B = (1.0, 4.2313330701600911252e1, 6.8718700749205790830e2, 5.3941960214247511077e3,
      2.1213794301586595867e4, 3.9307895800092710610e4, 2.8729085735721942674e4,
      5.2264952788528545610e3)  # fmt: skip
_C = (1.42343711074968357734e0, 4.63033784615654529590e0, 5.76949722146069140550e0,
      3.64784832476320460504e0, 1.27045825245236838258e0, 2.41780725177450611770e-1,
      2.27238449892691845833e-2, 7.74545014278341407640e-4)  # fmt: skip
_D = (1.0, 2.05319162663775882187e0, 1.67638483018380384940e0, 6.89767334985100004550e-1,
      1.48103976427480074590e-1, 1.51986665636164571966e-2, 5.47593808499534494600e-4,
      1.05075007164441684324e-9)  # fmt: skip
_E = (6.65790464350110377720e0, 5.46378491116411436990e0, 1.78482653991729133580e0,
      2.96560571828504891230e-1, 2.65321895265761230930e-2, 1.24266094738807843860e-3,
      2.71155556874348757815e-5, 2.01033439929228813265e-7)  # fmt: skip
_F = (1.0, 5.99832206555887937690e-1, 1.36929880922735805310e-1, 1.48753612908506148525e-2,
      7.86869131145613259100e-4, 1.84631831751005468180e-5, 1.42151175831644588870e-7,
      2.04426310338993978564e-15)  # fmt: skip


@njit(cache=True, inline="always")
def _poly(c, r):  # pragma: no cover - compiled
    return (((((((c[7] * r + c[6]) * r + c[5]) * r + c[4]) * r + c[3]) * r + c[2]) * r + c[1])
            * r + c[0])  # fmt: skip


@njit(cache=True)
def ppnd16(p):  # pragma: no cover - compiled
    """Φ⁻¹(p) for ``0 < p < 1`` (AS241 PPND16; ``1 − p`` is exact for the generator's p)."""
    q = p - 0.5
    if abs(q) <= 0.425:
        r = 0.180625 - q * q
        return q * _poly(_A, r) / _poly(_B, r)
    r = p if q < 0.0 else 1.0 - p
    r = math.sqrt(-math.log(r))
    if r <= 5.0:
        r -= 1.6
        x = _poly(_C, r) / _poly(_D, r)
    else:
        r -= 5.0
        x = _poly(_E, r) / _poly(_F, r)
    return -x if q < 0.0 else x


@njit(cache=True, inline="always")
def _mix(z):  # pragma: no cover - compiled
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=True, inline="always")
def _m52(i, k0, k1):  # pragma: no cover - compiled
    """The 52-bit integer m_i of spin i (int64)."""
    return np.int64(_mix(_mix(np.uint64(i) * _GAMMA + k0) ^ k1) >> _S12)


@njit(cache=True, inline="always")
def _field(m, disorder):  # pragma: no cover - compiled
    return disorder * ppnd16((m + 0.5) * _TWO_M52)


@njit(cache=True)
def hash_fields(start, stop, k0, k1, disorder, out):  # pragma: no cover - compiled
    """``out[j] = f_{start+j}`` for ``start <= i < stop``."""
    for i in range(start, stop):
        out[i - start] = _field(_m52(i, k0, k1), disorder)


@njit(cache=True, inline="always")
def _up(words, i):  # pragma: no cover - compiled
    return np.int64((words[i >> 6] >> np.uint64(i & 63)) & _ONE)


@njit(cache=True, inline="always")
def _plus(c, length):  # pragma: no cover - compiled
    return c + 1 if c < length - 1 else 0


@njit(cache=True, inline="always")
def _minus(c, length):  # pragma: no cover - compiled
    return c - 1 if c > 0 else length - 1


@njit(cache=True, inline="always")
def _site(c0, c1, c2, dims):  # pragma: no cover - compiled
    return (c0 * dims[1] + c1) * dims[2] + c2


@njit(cache=True, inline="always")
def _next(i, c, length, stride):  # pragma: no cover - compiled
    """Index of the neighbour one step up an axis (periodic) of site i at coordinate c."""
    return i + stride if c < length - 1 else i - (length - 1) * stride


@njit(cache=True, inline="always")
def _prev(i, c, length, stride):  # pragma: no cover - compiled
    return i - stride if c > 0 else i + (length - 1) * stride


@njit(cache=True, inline="always")
def _count_up(words, i, c0, c1, c2, dims):  # pragma: no cover - compiled
    """Up neighbours of site i = (c0, c1, c2)."""
    l0, l1, l2 = dims[0], dims[1], dims[2]
    k = 0
    if l2 > 1:
        k += _up(words, _next(i, c2, l2, 1)) + _up(words, _prev(i, c2, l2, 1))
    if l1 > 1:
        k += _up(words, _next(i, c1, l1, l2)) + _up(words, _prev(i, c1, l1, l2))
    if l0 > 1:
        s = l1 * l2
        k += _up(words, _next(i, c0, l0, s)) + _up(words, _prev(i, c0, l0, s))
    return k


@njit(cache=True)
def count_up(words, dims, out):  # pragma: no cover - compiled
    """``out[i]`` = up neighbours of every spin (tests)."""
    for c0 in range(dims[0]):
        for c1 in range(dims[1]):
            for c2 in range(dims[2]):
                i = _site(c0, c1, c2, dims)
                out[i] = _count_up(words, i, c0, c1, c2, dims)


@njit(cache=True, inline="always")
def _unstable(words, i, c0, c1, c2, p):  # pragma: no cover - compiled
    """Whether spin i (pointing down if rising, up if falling) flips at ``u``; ``p`` is the
    step's ``(dims, rising, u, mcut, jn, k0, k1, disorder, 1/dims)``."""
    dims, rising, u, mcut, jn, k0, k1, disorder = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    k = _count_up(words, i, c0, c1, c2, dims)
    m = _m52(i, k0, k1)
    if rising:
        if m < mcut[k]:
            return False
        return u + (_field(m, disorder) + jn[k]) >= 0.0
    if m > mcut[k]:
        return False
    return u + (_field(m, disorder) + jn[k]) < 0.0


@njit(cache=True, inline="always")
def _push(stack, top, i):  # pragma: no cover - compiled
    if top == stack.size:
        bigger = np.empty(2 * stack.size, dtype=stack.dtype)
        bigger[:top] = stack
        stack = bigger
    stack[top] = i
    return stack, top + 1


@njit(cache=True, inline="always")
def _visit(words, i, c0, c1, c2, p, stack, top):  # pragma: no cover - compiled
    """Flip and push site i = (c0, c1, c2) if it points the old way and is unstable."""
    if _up(words, i) == (0 if p[1] else 1) and _unstable(words, i, c0, c1, c2, p):
        words[i >> 6] ^= _ONE << np.uint64(i & 63)
        stack, top = _push(stack, top, i)
    return stack, top


@njit(cache=True)
def _avalanche(words, i, p, stack):  # pragma: no cover - compiled
    """Flip spin i (unstable) and relax the avalanche it starts (depth first, explicit stack);
    returns its size and the stack (grown if it was full)."""
    dims = p[0]
    l0, l1, l2 = dims[0], dims[1], dims[2]
    s0 = l1 * l2
    words[i >> 6] ^= _ONE << np.uint64(i & 63)
    stack[0] = i
    top = 1
    size = 1
    while top > 0:
        top -= 1
        j = np.int64(stack[top])
        c0, c1, c2 = _coords(j, dims, p[8])
        before = top
        if l2 > 1:
            m = _next(j, c2, l2, 1)
            stack, top = _visit(words, m, c0, c1, _plus(c2, l2), p, stack, top)
            m = _prev(j, c2, l2, 1)
            stack, top = _visit(words, m, c0, c1, _minus(c2, l2), p, stack, top)
        if l1 > 1:
            m = _next(j, c1, l1, l2)
            stack, top = _visit(words, m, c0, _plus(c1, l1), c2, p, stack, top)
            m = _prev(j, c1, l1, l2)
            stack, top = _visit(words, m, c0, _minus(c1, l1), c2, p, stack, top)
        if l0 > 1:
            m = _next(j, c0, l0, s0)
            stack, top = _visit(words, m, _plus(c0, l0), c1, c2, p, stack, top)
            m = _prev(j, c0, l0, s0)
            stack, top = _visit(words, m, _minus(c0, l0), c1, c2, p, stack, top)
        size += top - before
    return size, stack


@njit(cache=True, inline="always")
def _window(words, start):  # pragma: no cover - compiled
    """Bits ``start … start + 63`` of the spins as one word (bits outside the array: 0)."""
    nw = words.size
    if start < 0:
        if start <= -64:
            return np.uint64(0)
        return words[0] << np.uint64(-start)
    q = start >> 6
    r = start & 63
    lo = words[q] if q < nw else np.uint64(0)
    if r == 0:
        return lo
    hi = words[q + 1] if q + 1 < nw else np.uint64(0)
    return (lo >> np.uint64(r)) | (hi << np.uint64(64 - r))


@njit(cache=True, inline="always")
def _below(b):  # pragma: no cover - compiled
    """Mask of bits ``0 … b − 1`` (``0 <= b <= 64``)."""
    return _ALL if b >= 64 else (_ONE << np.uint64(b)) - _ONE


@njit(cache=True, inline="always")
def _neighbour_word(words, base, stride, wrap, at_edge_a, at_edge_b, split):  # pragma: no cover
    """The neighbour along one direction of the 64 spins of the word at ``base`` as a word: the
    window ``stride`` away, except the spins of a row at the lattice's edge (``at_edge_a``: the
    word's first row, bits below ``split``; ``at_edge_b``: its second row), whose neighbour is
    ``wrap`` away."""
    edge = np.uint64(0)
    if at_edge_a:
        edge |= _below(split)
    if at_edge_b:
        edge |= ~_below(split)
    out = _window(words, base + stride) & ~edge
    if edge != 0:
        out |= _window(words, base + wrap) & edge
    return out


@njit(cache=True, inline="always")
def _add(s0, s1, s2, x):  # pragma: no cover - compiled
    """Add the one-bit numbers ``x`` to the bit-sliced 3-bit counters ``(s0, s1, s2)``."""
    c0 = s0 & x
    s0 ^= x
    c1 = s1 & c0
    s1 ^= c0
    s2 ^= c1
    return s0, s1, s2


@njit(cache=True, inline="always")
def _up_counts(words, w, dims):  # pragma: no cover - compiled
    """Bit-sliced up-neighbour counts ``(s0, s1, s2)`` of the 64 spins of word ``w`` (a lattice
    with ``L2 >= 64``: a word spans at most two rows, its first ``split`` bits in the first)."""
    l0, l1, l2 = dims[0], dims[1], dims[2]
    base = w * 64
    c2 = base % l2
    c1 = (base // l2) % l1
    c0 = base // (l1 * l2)
    split = l2 - c2  # bits of the first row (>= 64: the word lies in one row)
    d1 = c1 + 1 if c1 < l1 - 1 else 0  # the second row's coordinates
    d0 = c0 if c1 < l1 - 1 else (c0 + 1 if c0 < l0 - 1 else 0)
    z = np.uint64(0)
    s0, s1, s2 = z, z, z
    # x: the row's last spin (+1) and first spin (−1) wrap
    e = _ONE << np.uint64(split - 1) if split <= 64 else z
    x = (_window(words, base + 1) & ~e) | (_window(words, base + 1 - l2) & e)
    s0, s1, s2 = _add(s0, s1, s2, x)
    e = _ONE << np.uint64(split) if split < 64 else z
    if c2 == 0:
        e |= _ONE
    x = (_window(words, base - 1) & ~e) | (_window(words, base - 1 + l2) & e)
    s0, s1, s2 = _add(s0, s1, s2, x)
    if l1 > 1:
        x = _neighbour_word(words, base, l2, l2 - l1 * l2, c1 == l1 - 1, d1 == l1 - 1, split)
        s0, s1, s2 = _add(s0, s1, s2, x)
        x = _neighbour_word(words, base, -l2, l1 * l2 - l2, c1 == 0, d1 == 0, split)
        s0, s1, s2 = _add(s0, s1, s2, x)
    if l0 > 1:
        s = l1 * l2
        x = _neighbour_word(words, base, s, s - l0 * s, c0 == l0 - 1, d0 == l0 - 1, split)
        s0, s1, s2 = _add(s0, s1, s2, x)
        x = _neighbour_word(words, base, -s, l0 * s - s, c0 == 0, d0 == 0, split)
        s0, s1, s2 = _add(s0, s1, s2, x)
    return s0, s1, s2


@njit(cache=True)
def up_counts_bitsliced(words, dims, out):  # pragma: no cover - compiled
    """``out[i]`` = up neighbours of every spin by the bit-sliced counts (tests; ``L2 >= 64``)."""
    n = out.size
    for w in range((n + 63) // 64):
        s0, s1, s2 = _up_counts(words, w, dims)
        for b in range(min(64, n - w * 64)):
            sh = np.uint64(b)
            out[w * 64 + b] = (
                ((s0 >> sh) & _ONE) + 2 * ((s1 >> sh) & _ONE) + 4 * ((s2 >> sh) & _ONE)
            )


@njit(cache=True, inline="always")
def _candidates(words, w, n, p):  # pragma: no cover - compiled
    """Bit mask of the spins of word ``w`` that point the old way and pass their hash cut:
    each spin's own ``mcut[k]`` from bit-sliced neighbour counts when ``L2 >= 64``, else the
    loosest cut (``k = z`` rising, ``k = 0`` falling)."""
    dims, rising, mcut, k0, k1 = p[0], p[1], p[3], p[5], p[6]
    old = ~words[w] if rising else words[w]
    base = w * 64
    if base + 64 > n:
        old &= _below(n - base)
    if old == 0:
        return old
    mask = np.uint64(0)
    if dims[2] >= 64:
        s0, s1, s2 = _up_counts(words, w, dims)
        for b in range(64):
            sh = np.uint64(b)
            k = (
                ((s0 >> sh) & _ONE)
                | (((s1 >> sh) & _ONE) << _ONE)
                | (((s2 >> sh) & _ONE) << np.uint64(2))
            )
            m = _m52(base + b, k0, k1)
            hit = m >= mcut[k] if rising else m <= mcut[k]
            mask |= np.uint64(hit) << sh
    elif rising:
        cut = mcut.min()
        for b in range(64):
            mask |= np.uint64(_m52(base + b, k0, k1) >= cut) << np.uint64(b)
    else:
        cut = mcut.max()
        for b in range(64):
            mask |= np.uint64(_m52(base + b, k0, k1) <= cut) << np.uint64(b)
    return mask & old


@njit(cache=True, inline="always")
def _divmod(j, length, inverse):  # pragma: no cover - compiled
    """``divmod(j, length)`` for ``0 <= j < 2**31`` without an integer division (a tenth of its
    time): the float quotient is off by at most one, and the remainder says which way."""
    q = np.int64(j * inverse)
    r = j - q * length
    if r < 0:
        q -= 1
        r += length
    elif r >= length:
        q += 1
        r -= length
    return q, r


@njit(cache=True, inline="always")
def _coords(i, dims, inverses):  # pragma: no cover - compiled
    """Coordinates of site ``i``; ``inverses = 1/dims`` (floats)."""
    q, c2 = _divmod(i, dims[2], inverses[2])
    c0, c1 = _divmod(q, dims[1], inverses[1])
    return c0, c1, c2


@njit(cache=True)
def relax_serial(words, n, w0, w1, p, stack, stats):  # pragma: no cover - compiled
    """Relax the spins at ``u`` scanning words ``[w0, w1)`` in order (module docstring);
    ``stats += [flips, avalanches]``, ``stats[2] = max(stats[2], largest)``; returns the
    stack."""
    old = 0 if p[1] else 1
    for w in range(w0, w1):
        mask = _candidates(words, w, n, p)
        if mask == 0:
            continue
        for b in range(64):
            if (mask >> np.uint64(b)) & _ONE == 0:
                continue
            i = w * 64 + b
            if _up(words, i) != old:
                continue  # flipped by an avalanche started earlier in this word
            c0, c1, c2 = _coords(i, p[0], p[8])
            if _unstable(words, i, c0, c1, c2, p):
                size, stack = _avalanche(words, i, p, stack)
                stats[0] += size
                stats[1] += 1
                stats[2] = max(stats[2], size)
    return stack


@njit(cache=True, parallel=True)
def collect(words, n, chunk, p, buf, counts, resume):  # pragma: no cover - compiled
    """Per chunk ``c`` of ``chunk`` words: the spins unstable at ``u`` in the current state (read
    only), in index order, into ``buf[c, :counts[c]]``; ``resume[c]`` is the first word not
    done (the chunk's end, or the word whose spins no longer fit in ``buf[c]``)."""
    n_words = (n + 63) // 64
    cap = buf.shape[1]
    for c in prange(counts.size):
        got = 0
        w1 = min((c + 1) * chunk, n_words)
        stop = w1
        for w in range(c * chunk, w1):
            mask = _candidates(words, w, n, p)
            if mask == 0:
                continue
            first = got
            for b in range(64):
                if (mask >> np.uint64(b)) & _ONE == 0:
                    continue
                i = w * 64 + b
                c0, c1, c2 = _coords(i, p[0], p[8])
                if _unstable(words, i, c0, c1, c2, p):
                    if got == cap:
                        got = -1
                        break
                    buf[c, got] = i
                    got += 1
            if got < 0:
                got = first  # this word and the rest are left to the serial scan
                stop = w
                break
        counts[c] = got
        resume[c] = stop


@njit(cache=True)
def apply_candidates(words, n, chunk, p, buf, counts, resume, stack, stats):  # pragma: no cover
    """Flip the collected spins in index order, each with its avalanche (a spin already flipped
    by an earlier one is skipped: it stayed unstable, and that avalanche flipped it), and scan
    the words a chunk left (``resume[c]`` to its end) by :func:`relax_serial`, chunk by chunk:
    the serial scan's order. Returns the stack."""
    n_words = (n + 63) // 64
    old = 0 if p[1] else 1
    for c in range(counts.size):
        for t in range(counts[c]):
            i = np.int64(buf[c, t])
            if _up(words, i) != old:
                continue
            size, stack = _avalanche(words, i, p, stack)
            stats[0] += size
            stats[1] += 1
            stats[2] = max(stats[2], size)
        w1 = min((c + 1) * chunk, n_words)
        if resume[c] < w1:
            stack = relax_serial(words, n, resume[c], w1, p, stack, stats)
    return stack
