"""Numba kernels of the Preisach model (discrete and continuous).

The memory of a Preisach model is the *staircase*: the alternating sequence of dominant input
extrema left after wiping-out (Mayergoyz). The kernels keep it as a stack

    vals = [+inf, -inf, M_1, m_1, M_2, m_2, ...]

with two sentinels (index 0: a maximum ``+inf``, index 1: a minimum ``-inf``). Even indices are
maxima, odd indices minima; the last entry is the current input. Reduced form: maxima strictly
decreasing, minima strictly increasing, every minimum below its neighbouring maxima.

Relay convention: a relay (alpha, beta), alpha >= beta, switches up once ``u >= alpha`` and down
once ``u < beta``. In a reduced staircase relay (alpha, beta) is up iff its last "event" is an
up event, where a maximum ``M`` is an up event if ``M >= alpha`` and a minimum ``m`` a down event
if ``m < beta``. Hence, on a rising input from ``u`` to ``v`` below the previous maximum, the
relays that switch up are exactly those with ``alpha in (u, v]`` and ``beta > m`` (``m`` the last
minimum); on a falling input those with ``beta in (v, u]`` and ``alpha <= M`` (``M`` the last
maximum). Reaching the previous maximum (``v >= M_prev``) wipes out the step ``(m, M_prev)``
and the query continues with the older minimum.

Discrete model: every stack entry also stores ``cnt_a`` (number of relays with ``alpha <= value``)
and ``cnt_b`` (number with ``beta <= value``): positions in the alpha-sorted and beta-sorted relay
orders. The switching relays of one staircase step are a contiguous index range in alpha-order
(rising) filtered by ``beta > m``: a 3-sided range query answered in O(1 + k) by a sparse-table
range-maximum of beta over alpha-order (report the argmax if it passes, recurse on both sides).
Falling inputs use the range-minimum of alpha over beta-order. A range of at most ``_SHORT``
(256) relays is not split further but summed branch-free (four independent accumulators, packed
in one SIMD register): a bounded amount of work per visited node, so a step still costs O(1 + k)
node visits, and at the paper's densities (~100 thresholds crossed per step, ~5 switching) this
is much faster than recursing down to single relays. (The callers pass as
``beta_by_a``/``alpha_by_b`` search keys in which relays of zero weight carry beta = -inf and
alpha = +inf, so that they are never reported.)

SIMD and its fallback: the packed four-lane sums use a numba ``intrinsic`` (llvmlite IR). Every
kernel that reaches them takes a last argument ``mode`` whose *type* selects the path at compile
time: :data:`SIMD_MODE` (``True``, a boolean) the intrinsic, :data:`SCALAR_MODE` (``0``, an
int) a plain loop with the same four accumulators in the same order (bit-identical sums).
:func:`lane_mode` returns the mode to use: scalar if the environment variable
``HYSTERESIS_NO_SIMD`` is set to a non-empty value other than ``0``, if the module flag
:data:`USE_SIMD` is set to ``False``, or if the intrinsic fails to compile on this machine
(probed once, with a warning).

Bounds safety: whatever the data (NaN, ±inf, counts from a forged state), every index stays in
range: bucket indices are clamped with NaN-safe comparisons, relay ranges are clamped to
``[0, n]`` and the staircase loops never step past the sentinels.

Pruning (keeps the stack bounded by ``2 n_relays + 6`` entries): a completed maximum with the same
``cnt_a`` as the previous maximum separates no relays from it; it is removed together with the
minimum between them (and symmetrically for minima with equal ``cnt_b``). This leaves every relay
state unchanged.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload

#: ranges of at most this many relays are scanned instead of split by range-extremum queries
_SHORT = 256
#: capacity of the explicit stack of the range recursion (log2(n) + 1 <= 64 pending ranges)
_WORK_RANGES = 66
#: inputs per block of the threshold-count pre-pass of :func:`discrete_apply`
_CHUNK = 256

#: ``mode`` argument selecting the packed SIMD lane sums (its numba type, boolean, is what
#: matters; plain Python bool and int keep the dispatcher's fast argument typing)
SIMD_MODE = True
#: ``mode`` argument selecting the plain scalar lane sums (numba type int64)
SCALAR_MODE = 0
#: ``False`` forces the scalar path; ``None`` until the intrinsic has been probed
USE_SIMD: bool | None = (
    False if os.environ.get("HYSTERESIS_NO_SIMD", "").strip() not in ("", "0") else None
)

# --------------------------------------------------------------------------------------------
# sparse tables
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def sparse_table(values, largest):  # pragma: no cover - compiled
    """Sparse table of range-argmax (``largest=True``) or range-argmin (``largest=False``)
    indices, for the O(1) queries :func:`_range_argmax` / :func:`_range_argmin`.

    Plain-Python reading::

        better = max if largest else min        # ties: the left index
        table[0] = range(n)
        for k in 1..: table[k][i] = arg-better of values over [i, i + 2**k)
                      = better of table[k-1][i] and table[k-1][i + 2**(k-1)]
    """
    n = values.size
    levels = 1
    while (1 << levels) <= n:
        levels += 1
    table = np.empty((levels, max(n, 1)), dtype=np.int32)
    for i in range(n):
        table[0, i] = i
    for k in range(1, levels):
        half = 1 << (k - 1)
        for i in range(n - (1 << k) + 1):
            a = table[k - 1, i]
            b = table[k - 1, i + half]
            if largest:
                table[k, i] = a if values[a] >= values[b] else b
            else:
                table[k, i] = a if values[a] <= values[b] else b
    return table


@njit(cache=True, inline="always")
def _floor_log2(x):  # pragma: no cover - compiled
    """floor(log2(x)) for x >= 1 by halving the candidate range (6 comparisons for 64 bits)."""
    k = 0
    if x >= 1 << 32:
        x >>= 32
        k += 32
    if x >= 1 << 16:
        x >>= 16
        k += 16
    if x >= 1 << 8:
        x >>= 8
        k += 8
    if x >= 1 << 4:
        x >>= 4
        k += 4
    if x >= 1 << 2:
        x >>= 2
        k += 2
    if x >= 1 << 1:
        k += 1
    return k


@njit(cache=True, inline="always")
def _range_argmax(table, values, lo, hi):  # pragma: no cover - compiled
    """argmax of values[lo:hi] (hi > lo) in O(1)."""
    k = _floor_log2(hi - lo)
    a = table[k, lo]
    b = table[k, hi - (1 << k)]
    return a if values[a] >= values[b] else b


@njit(cache=True, inline="always")
def _range_argmin(table, values, lo, hi):  # pragma: no cover - compiled
    """argmin of values[lo:hi] (hi > lo) in O(1)."""
    k = _floor_log2(hi - lo)
    a = table[k, lo]
    b = table[k, hi - (1 << k)]
    return a if values[a] <= values[b] else b


@njit(cache=True, inline="always")
def _count_le(sorted_values, pos, x):  # pragma: no cover - compiled
    """Number of ``sorted_values <= x``, by galloping from a previous answer ``pos``.

    Plain-Python reading: ``bisect.bisect_right(sorted_values, x)``; the search first doubles a
    step away from ``pos`` so the cost is O(log(1 + |answer - pos|)).
    """
    n = sorted_values.size
    pos = min(max(pos, 0), n)  # a stale or forged start must not index out of range
    if pos < n and sorted_values[pos] <= x:
        # answer > pos: gallop right
        lo = pos + 1  # known: answer >= lo
        step = 1
        hi = pos + 1
        while hi < n and sorted_values[hi] <= x:
            lo = hi + 1
            hi = hi + step
            step *= 2
        if hi > n:
            hi = n
        # answer in [lo, hi]
        while lo < hi:
            mid = (lo + hi) >> 1
            if sorted_values[mid] <= x:
                lo = mid + 1
            else:
                hi = mid
        return lo
    # answer <= pos: gallop left
    hi = pos  # known: answer <= hi
    step = 1
    lo = pos - 1
    while lo >= 0 and sorted_values[lo] > x:
        hi = lo
        lo = lo - step
        step *= 2
    if lo < 0:
        lo = -1
    # sorted_values[lo] <= x (or lo == -1); answer in [lo + 1, hi]
    lo += 1
    while lo < hi:
        mid = (lo + hi) >> 1
        if sorted_values[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, inline="always")
def _bucket_of(x, lo, inv_h, nb):  # pragma: no cover - compiled
    """Bucket of ``x`` on a uniform grid; a monotone non-decreasing function of ``x``, always
    in ``[0, nb - 1]``: a NaN ``t`` (``inf * 0`` when the grid is degenerate or ``x - lo``
    overflows) goes to bucket 0, whose search range then covers what it must."""
    t = (x - lo) * inv_h
    if not (t > 0.0):  # also NaN: int(NaN) would be an arbitrary (out-of-range) index
        return 0
    if not (t < nb - 1):
        return nb - 1
    return int(t)


@njit(cache=True)
def bucket_starts(sorted_values, lo, inv_h, nb):  # pragma: no cover - compiled
    """``starts[b]`` = first index whose value lies in bucket >= b (``starts[nb] = n``).

    int32 (half the cache footprint of int64), like the sparse tables: ``n < 2**31``.
    """
    n = sorted_values.size
    starts = np.empty(nb + 1, dtype=np.int32)
    i = 0
    for b in range(nb + 1):
        while i < n and _bucket_of(sorted_values[i], lo, inv_h, nb) < b:
            i += 1
        starts[b] = i
    return starts


@njit(cache=True, inline="always")
def _count_le_bucket(sorted_values, starts, lo, inv_h, x):  # pragma: no cover - compiled
    """Number of ``sorted_values <= x`` (``bisect.bisect_right``) in O(1) expected time.

    Because the bucket map is monotone, every value in a lower bucket than ``x``'s is <= x and
    every value in a higher bucket is > x: the answer lies in ``[starts[b], starts[b+1]]`` and
    a binary search over that bucket finishes it (O(log n) worst case for clustered values).
    The search halves a candidate count with conditional moves, not branches: the outcome of
    each comparison is unpredictable, a mispredicted branch would cost more than the loads.
    """
    nb = starts.size - 1
    b = _bucket_of(x, lo, inv_h, nb)
    base = starts[b]
    n = starts[b + 1] - base
    if n == 0:
        return base
    while n > 1:
        half = n >> 1
        base = base + half if sorted_values[base + half] <= x else base
        n -= half
    return base + (sorted_values[base] <= x)


@njit(cache=True)
def _count_lt(sorted_values, x):  # pragma: no cover - compiled
    """Number of ``sorted_values < x`` (``bisect.bisect_left``), O(log n)."""
    lo = 0
    hi = sorted_values.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if sorted_values[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


# --------------------------------------------------------------------------------------------
# 3-sided range reporting
# --------------------------------------------------------------------------------------------


_V4 = ir.VectorType(ir.DoubleType(), 4)


def _lane_sums_intrinsic(predicate):
    """Build an intrinsic ``(keys, weights, a, n_blocks, x) -> (s0, s1, s2, s3)``.

    Plain-Python reading::

        s = [0.0, 0.0, 0.0, 0.0]
        for j in range(n_blocks):
            for lane in range(4):
                i = a + 4 * j + lane
                s[lane] += weights[i] if predicate(keys[i], x) else 0.0
        return tuple(s)

    The four lanes are four independent addition chains kept in one AVX register: the same
    additions in the same order as four scalar accumulators, so the sums are bit-identical to
    the scalar loop, but one packed compare/select/add handles four relays.
    """

    @intrinsic
    def lane_sums(typingctx, keys, weights, a, n_blocks, x):
        for arr in (keys, weights):
            # raw pointer arithmetic below: only contiguous float64 arrays
            if not (isinstance(arr, types.Array) and arr.dtype == types.float64):
                return None
            if arr.ndim != 1 or arr.layout not in "CF":
                return None
        # the call site casts the integers to intp and x to float64
        sig = types.UniTuple(types.float64, 4)(keys, weights, types.intp, types.intp, types.float64)

        def codegen(context, builder, signature, args):
            keys_v, weights_v, a_v, n_v, x_v = args
            kp = context.make_array(signature.args[0])(context, builder, keys_v).data
            wp = context.make_array(signature.args[1])(context, builder, weights_v).data
            zero = ir.Constant(_V4, [0.0] * 4)
            xv = zero
            for lane in range(4):
                xv = builder.insert_element(xv, x_v, ir.Constant(ir.IntType(32), lane))
            acc = cgutils.alloca_once_value(builder, zero)
            with cgutils.for_range(builder, n_v) as loop:
                i = builder.add(a_v, builder.mul(loop.index, ir.Constant(loop.index.type, 4)))
                kv = builder.load(builder.bitcast(builder.gep(kp, [i]), _V4.as_pointer()), align=8)
                wv = builder.load(builder.bitcast(builder.gep(wp, [i]), _V4.as_pointer()), align=8)
                hit = builder.fcmp_ordered(predicate, kv, xv)
                builder.store(builder.fadd(builder.load(acc), builder.select(hit, wv, zero)), acc)
            total = builder.load(acc)
            lanes = [
                builder.extract_element(total, ir.Constant(ir.IntType(32), j)) for j in range(4)
            ]
            return context.make_tuple(builder, signature.return_type, lanes)

        return sig, codegen

    return lane_sums


_lane_sums_above = _lane_sums_intrinsic(">")
_lane_sums_at_most = _lane_sums_intrinsic("<=")


@njit(cache=True)
def _scalar_lane_sums_above(keys, weights, a, n_blocks, x):  # pragma: no cover - compiled
    """Plain fallback of ``_lane_sums_above``: the same four accumulators, the same order."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    for j in range(n_blocks):
        i = a + 4 * j
        s0 += weights[i] if keys[i] > x else 0.0
        s1 += weights[i + 1] if keys[i + 1] > x else 0.0
        s2 += weights[i + 2] if keys[i + 2] > x else 0.0
        s3 += weights[i + 3] if keys[i + 3] > x else 0.0
    return s0, s1, s2, s3


@njit(cache=True)
def _scalar_lane_sums_at_most(keys, weights, a, n_blocks, x):  # pragma: no cover - compiled
    """Plain fallback of ``_lane_sums_at_most``: the same four accumulators, the same order."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    for j in range(n_blocks):
        i = a + 4 * j
        s0 += weights[i] if keys[i] <= x else 0.0
        s1 += weights[i + 1] if keys[i + 1] <= x else 0.0
        s2 += weights[i + 2] if keys[i + 2] <= x else 0.0
        s3 += weights[i + 3] if keys[i + 3] <= x else 0.0
    return s0, s1, s2, s3


def _lanes_above(keys, weights, a, n_blocks, x, mode):  # pragma: no cover - typed by overload
    """Four-lane sums of ``weights`` where ``keys > x``: SIMD or scalar by the type of mode."""
    raise NotImplementedError("only callable from compiled code")


def _lanes_at_most(keys, weights, a, n_blocks, x, mode):  # pragma: no cover - overload
    """Four-lane sums of ``weights`` where ``keys <= x``: SIMD or scalar by the type of mode."""
    raise NotImplementedError("only callable from compiled code")


def _is_simd_mode(mode) -> bool:
    return isinstance(mode, types.Boolean)


@overload(_lanes_above, inline="always")
def _ov_lanes_above(keys, weights, a, n_blocks, x, mode):  # pragma: no cover - compile time
    if _is_simd_mode(mode):

        def simd(keys, weights, a, n_blocks, x, mode):
            return _lane_sums_above(keys, weights, a, n_blocks, x)

        return simd

    def scalar(keys, weights, a, n_blocks, x, mode):
        return _scalar_lane_sums_above(keys, weights, a, n_blocks, x)

    return scalar


@overload(_lanes_at_most, inline="always")
def _ov_lanes_at_most(keys, weights, a, n_blocks, x, mode):  # pragma: no cover - compile time
    if _is_simd_mode(mode):

        def simd(keys, weights, a, n_blocks, x, mode):
            return _lane_sums_at_most(keys, weights, a, n_blocks, x)

        return simd

    def scalar(keys, weights, a, n_blocks, x, mode):
        return _scalar_lane_sums_at_most(keys, weights, a, n_blocks, x)

    return scalar


@njit(cache=True)
def _probe_lanes(keys, weights, mode):  # pragma: no cover - compiled
    return _lanes_above(keys, weights, 0, keys.size >> 2, 0.5, mode)


def lane_mode():
    """The ``mode`` argument for the kernels: :data:`SIMD_MODE` unless disabled (module flag
    :data:`USE_SIMD` ``= False`` or ``HYSTERESIS_NO_SIMD=1``) or the intrinsic does not compile
    here (probed once; then a ``RuntimeWarning`` and the scalar path for good)."""
    global USE_SIMD
    if USE_SIMD is None:
        keys = np.arange(8.0)
        try:
            got = _probe_lanes(keys, np.ones(8), SIMD_MODE)
            want = _probe_lanes(keys, np.ones(8), SCALAR_MODE)
            USE_SIMD = bool(got == want)
        except Exception as exc:  # any compile/lowering failure of the intrinsic
            warnings.warn(
                f"SIMD lane sums unavailable ({type(exc).__name__}: {exc}); using the scalar "
                "fallback",
                RuntimeWarning,
                stacklevel=2,
            )
            USE_SIMD = False
    return SIMD_MODE if USE_SIMD else SCALAR_MODE


@njit(cache=True)
def masked_sums(keys, weights, a, b, x, mode):  # pragma: no cover - compiled
    """``(sum of weights[a:b] where keys > x, sum where keys <= x)`` through the lane sums of
    ``mode`` (for tests comparing the SIMD and scalar paths)."""
    a = min(max(a, 0), keys.size)
    b = min(max(b, a), keys.size)
    return (
        _masked_sum(keys, weights, a, b, x, mode, True),
        _masked_sum(keys, weights, a, b, x, mode, False),
    )


@njit(cache=True, inline="always")
def _masked_sum(keys, weights, a, b, bound, mode, above):  # pragma: no cover - compiled
    """Weight of the relays in ``range(a, b)`` (``b >= a``, ``keys`` non-empty) whose key is
    above ``bound`` (``above=True``) or at most ``bound`` (``above=False``).

    Plain-Python reading::

        passes = (lambda key: key > bound) if above else (lambda key: key <= bound)
        return sum(weights[i] for i in range(a, b) if passes(keys[i]))

    with four independent accumulators: lane ``j`` adds the relays ``i = a + j (mod 4)`` in
    order, the tail goes to lane 0, and the result is ``(s0 + s1) + (s2 + s3)``. The lanes are
    packed in one SIMD register (:func:`_lane_sums_intrinsic`) or, with the scalar ``mode``,
    summed by a plain loop. ``above`` is a constant at every call site: after inlining, the
    branches on it fold away.
    """
    n_blocks = (b - a) >> 2
    if above:
        s0, s1, s2, s3 = _lanes_above(keys, weights, a, n_blocks, bound, mode)
    else:
        s0, s1, s2, s3 = _lanes_at_most(keys, weights, a, n_blocks, bound, mode)
    # the 0..3 remaining relays go to lane 0 in order; a fixed three-step branch-free tail
    # (an index past the range reads a clamped, in-bounds entry and adds +0.0, which leaves
    # the non-negative sum s0 unchanged)
    i = a + 4 * n_blocks
    last = keys.size - 1
    for j in range(3):
        k = min(i + j, last)
        passes = keys[k] > bound if above else keys[k] <= bound
        s0 += weights[k] * ((i + j < b) & passes)
    return (s0 + s1) + (s2 + s3)


#: ``rising`` argument of :func:`_switched_weight`: an up step (relays switching up)
_RISING = True
#: ``rising`` argument of :func:`_switched_weight`: a down step (relays switching down)
_FALLING = False


@njit(cache=True, inline="always")
def _switched_weight(
    table, keys, weights, lo, hi, bound, work, mode, rising
):  # pragma: no cover - compiled
    """Total weight of the relays that switch in one step of the staircase.

    The two directions are mirror images, selected by ``rising``:

    * ``rising`` = :data:`_RISING` (the input rises through a step): ``keys`` are the relays'
      beta in alpha-order (search keys, see the module docstring), ``table`` the sparse table
      of range-argmax of ``keys``, ``bound`` the last minimum ``m``; relays with ``beta > m``
      switch up.
    * ``rising`` = :data:`_FALLING`: ``keys`` are the alpha in beta-order, ``table`` the
      range-argmin, ``bound`` the last maximum ``M``; relays with ``alpha <= M`` switch down.

    ``weights`` are in the same order as ``keys``; ``[lo, hi)`` is the step's index range in
    that order (clamped to the arrays); ``work`` the explicit stack (``2 * _WORK_RANGES``
    int64); ``mode`` the lane sums (:func:`lane_mode`). ``rising`` is a constant at every call
    site: after inlining, the branches on it fold away and each direction compiles to its own
    straight code.

    Plain-Python reading::

        switches = (lambda key: key > bound) if rising else (lambda key: key <= bound)
        return sum(weights[i] for i in range(lo, hi) if switches(keys[i]))

    but in O(1 + k) for k switching relays: take the range extremum of the key (max rising,
    min falling); if that relay switches it is reported and both sides are searched (explicit
    stack ``work``), otherwise no relay of the range switches. Ranges of at most ``_SHORT``
    relays are summed by :func:`_masked_sum`.
    """
    total = 0.0
    lo = max(lo, 0)  # counts from a forged state must not index out of range
    hi = min(hi, keys.size)
    if hi <= lo:
        return total
    work[0] = lo
    work[1] = hi
    top = 1
    while top > 0:
        top -= 1
        a = work[2 * top]
        b = work[2 * top + 1]
        if b - a <= _SHORT:
            # a short range is scanned branch-free: bounded O(1) work per visited node, cheaper
            # than recursing (mispredicted branches) and the complexity stays O(1 + k)
            total += _masked_sum(keys, weights, a, b, bound, mode, rising)
            continue
        if rising:
            k = _range_argmax(table, keys, a, b)
            switches = keys[k] > bound
        else:
            k = _range_argmin(table, keys, a, b)
            switches = keys[k] <= bound
        if switches:
            total += weights[k]
            # push the larger side first so that the smaller one is processed first: every
            # pending range is then at least as long as the current one's parent half, and the
            # explicit stack never holds more than log2(n) + 1 ranges
            if k - a >= b - k - 1:
                first_lo, first_hi, second_lo, second_hi = a, k, k + 1, b
            else:
                first_lo, first_hi, second_lo, second_hi = k + 1, b, a, k
            if first_hi > first_lo:
                work[2 * top] = first_lo
                work[2 * top + 1] = first_hi
                top += 1
            if second_hi > second_lo:
                work[2 * top] = second_lo
                work[2 * top + 1] = second_hi
                top += 1
    return total


# --------------------------------------------------------------------------------------------
# discrete model: apply
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def discrete_apply(
    inputs,
    alpha_by_a,
    beta_by_a,
    w_by_a,
    table_a,
    alpha_by_b,
    beta_by_b,
    w_by_b,
    table_b,
    starts_a,
    starts_b,
    grid,
    vals,
    cnt_a,
    cnt_b,
    top,
    output,
    mode,
):  # pragma: no cover - compiled
    """Drive a discrete Preisach model; returns ``(outputs, vals, cnt_a, cnt_b, top, output)``.

    ``vals``/``cnt_a``/``cnt_b`` are the staircase stack (fresh copies owned by the kernel, with
    spare capacity: the stack grows by at most one entry per input and pruning bounds it by
    ``2 n_relays + 6``) with the current input at index ``top``. ``starts_*``/``grid`` are the
    bucket grids of :func:`_count_le_bucket`. Returns ``top = -1`` if the capacity was too small
    (a bug in the caller, never silently ignored). The counts ``count(alpha <= v)`` and
    ``count(beta <= v)`` of the inputs are looked up ``_CHUNK`` inputs at a time before the
    staircase pass over those inputs (same values, but independent lookups overlap in the CPU).

    Plain-Python reading::

        for v in inputs:
            u = vals[top]
            if v > u:                                   # rising
                if top is a minimum: (prune it if it separates nothing) and push a new maximum
                lo = count(alpha <= u)
                while v >= vals[top - 2]:               # wipe out the step (m, M_prev)
                    output += 2 * weight(alpha-index in [lo, cnt_a[top-2]), beta > vals[top-1])
                    lo = cnt_a[top - 2]; top -= 2
                output += 2 * weight(alpha-index in [lo, count(alpha <= v)), beta > vals[top-1])
                vals[top] = v
            elif v < u:                                 # falling: the mirror image
                ...
            outputs.append(output)
    """
    n_in = inputs.size
    outputs = np.empty(n_in)
    work = np.empty(2 * _WORK_RANGES, dtype=np.int64)
    pa = cnt_a[top]
    pb = cnt_b[top]
    chunk_a = np.empty(_CHUNK, dtype=np.int64)
    chunk_b = np.empty(_CHUNK, dtype=np.int64)
    for c0 in range(0, n_in, _CHUNK):
        c1 = min(c0 + _CHUNK, n_in)
        # the threshold counts of a chunk of inputs first: independent lookups that the CPU
        # overlaps, instead of one exposed lookup latency per step in the branchy main loop
        for t in range(c0, c1):
            v = inputs[t]
            chunk_a[t - c0] = _count_le_bucket(alpha_by_a, starts_a, grid[0], grid[1], v)
            chunk_b[t - c0] = _count_le_bucket(beta_by_b, starts_b, grid[2], grid[3], v)
        for t in range(c0, c1):
            v = inputs[t]
            u = vals[top]
            if v > u:
                npa = chunk_a[t - c0]
                npb = chunk_b[t - c0]
                if top & 1:
                    # the current minimum becomes a turning point
                    if top >= 5 and cnt_b[top] == cnt_b[top - 2]:
                        top -= 2  # equivalent to the previous minimum: drop (M, m) between them
                    top += 1
                    if top >= vals.size:
                        return outputs[:t], vals, cnt_a, cnt_b, -1, output  # caller: capacity bug
                lo = pa
                # top >= 4: never wipe out the +inf sentinel (only an input of +inf could)
                while top >= 4 and v >= vals[top - 2]:
                    hi = cnt_a[top - 2]
                    output += 2.0 * _switched_weight(
                        table_a, beta_by_a, w_by_a, lo, hi, vals[top - 1], work, mode, _RISING
                    )
                    lo = hi
                    top -= 2
                output += 2.0 * _switched_weight(
                    table_a, beta_by_a, w_by_a, lo, npa, vals[top - 1], work, mode, _RISING
                )
                vals[top] = v
                cnt_a[top] = npa
                cnt_b[top] = npb
                pa = npa
                pb = npb
            elif v < u:
                npa = chunk_a[t - c0]
                npb = chunk_b[t - c0]
                if not (top & 1):
                    # the current maximum becomes a turning point
                    if top >= 4 and cnt_a[top] == cnt_a[top - 2]:
                        top -= 2
                    top += 1
                    if top >= vals.size:
                        return outputs[:t], vals, cnt_a, cnt_b, -1, output  # caller: capacity bug
                hi = pb
                # top >= 5: never wipe out the -inf sentinel
                while top >= 5 and v <= vals[top - 2]:
                    lo = cnt_b[top - 2]
                    output -= 2.0 * _switched_weight(
                        table_b, alpha_by_b, w_by_b, lo, hi, vals[top - 1], work, mode, _FALLING
                    )
                    hi = lo
                    top -= 2
                output -= 2.0 * _switched_weight(
                    table_b, alpha_by_b, w_by_b, npb, hi, vals[top - 1], work, mode, _FALLING
                )
                vals[top] = v
                cnt_a[top] = npa
                cnt_b[top] = npb
                pa = npa
                pb = npb
            outputs[t] = output
    return outputs, vals, cnt_a, cnt_b, top, output


# --------------------------------------------------------------------------------------------
# discrete model: next switching inputs
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _first_above(table, values, lo, hi, m):  # pragma: no cover - compiled
    """Smallest index i in [lo, hi) with values[i] > m, or -1. O(log n) range-max queries."""
    lo = max(lo, 0)
    hi = min(hi, values.size)
    if hi <= lo:
        return -1
    if values[_range_argmax(table, values, lo, hi)] <= m:
        return -1
    # invariant: some index in [lo, hi) passes
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if values[_range_argmax(table, values, lo, mid)] > m:
            hi = mid
        else:
            lo = mid
    return lo


@njit(cache=True)
def _last_at_most(table, values, lo, hi, big):  # pragma: no cover - compiled
    """Largest index i in [lo, hi) with values[i] <= big, or -1. O(log n) range-min queries."""
    lo = max(lo, 0)
    hi = min(hi, values.size)
    if hi <= lo:
        return -1
    if values[_range_argmin(table, values, lo, hi)] > big:
        return -1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if values[_range_argmin(table, values, mid, hi)] <= big:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def discrete_switching(
    alpha_by_a,
    beta_by_a,
    w_by_a,
    table_a,
    alpha_by_b,
    beta_by_b,
    w_by_b,
    table_b,
    vals,
    cnt_a,
    cnt_b,
    top,
    mode,
):  # pragma: no cover - compiled
    """``(lower, upper, jump_down, jump_up)`` of a discrete model in the staircase state.

    Plain-Python reading::

        # rising: the staircase steps above the input, in increasing alpha
        for each step (alpha-range (u, M_prev] or (M_prev, M_prev2] ..., last minimum m):
            i = first relay in alpha-order of that range with beta > m
            if found: upper = alpha[i]; jump_up = 2 * weight(alpha == upper, beta > m); stop
        # falling: the mirror image with beta, range-min of alpha and alpha <= M

    Each step costs one O(1) range query; the step that holds the answer O(log n) more.
    """
    work = np.empty(2 * _WORK_RANGES, dtype=np.int64)
    u = vals[top]
    upper = np.inf
    jump_up = 0.0
    # ---- rising
    if top & 1:  # current is a minimum: a new step (u, M_last] with m = u opens
        lo = cnt_a[top]
        c = top + 1
        m = u
        hi = cnt_a[c - 2]
        ref = c - 2
    else:
        lo = cnt_a[top]
        c = top
        m = vals[c - 1]
        hi = cnt_a[c - 2]
        ref = c - 2
    while True:
        i = _first_above(table_a, beta_by_a, lo, hi, m)
        if i >= 0:
            upper = alpha_by_a[i]
            j = _count_le(alpha_by_a, i, upper)
            jump_up = 2.0 * _switched_weight(
                table_a, beta_by_a, w_by_a, i, j, m, work, mode, _RISING
            )
            break
        if ref == 0:
            break
        # wipe out: continue above the previous maximum with the older minimum
        lo = hi
        m = vals[ref - 1]
        hi = cnt_a[ref - 2]
        ref -= 2
    # ---- falling
    lower = -np.inf
    jump_down = 0.0
    if top & 1:
        hi = cnt_b[top]
        big = vals[top - 1]
        lo = cnt_b[top - 2]
        ref = top - 2
    else:  # current is a maximum: a new step (m_last, u] with M = u opens
        hi = cnt_b[top]
        big = u
        lo = cnt_b[top - 1]
        ref = top - 1
    while True:
        i = _last_at_most(table_b, alpha_by_b, lo, hi, big)
        if i >= 0:
            lower = beta_by_b[i]
            # relays with beta == lower: indices [count(beta < lower), i]
            j = _count_lt(beta_by_b, lower)
            jump_down = -2.0 * _switched_weight(
                table_b, alpha_by_b, w_by_b, j, i + 1, big, work, mode, _FALLING
            )
            break
        if ref == 1:
            break
        hi = lo
        big = vals[ref - 1]
        lo = cnt_b[ref - 2]
        ref -= 2
    return lower, upper, jump_down, jump_up


# --------------------------------------------------------------------------------------------
# continuous model: staircase pass
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def continuous_staircase(inputs, vals, refs, top):  # pragma: no cover - compiled
    """Staircase bookkeeping of a continuous model (no Everett evaluation).

    ``vals``/``refs`` must have room for ``top + 1 + inputs.size`` entries.
    ``refs[i]`` names where the prefix sum up to stack entry ``i`` is found: a step index
    ``t >= 0`` (the entry was last current at step ``t``) or ``-1 - i0`` for an entry ``i0`` of
    the initial stack (its prefix sum is cached in the state).

    Returns per step ``(a, b, sign, base)`` such that the Everett sum at step ``t`` is
    ``S_t = prefix(base_t) + sign_t * E(a_t, b_t)`` (output ``-1 + 2 S_t``), and the final stack.

    Plain-Python reading::

        for t, v in enumerate(inputs):
            rising: push a maximum if the top is a minimum; pop (m, M_prev) while v >= M_prev
            falling: the mirror image
            vals[top] = v; refs[top] = t
            pair = (vals[top], vals[top-1]) with sign +1 if top is a maximum
                   else (vals[top-1], vals[top]) with sign -1
            base = refs[top - 1]
    """
    n_in = inputs.size
    a_out = np.empty(n_in)
    b_out = np.empty(n_in)
    sign = np.empty(n_in)
    base = np.empty(n_in, dtype=np.int64)
    for t in range(n_in):
        v = inputs[t]
        u = vals[top]
        if v > u:
            if top & 1:
                top += 1
            while top >= 4 and v >= vals[top - 2]:  # never past the +inf sentinel
                top -= 2
        elif v < u:
            if not (top & 1):
                top += 1
            while top >= 5 and v <= vals[top - 2]:  # never past the -inf sentinel
                top -= 2
        vals[top] = v
        refs[top] = t
        if top & 1:
            a_out[t] = vals[top - 1]
            b_out[t] = v
            sign[t] = -1.0
        else:
            a_out[t] = v
            b_out[t] = vals[top - 1]
            sign[t] = 1.0
        base[t] = refs[top - 1]
    return a_out, b_out, sign, base, vals, refs, top


@njit(cache=True)
def continuous_accumulate(terms, base, initial_prefix):  # pragma: no cover - compiled
    """``S_t = prefix(base_t) + terms_t`` (see :func:`continuous_staircase`).

    Plain-Python reading::

        for t: S[t] = (S[base[t]] if base[t] >= 0 else initial_prefix[-1 - base[t]]) + terms[t]
    """
    n = terms.size
    s = np.empty(n)
    for t in range(n):
        b = base[t]
        s[t] = (s[b] if b >= 0 else initial_prefix[-1 - b]) + terms[t]
    return s
