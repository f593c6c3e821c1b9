"""Numba kernels of the event-driven integrator for piecewise-constant operators.

The system is ``q'' + 2ζq' + q = cos φ + C·M``, ``φ' = Ω``, with ``M`` constant between switches.
Time is kept as (period index ``n``, time ``τ`` since the start of the period, ``0 <= τ < T``,
``T = 2π/Ω``) so that the forcing phase ``φ = φ_0 + Ωτ`` never loses digits on long runs.

The relays come as a *table* of one of two kinds, and one event loop (:func:`advance_table`)
serves both; the kind only decides how the next thresholds are found and how a switch updates
the relays and ``M`` (:func:`_table_refresh`, :func:`_table_switch`):

* kind 0, **nested plan** (O(1) per switch): relays whose upper and lower thresholds increase
  together (:meth:`hysteresis.relay_table.RelayTable.nested_plan`, every equal-width model, the
  paper's spin dimers), grouped by equal thresholds; the state is one index ``k`` = number of up
  groups; the next up threshold is ``up[k]`` (switch when ``q >= up[k]``), the next down
  threshold ``down[k-1]`` (switch when ``q < down[k-1]``), the output ``mval[k]``.
* kind 1, **heap** (any relays): a down relay has ``alpha > q`` and an up relay ``beta <= q``,
  so the next up switch is the smallest ``alpha`` among the down relays and the next down switch
  the largest ``beta`` among the up relays. The two priority queues are hierarchical 64-ary
  bitsets over the presorted thresholds (alpha ascending, beta descending): a set bit is a
  member; the minimum is one "lowest set bit" lookup (de Bruijn multiplication) per level, insert
  and delete touch one word per level (3 levels up to 262 144 relays): O(log₆₄ N) per switched
  relay, with no key comparisons and no unpredictable sift branches of a binary heap.
  All relays at the current threshold switch together (their weights form the jump). ``M`` is
  kept in integer weight units when all weights are multiples of one unit (dimers: 1/N and
  2/N), else as a Neumaier-compensated sum, so it does not drift over 10⁹ switches.

Plain-Python reading of one hop (``advance_table``)::

    F = C*M; e_n = q^(n)(0)/n! as linear forms in (q, v, F, cos φ, sin φ) (precomputed from the
        equation of motion, taylor_matrix_coefficients)
    theta = next threshold in the direction of v; x = (theta - q)/v (the linear estimate)
    fast short hop, if |x| < h_s = relay.FAST_HOP/ρ = 3e-3/ρ (most hops of a dense ensemble;
        e_2..e_6 suffice):
        h0 = x - k2 x^2 + (2 k2^2 - k3) x^3        (series reversion, k_n = e_n/v)
        dh = (sum_{n>=1} e_n h0^n - (theta - q)) / q'(h0)    (one Newton step; 1/q'(h0) by
             its series in h0), h = h0 - dh
        v, cos φ, sin φ at h from their values at h0 corrected to first order in dh
        accepted if the step's error bound is < 1e-17 and q is provably monotone on [0, h]
        (|v(s) - v| < |v|/2 by the sum of |n e_n| h^(n-1)); else the general path below
    general path, if the threshold is predicted within h_T = 0.02/ρ (degree-8 polynomial):
        Newton on sum e_n h^n = theta from the root of the quadratic; the same monotonicity test
    otherwise (long flight, turning point):
        scan [0, H] in sub-intervals with the exact propagator; inside each sub-interval split at
        the zero of q'' and at the zero of v, so q is monotone between checkpoints; the first
        checkpoint at or past a threshold brackets the crossing, found by safeguarded Newton
        on the exact solution; stretches of up to SKIP_SPAN sub-intervals that the cubic
        Hermite interpolant plus max|q''''| L^4/384 keep strictly between the thresholds are
        passed in one evaluation on the same grid (scan_flight: the same crossing, bit for bit).
    at a switch: q := threshold exactly, the table switches, tangent vectors get the saltation
        δv += C·ΔM/v* · δq  (paper eq. salt_matrix); a switch undoing the previous one at the
        same threshold (a zero-width group) where the flow pushes in from both sides and the
        new excursion lasts 2|v|/|q''| <= SLIDE_EXCURSION/ρ returns status 4: the caller
        integrates the Filippov sliding motion in closed form (oscillators/engines/_sliding.py)
    tangent vectors between switches: Φ(h) = [[g' + 2ζg, g], [-g, g']], g = Φ_01(h), by its
        Taylor series on Taylor hops, in closed form on exact flights

The kernel is compiled with fused multiply-add allowed (``fastmath={"contract"}``, nothing
else): the hop is a chain of dependent polynomial evaluations, and a fused step is both shorter
and rounded once. The fast short hop and what follows it on every path (:func:`fast_hop`,
:func:`fast_tangent`, :func:`saltation`, :func:`slides`) fuse in the source instead
(:func:`fma`), leaving the compiler nothing to choose, so they round alike in this loop and in
the vector lanes of :mod:`oscillators.engines._relay_lanes`.

The event loop (:func:`advance_table`) is compiled without numba's reference counting
(``_nrt=False``, an option outside numba's public API: probed at import, the plain loop where
numba refuses it or ``HYSTERESIS_RELAY_REFCOUNT=1``; the functions it calls inherit it): it
allocates nothing and only borrows the arrays of its caller, but the helpers inlined into it
(:func:`hop`, :func:`_table_switch`, :func:`settle_switch`) take arrays, and numba counted
their references on every pass, about 18 atomic read-modify-writes per switch (measured: 52 ->
30 ns per switch of the N = 20 000 dimers without tangent, 58 -> 38 ns with). The results are
bit for bit those of the reference-counted loop: the counting calls also stopped LLVM from
reusing values loaded before them, and where that reuse would change which products are fused
(the Taylor landing's polynomial, see :func:`hop`), :func:`_memory_barrier` keeps the former
code.

Grazing: crossings are decided on the computed extrema. A maximum that reaches ``up`` (``>=``)
switches (the relay convention ``u >= α``); a minimum that only touches ``down`` (``== down``)
does not (the relay needs ``u < β``). A crossing that happens and undoes itself inside one
sub-interval is found because every interior extremum is a checkpoint. A degenerate double zero of
q'' inside one sub-interval (length 0.1/max(1, Ω)) is not resolved; it needs |v| and |q''| both
tiny at once.
"""

from __future__ import annotations

import math
import os

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from oscillators.engines._play_kernels import _hit_possible
from oscillators.linear import exact_step, hom_matrix, phase_column

# fused multiply-add allowed (no other fast-math liberty): shorter dependency chains, and
# each fused step rounds once instead of twice
_CONTRACT = {"contract"}

#: environment variable that, set to ``1``, compiles the event loop with numba's reference
#: counting (the plain path; tests/test_oscillators/test_relay_refcount.py compares the two)
PLAIN_LOOP_ENV = "HYSTERESIS_RELAY_REFCOUNT"


@njit(cache=True)
def _probe(x):
    return x + 1.0


def _loop_options() -> dict:
    """``{"_nrt": False}`` (the event loop without reference counting, module docstring) where
    this numba accepts that option — it is not part of numba's public API, so it is probed on
    a trivial function once per process (cached) — else ``{}``, the plain reference-counted
    loop; ``{}`` too when :data:`PLAIN_LOOP_ENV` is ``1``."""
    if os.environ.get(PLAIN_LOOP_ENV) == "1":
        return {}
    try:
        njit(cache=True, _nrt=False)(_probe.py_func)(1.0)
    except Exception:  # noqa: BLE001  (any refusal of the option means: the plain loop)
        return {}
    return {"_nrt": False}


_LOOP_OPTIONS = _loop_options()


@intrinsic
def _memory_barrier(typingctx):
    """A compiler-only memory barrier (empty inline assembly that clobbers memory; no machine
    instruction): LLVM must assume every array changed, so values loaded before it are loaded
    again after it. Keeps the event loop's code (and its fused multiply-adds) what it was when
    reference counting calls stood at these places."""

    def codegen(context, builder, sig, args):
        fnty = ir.FunctionType(ir.VoidType(), [])
        builder.asm(fnty, "", "~{memory}", [], side_effect=True)
        return context.get_dummy_value()

    return types.none(), codegen


#: Taylor order of the short-hop expansion (error term h^9/9! ≈ 1e-21 at h = 0.02).
ORDER = 8

# parameter vector layout (P_UNIT: weight unit of the heap table's integer output, 0 = float)
# P_SL: the longest excursion across a zero-width threshold before the motion is set on the
# sliding set (status 4; oscillators/engines/_sliding.py)
P_ZETA, P_OMEGA, P_C, P_PHI0, P_A, P_B, P_T, P_HT, P_DSUB, P_TBASE, P_UNIT, P_HS, P_SL = range(13)
N_PAR = 13
# float state layout: q, v, tau, cos(phi), sin(phi), next up / down threshold, output M now,
# compensated output (heap table, float weights: value and Neumaier compensation), the running
# integral of M over the elapsed time (for exact time averages of the output), the jump of M and
# the direction (+1/-1) of the last switch (written only when the kernel stops with status 3 or 4)
# and the threshold and jump of the previous switch (a switch undoing it at the same threshold
# is a zero-width group chattering: the candidate of a sliding motion; kept across calls so that
# where a slide begins does not depend on the sampling)
S_Q, S_V, S_TAU, S_COS, S_SIN, S_UP, S_DN, S_MV, S_M, S_MC, S_IM, S_JMP, S_DIR = range(13)
S_PQ, S_PJ = 13, 14
N_ST = 15
# int state layout: k (nested index), n (period), number of switches so far, weight units up and
# in total (heap table, integer output), heap table: alpha rank of the next up switch and beta
# rank of the next down switch (-1: none), the switch count at which the kernel stops (the
# switch budget, status 3)
I_K, I_N, I_NSW, I_UP, I_TOT, I_IA, I_IB, I_MAXSW = range(8)
N_IST = 8
# columns of the hop tables (taylor_matrix_coefficients) holding q's Taylor coefficients as
# linear forms in q, v, F = C·M, cos φ, sin φ; the q and v coefficients are [A^n]_00/n! and
# [A^n]_01/n!, the first two propagator columns
TC_Q, TC_V, TC_F, TC_C, TC_S = 0, 1, 4, 5, 6


def make_params(
    zeta: float,
    omega: float,
    coupling: float,
    phi0: float,
    amp_a: float,
    amp_b: float,
    t_base: float,
    taylor: bool = True,
    slide_excursion: float = 1e-3,
    fast_hop: float = 1e-3,
) -> np.ndarray:
    """Pack the parameter vector used by the kernels (``slide_excursion``: see
    :data:`oscillators.engines.base.SLIDE_EXCURSION`; ``fast_hop``: the fast short hop's limit
    ρh; both divided by ρ here)."""
    par = np.zeros(N_PAR)
    par[P_ZETA] = zeta
    par[P_OMEGA] = omega
    par[P_C] = coupling
    par[P_PHI0] = phi0
    par[P_A] = amp_a
    par[P_B] = amp_b
    par[P_T] = 2.0 * math.pi / omega
    # Hop limits from the Taylor remainder. q^(n)(0)/n! is a linear form in (q, v, F, cos φ,
    # sin φ) whose coefficients are bounded by ρ^n/n! times O(1), ρ = max(1, Ω, 2ζ) (the
    # forcing contributes Ω^k, the homogeneous part ‖A^n‖ <= ‖A‖^n with ‖A‖ = max(1, 2ζ) up to
    # a factor (1 + 1/(2ζ))^n, and its eigenvalues −ζ ± √(ζ² − 1) reach 2ζ). The degree-d
    # polynomial then leaves a remainder <= (ρ h)^(d+1)/(d+1)! · e^(ρh) relative to the state's
    # size, so the limits are h·ρ <= const: with d = 8, ρh <= 0.02 gives (0.02)^9/9! ≈ 1.4e-21
    # (≤ 5e-20 with the factor 1.5^9 at ζ = 1); with d = 6 (fast hop), ρh <= 1e-3 gives
    # 1e-21/5040 ≈ 2e-25, ρh <= 3e-3 (the relay engine's FAST_HOP) 2.2e-18/5040 ≈ 4e-22. For
    # ζ <= 1/2 this is the former limit 0.02/max(1, Ω) unchanged.
    rho = max(1.0, omega, 2.0 * zeta)
    par[P_HT] = (0.02 / rho) if taylor else 0.0
    par[P_DSUB] = 0.1 / max(1.0, omega)
    par[P_TBASE] = t_base
    # short hops (most hops of a dense ensemble) take the fast path (degree-6 polynomials)
    par[P_HS] = (fast_hop / rho) if taylor else 0.0
    par[P_SL] = slide_excursion / rho
    return par


def taylor_matrix_coefficients(zeta: float, omega: float) -> np.ndarray:
    """Rows n = 0..ORDER of the hop tables.

    Columns 0-3: the entries of A^n/n! with A = [[0, 1], [-1, -2ζ]] (flattened 2×2), the Taylor
    coefficients of the propagator Φ(h) = Σ A^n h^n/n!. Columns ``TC_Q, TC_V, TC_F, TC_C, TC_S``
    (0, 1, 4, 5, 6): the n-th Taylor coefficient of q as a linear form in the hop's start values,
    ``q^(n)(0)/n! = t_q q + t_v v + t_F F + t_c cos φ + t_s sin φ`` (F = C·M), which follows from
    ``x' = A x + (0, cos φ + F)``: ``q^(n) = [A^n x]_0 + Σ_{k<n} [A^(n-1-k)]_01 f^(k)`` with
    ``f^(0) = cos φ + F`` and ``f^(k) = Ω^k cos(φ + kπ/2)``. The fast hop evaluates these forms
    side by side instead of the recursion, which is a chain of ORDER dependent steps.
    """
    a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    out = np.zeros((ORDER + 1, 7))
    powers = [np.eye(2)]
    for _ in range(ORDER):
        powers.append(powers[-1] @ a)
    for n in range(ORDER + 1):
        fac = math.factorial(n)
        out[n, :4] = (powers[n] / fac).ravel()  # includes TC_Q, TC_V
        for k in range(n):
            w = powers[n - 1 - k][0, 1] / fac
            if k == 0:
                out[n, TC_F] += w
            out[n, TC_C] += w * omega**k * round(math.cos(k * math.pi / 2))
            out[n, TC_S] -= w * omega**k * round(math.sin(k * math.pi / 2))
    return out


@njit(cache=True)
def _poly2(e, h):
    """Value and derivative of sum e[n] h^n."""
    p = e[ORDER]
    dp = ORDER * e[ORDER]
    for n in range(ORDER - 1, 0, -1):
        p = p * h + e[n]
        dp = dp * h + n * e[n]
    p = p * h + e[0]
    return p, dp


@njit(cache=True)
def _slope_bound(e, h):
    """Bound of |v(s) - v(0)| on [0, h]: sum_{n>=2} n |e_n| h^(n-1)."""
    b = 0.0
    hp = h
    for n in range(2, ORDER + 1):
        b += n * abs(e[n]) * hp
        hp *= h
    return b


@njit(cache=True)
def _excursion_bound(e, h):
    """Bound of |q(s) - q(0)| on [0, h]: sum_{n>=1} |e_n| h^n."""
    b = 0.0
    hp = h
    for n in range(1, ORDER + 1):
        b += abs(e[n]) * hp
        hp *= h
    return b


@njit(cache=True)
def _rotation(x):
    """cos x, sin x by their Taylor series (|x| <= 0.02: error below 1e-20)."""
    x2 = x * x
    cx = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)))
    sx = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))))
    return cx, sx


@njit(cache=True)
def _eval(par, force, q0, v0, c0, s0, tau0, h):
    """Exact q, v, q'', q''' at time h after (q0, v0) at period time tau0."""
    zeta = par[P_ZETA]
    omega = par[P_OMEGA]
    ph = par[P_PHI0] + omega * (tau0 + h)
    c1 = math.cos(ph)
    s1 = math.sin(ph)
    q, v = exact_step(q0, v0, c0, s0, c1, s1, force, h, zeta, omega, par[P_A], par[P_B])
    a = -2.0 * zeta * v - q + c1 + force
    j = -2.0 * zeta * a - v - omega * s1
    return q, v, a, j


@njit(cache=True)
def _root(par, force, q0, v0, c0, s0, tau0, kind, target, lo, hi, flo):
    """Zero of f on [lo, hi] (sign change), f = q - target (kind 0), v (kind 1), q'' (kind 2).

    Safeguarded Newton: bisection whenever the Newton step leaves the bracket.
    """
    t = 0.5 * (lo + hi)
    neg_lo = flo < 0.0
    for _ in range(200):
        q, v, a, j = _eval(par, force, q0, v0, c0, s0, tau0, t)
        if kind == 0:
            f = q - target
            df = v
        elif kind == 1:
            f = v
            df = a
        else:
            f = a
            df = j
        if f == 0.0:
            return t
        if (f < 0.0) == neg_lo:
            lo = t
        else:
            hi = t
        tn = t - f / df if df != 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 2e-16 * max(1.0, abs(t)) or hi - lo <= 4e-16 * max(1.0, hi):
            return tn
        t = tn
    return t


@njit(cache=True)
def _check_point(par, force, q0, v0, c0, s0, tau0, tp, qp, tn, qn, up, down):
    """Crossing on the monotone stretch [tp, tn]? Returns (time, +1/-1) or (-1, 0)."""
    if qn >= up:
        return _root(par, force, q0, v0, c0, s0, tau0, 0, up, tp, tn, qp - up), 1
    if qn < down:
        return _root(par, force, q0, v0, c0, s0, tau0, 0, down, tp, tn, qp - down), -1
    return -1.0, 0


@njit(cache=True)
def _check_piece(par, force, q0, v0, c0, s0, tau0, t1, q1, v1, t2, q2, v2, up, down):
    """[t1, t2] with monotone v: checkpoints at the zero of v (extremum of q) and at t2."""
    if v1 * v2 < 0.0:
        tv = _root(par, force, q0, v0, c0, s0, tau0, 1, 0.0, t1, t2, v1)
        qv, _, _, _ = _eval(par, force, q0, v0, c0, s0, tau0, tv)
        hc, d = _check_point(par, force, q0, v0, c0, s0, tau0, t1, q1, tv, qv, up, down)
        if d != 0:
            return hc, d
        return _check_point(par, force, q0, v0, c0, s0, tau0, tv, qv, t2, q2, up, down)
    return _check_point(par, force, q0, v0, c0, s0, tau0, t1, q1, t2, q2, up, down)


#: most sub-intervals (of ``par[P_DSUB]``) one proven-free stretch of an exact flight skips
SKIP_SPAN = 8


@njit(cache=True)
def flight_derivative_bound(par, force, q0, v0, c0, s0):
    """Bound of ``|q⁗|`` for all ``t >= 0`` of the flight from (q0, v0) (phase cos/sin (c0,
    s0)), or ``inf`` for ζ >= 1. The motion is ``F + A cos φ + B sin φ + x_h(t)`` with the free
    motion ``x_h = Re(K e^{λt})``, ``|λ| = 1`` for ζ < 1: every derivative of ``x_h`` is at most
    ``|K| e^{-ζt} <= |K|``, every derivative of order n of the forcing response at most
    ``√(A² + B²) Ω^n``."""
    zeta = par[P_ZETA]
    if not zeta < 1.0:
        return np.inf
    omega = par[P_OMEGA]
    amp_a = par[P_A]
    amp_b = par[P_B]
    wd = math.sqrt(1.0 - zeta * zeta)
    x = q0 - (amp_a * c0 + amp_b * s0 + force)
    y = v0 - omega * (amp_b * c0 - amp_a * s0)
    k2 = (y + zeta * x) / wd
    o2 = omega * omega
    return math.sqrt(x * x + k2 * k2) + math.sqrt(amp_a * amp_a + amp_b * amp_b) * o2 * o2


@njit(cache=True)
def scan_crossing(par, force, q0, v0, c0, s0, tau0, horizon, up, down):
    """First time in (0, horizon] with q >= up or q < down on the exact segment solution.

    Returns (time, direction) with direction +1 (up), -1 (down) or 0 (none; time = horizon).
    (c0, s0) must be cos/sin of the phase at tau0. :func:`scan_flight` with stretches of up to
    :data:`SKIP_SPAN` sub-intervals proven free of thresholds skipped in one evaluation.
    """
    return scan_flight(par, force, q0, v0, c0, s0, tau0, horizon, up, down, SKIP_SPAN)


@njit(cache=True)
def scan_flight(par, force, q0, v0, c0, s0, tau0, horizon, up, down, span_max):
    """:func:`scan_crossing` with skips of at most ``span_max`` sub-intervals (0 or 1: none).

    The flight is cut into sub-intervals of ``par[P_DSUB]`` (the last one stretched to the
    horizon); each is split at the zero of q'' and of v, so q is monotone between checkpoints
    and the first checkpoint at or past a threshold brackets the crossing. Skips: a stretch of
    whole sub-intervals on the same grid (the same clock values, summed the same way) is passed
    in one exact evaluation at its end when the cubic Hermite interpolant of (q, v) at its ends,
    widened by the bound ``max|q⁗| L⁴/384`` (:func:`flight_derivative_bound`) and a margin
    1e-9·(1 + |q0|) far above round-off, stays strictly between ``down`` and ``up``: no
    crossing is there, and the sub-interval that holds one is split exactly as without skips,
    so the crossing comes out bit for bit the same. Single sub-intervals are tested first (their
    end is evaluated anyway; a free one needs no split); after a free one the next try spans
    two, doubling after each success up to ``span_max``, and a failed try (one evaluation
    lost) returns to single sub-intervals.
    """
    zeta = par[P_ZETA]
    dsub = par[P_DSUB]
    m4 = flight_derivative_bound(par, force, q0, v0, c0, s0) if span_max > 1 else np.inf
    tol = 1e-9 * (1.0 + abs(q0))
    up_in = up - tol
    down_in = down + tol
    span = 1
    tl = 0.0
    ql = q0
    vl = v0
    al = -2.0 * zeta * v0 - q0 + c0 + force
    while tl < horizon:
        if span > 1:
            # after a skip: the next `span` grid points at once, while none is the stretched
            # last one (a failed try costs one evaluation and returns to single steps)
            te = tl
            n = 0
            while n < span:
                tn = te + dsub
                if tn > horizon or horizon - tn < 0.25 * dsub:
                    break
                te = tn
                n += 1
            if n == span:
                qe, ve, ae, _ = _eval(par, force, q0, v0, c0, s0, tau0, te)
                if not _hit_possible(ql, vl, qe, ve, te - tl, up_in, down_in, m4):
                    tl = te
                    ql = qe
                    vl = ve
                    al = ae
                    span = min(2 * span, span_max)
                    continue
            span = 1
        tr = tl + dsub
        if tr > horizon or horizon - tr < 0.25 * dsub:
            tr = horizon
        qr, vr, ar, _ = _eval(par, force, q0, v0, c0, s0, tau0, tr)
        if m4 < np.inf and not _hit_possible(ql, vl, qr, vr, tr - tl, up_in, down_in, m4):
            span = 2  # free: no split needed, and the next try spans two sub-intervals
        elif al * ar < 0.0:
            ta = _root(par, force, q0, v0, c0, s0, tau0, 2, 0.0, tl, tr, al)
            qa, va, _, _ = _eval(par, force, q0, v0, c0, s0, tau0, ta)
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, tl, ql, vl, ta, qa, va, up, down)
            if d != 0:
                return hc, d
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, ta, qa, va, tr, qr, vr, up, down)
            if d != 0:
                return hc, d
        else:
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, tl, ql, vl, tr, qr, vr, up, down)
            if d != 0:
                return hc, d
        tl = tr
        ql = qr
        vl = vr
        al = ar
    return horizon, 0


@njit(cache=True, inline="always")
def _tangent_update(m00, m01, m10, m11, pq, pv, a0, a1, a2, b0, b1, b2, f0, f1, f2):
    """(δq, δv) of the three tangent columns (a_j, b_j; δφ = f_j) after the hop:
    [δq, δv] := Φ [δq, δv] + (pq, pv) δφ. Columns beyond those in use are zero and stay zero."""
    return (
        m00 * a0 + m01 * b0 + pq * f0,
        m00 * a1 + m01 * b1 + pq * f1,
        m00 * a2 + m01 * b2 + pq * f2,
        m10 * a0 + m11 * b0 + pv * f0,
        m10 * a1 + m11 * b1 + pv * f1,
        m10 * a2 + m11 * b2 + pv * f2,
    )


@njit(cache=True, inline="always")
def _hop_tangent(
    m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b, ntan, a0, a1, a2, b0, b1, b2, f0, f1, f2
):
    """The tangent update of one hop (every hop mode): [δq, δv] := Φ(h) [δq, δv] + (pq, pv) δφ
    with the phase column (pq, pv) from the forcing phase (c, s) -> (c1, s1) when δφ is
    tracked (``ntan == 3``); else the two (δq, δv) columns only (the third stays zero)."""
    if ntan == 3:
        pq, pv = phase_column(m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b)
        return _tangent_update(m00, m01, m10, m11, pq, pv, a0, a1, a2, b0, b1, b2, f0, f1, f2)
    return (
        m00 * a0 + m01 * b0,
        m00 * a1 + m01 * b1,
        a2,
        m10 * a0 + m11 * b0,
        m10 * a1 + m11 * b1,
        b2,
    )


# -- relay tables -------------------------------------------------------------------------------
# The table is three flat arrays, tf (float), ti (int), lay (int), plus the mutable bitsets
# ``bits`` (flat arrays, not tuples: inside the hot loop every array handle costs reference
# counting, measured at ~100 ns per switch with tuples of arrays).
# kind 0, nested plan (O(1)): lay = [G]; tf = up (G) | down (G) | mval (G + 1); the state is
#   k = ist[I_K] groups up.
# kind 1, bitset heaps (O(log_64 N)): lay = [levels, n, level offsets of D, of U]; tf = alpha
#   ascending | beta descending | weight by alpha rank | weight by beta rank (n each); ti = beta
#   rank of each alpha rank | alpha rank of each beta rank | integer weight units by alpha rank |
#   by beta rank; bits = the two hierarchical bitsets, D over the alpha ranks (set = relay down)
#   and U over the beta ranks (set = relay up).
KIND_NESTED = 0
KIND_HEAP = 1

_DEBRUIJN = np.uint64(0x03F79D71B4CB0A89)
_CTZ_TABLE = np.zeros(64, dtype=np.int64)
for _i in range(64):
    _CTZ_TABLE[int(((1 << _i) * 0x03F79D71B4CB0A89 % (1 << 64)) >> 58)] = _i
_U0 = np.uint64(0)
_U1 = np.uint64(1)
_U6 = np.uint64(6)
_U58 = np.uint64(58)
_U63 = np.uint64(63)


@njit(cache=True, inline="always")
def _ctz(x):
    """Index of the lowest set bit of a non-zero uint64 (de Bruijn multiplication)."""
    low = x & (_U0 - x)
    return _CTZ_TABLE[(low * _DEBRUIJN) >> _U58]


@njit(cache=True, inline="always")
def _bs_first(bits, lay, base, levels):
    """Smallest set index of the bitset whose level offsets are lay[base:base+levels], or -1."""
    idx = 0
    for lv in range(levels - 1, -1, -1):
        w = bits[lay[base + lv] + idx]
        if w == _U0:
            return -1
        idx = idx * 64 + _ctz(w)
    return idx


@njit(cache=True, inline="always")
def _bs_set(bits, lay, base, levels, idx):
    for lv in range(levels):
        pos = lay[base + lv] + (idx >> 6)
        w = bits[pos]
        bits[pos] = w | (_U1 << np.uint64(idx & 63))
        if w != _U0:
            return  # the summary bits above are set already
        idx >>= 6


@njit(cache=True, inline="always")
def _bs_clear(bits, lay, base, levels, idx):
    for lv in range(levels):
        pos = lay[base + lv] + (idx >> 6)
        w = bits[pos] & ~(_U1 << np.uint64(idx & 63))
        bits[pos] = w
        if w != _U0:
            return  # the word still holds a set bit: the summary bit above stays
        idx >>= 6


@njit(cache=True, inline="always")
def _bs_next(bits, lay, base, levels, i):
    """Smallest member after removing the former minimum ``i``: the rest of its leaf word if
    any (one load, the common case), else a search from the top."""
    w = bits[lay[base] + (i >> 6)]
    if w != _U0:
        return (i & ~63) + _ctz(w)
    return _bs_first(bits, lay, base, levels)


@njit(cache=True)
def _table_refresh(par, kind, tf, ti, bits, lay, st, ist):
    """Next up / down thresholds and the output of the current table state into st (ist)."""
    if kind == KIND_NESTED:
        g = lay[0]
        k = ist[I_K]
        st[S_UP] = tf[k] if k < g else np.inf
        st[S_DN] = tf[g + k - 1] if k > 0 else -np.inf
        st[S_MV] = tf[2 * g + k]
        return
    levels = lay[0]
    n = lay[1]
    i = _bs_first(bits, lay, 2, levels)
    ist[I_IA] = i
    st[S_UP] = tf[i] if i >= 0 else np.inf
    j = _bs_first(bits, lay, 2 + levels, levels)
    ist[I_IB] = j
    st[S_DN] = tf[n + j] if j >= 0 else -np.inf
    unit = par[P_UNIT]
    if unit > 0.0:
        st[S_MV] = unit * (2 * ist[I_UP] - ist[I_TOT])
    else:
        st[S_MV] = st[S_M] + st[S_MC]


@njit(cache=True, inline="always")
def _neumaier_add(st, x):
    """st[S_M] + st[S_MC] += x with Neumaier's compensation (no drift over many switches)."""
    s = st[S_M]
    t = s + x
    if abs(s) >= abs(x):
        st[S_MC] += (s - t) + x
    else:
        st[S_MC] += (x - t) + s
    st[S_M] = t


@njit(cache=True, inline="always")
def nested_switch(tf, off, g, k_old, direction):
    """The nested table at ``tf[off:]`` (``g`` groups, k_old up) switched one group in
    ``direction``: ``(k, next up threshold, next down threshold, output, jump ΔM)``."""
    k = k_old + direction
    up = tf[off + k] if k < g else np.inf
    down = tf[off + g + k - 1] if k > 0 else -np.inf
    mv = tf[off + 2 * g + k]
    return k, up, down, mv, mv - tf[off + 2 * g + k_old]


@njit(cache=True, inline="always")
def _table_switch(par, kind, tf, ti, bits, lay, st, ist, direction):
    """Switch every relay at the current threshold in ``direction``; returns the jump ΔM and
    leaves the next thresholds and the output in st[S_UP], st[S_DN], st[S_MV].

    Heap table: the switched relays leave one queue (their bits are cleared, the next minimum
    is normally in the same word) and join the other, whose extremum can only move to them
    (a rank comparison), so a switch costs O(1) word operations unless a word runs empty.
    """
    if kind == KIND_NESTED:
        k, up, down, mv, jump = nested_switch(tf, 0, lay[0], ist[I_K], direction)
        ist[I_K] = k
        st[S_UP] = up
        st[S_DN] = down
        st[S_MV] = mv
        return jump
    levels = lay[0]
    n = lay[1]
    unit = par[P_UNIT]
    du = 0
    dw = 0.0
    # one loop for both directions: the switched relays leave queue "src" (D when rising, U
    # when falling) and join queue "dst"; offsets select the arrays of each side
    if direction > 0:
        cur = ist[I_IA]
        oth = ist[I_IB]
        src = 2
        dst = 2 + levels
        side = 0
    else:
        cur = ist[I_IB]
        oth = ist[I_IA]
        src = 2 + levels
        dst = 2
        side = n
    thr = tf[side + cur]
    while cur >= 0 and tf[side + cur] == thr:
        _bs_clear(bits, lay, src, levels, cur)
        j = ti[side + cur]
        _bs_set(bits, lay, dst, levels, j)
        if oth < 0 or j < oth:
            oth = j
        du += ti[2 * n + side + cur]
        dw += tf[2 * n + side + cur]
        cur = _bs_next(bits, lay, src, levels, cur)
    if direction > 0:
        ist[I_IA] = cur
        ist[I_IB] = oth
    else:
        ist[I_IB] = cur
        ist[I_IA] = oth
        du = -du
        dw = -dw
    st[S_UP] = tf[ist[I_IA]] if ist[I_IA] >= 0 else np.inf
    st[S_DN] = tf[n + ist[I_IB]] if ist[I_IB] >= 0 else -np.inf
    if unit > 0.0:
        ist[I_UP] += du
        st[S_MV] = unit * (2 * ist[I_UP] - ist[I_TOT])
        return 2.0 * unit * du
    _neumaier_add(st, 2.0 * dw)
    st[S_MV] = st[S_M] + st[S_MC]
    return 2.0 * dw


@njit(cache=True)
def hop_coefficients(mp):
    """The fast hop's coefficients (rows 2-6 of the hop tables, columns ``TC_*``, and the
    propagator's g = Φ_01 and g' Taylor coefficients) as one tuple: held in registers by
    :func:`hop` (loads from ``mp`` inside the loop would be repeated after every store:
    numba arrays carry no aliasing information)."""
    t2q = mp[2, TC_Q]
    t2v = mp[2, TC_V]
    t2f = mp[2, TC_F]
    t2c = mp[2, TC_C]
    t2s = mp[2, TC_S]
    t3q = mp[3, TC_Q]
    t3v = mp[3, TC_V]
    t3f = mp[3, TC_F]
    t3c = mp[3, TC_C]
    t3s = mp[3, TC_S]
    t4q = mp[4, TC_Q]
    t4v = mp[4, TC_V]
    t4f = mp[4, TC_F]
    t4c = mp[4, TC_C]
    t4s = mp[4, TC_S]
    t5q = mp[5, TC_Q]
    t5v = mp[5, TC_V]
    t5f = mp[5, TC_F]
    t5c = mp[5, TC_C]
    t5s = mp[5, TC_S]
    t6q = mp[6, TC_Q]
    t6v = mp[6, TC_V]
    t6f = mp[6, TC_F]
    t6c = mp[6, TC_C]
    t6s = mp[6, TC_S]
    g0, g1, g2, g3, g4, g5, g6 = (
        mp[0, 1],
        mp[1, 1],
        mp[2, 1],
        mp[3, 1],
        mp[4, 1],
        mp[5, 1],
        mp[6, 1],
    )
    d0, d1, d2, d3, d4, d5, d6 = (
        mp[0, 3],
        mp[1, 3],
        mp[2, 3],
        mp[3, 3],
        mp[4, 3],
        mp[5, 3],
        mp[6, 3],
    )
    return (
        t2q, t2v, t2f, t2c, t2s, t3q, t3v, t3f, t3c, t3s, t4q, t4v, t4f, t4c, t4s, t5q,
        t5v, t5f, t5c, t5s, t6q, t6v, t6f, t6c, t6s, g0, g1, g2, g3, g4, g5, g6, d0, d1,
        d2, d3, d4, d5, d6
    )  # fmt: skip


@intrinsic
def fma(typingctx, a, b, c):
    """``fl(a·b + c)``, rounded once (LLVM's ``llvm.fma``): the same bits in scalar and vector
    code and whatever products the compiler would fuse around it."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)

    return sig, codegen


# The fast hop and its tangent update are written so that no product meets a sum outside an
# explicit fma: every multiply-add is fused in the source, and no addition or subtraction has a
# plain product as an operand. Compiled with or without ``contract``, in scalar or vector code,
# they then round alike, so the same hop gives the same bits in the event loop and in the lanes
# of oscillators/engines/_relay_lanes.py (tests/test_oscillators/test_fast_hop.py compiles them
# both ways and compares).
@njit(cache=True, inline="always", error_model="numpy")
def fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon):
    """The fast short hop (module docstring) from (q, v, cos φ, sin φ) with the output force
    ``force`` = C·M to the threshold ``gap`` = θ − q away: returns ``(ok, h, v, cos φ, sin φ)``
    at the crossing, ``ok`` False when the step's error bound (< 1e-17), the monotonicity of q
    on [0, h], ``h < h_small`` or ``h <= horizon`` fails (the caller then takes another path;
    the other values are then meaningless). Branch-free: the same code serves one system
    (:func:`hop`, after its test ``|gap| < h_small |v|``) and many side by side
    (:mod:`oscillators.engines._relay_lanes`).

    Plain reading (every ``a·b + c`` below is one :func:`fma`)::

        e_n = linear form of (q, v, F, cos φ, sin φ)            n = 2..6, q's Taylor coefficients
        x = gap / v;  h0 = x − k2 x² + (2 k2² − k3) x³          series reversion, k_n = e_n / v
        res = q(h0) − θ;  1/q'(h0) ≈ (1 − u)(1 + u²)/v          one Newton step h = h0 − res/q'
        v(h), cos φ(h), sin φ(h) corrected to first order in the Newton step
        ok = 0 < h <= horizon, h < h_small, error bound <= 1e-17, |v(s) − v| < |v|/2 on [0, h]
    """
    (
        t2q, t2v, t2f, t2c, t2s, t3q, t3v, t3f, t3c, t3s, t4q, t4v, t4f, t4c, t4s, t5q,
        t5v, t5f, t5c, t5s, t6q, t6v, t6f, t6c, t6s, g0, g1, g2, g3, g4, g5, g6, d0, d1,
        d2, d3, d4, d5, d6
    ) = coefs  # fmt: skip
    e2 = fma(t2q, q, fma(t2v, v, fma(t2f, force, fma(t2c, c, t2s * s))))
    e3 = fma(t3q, q, fma(t3v, v, fma(t3f, force, fma(t3c, c, t3s * s))))
    e4 = fma(t4q, q, fma(t4v, v, fma(t4f, force, fma(t4c, c, t4s * s))))
    e5 = fma(t5q, q, fma(t5v, v, fma(t5f, force, fma(t5c, c, t5s * s))))
    e6 = fma(t6q, q, fma(t6v, v, fma(t6f, force, fma(t6c, c, t6s * s))))
    r = 1.0 / v
    x = gap * r
    k2 = e2 * r
    k3 = e3 * r
    # series reversion of x = h + k2 h^2 + k3 h^3 + ... to third order
    h0 = fma(x * x, fma(x, fma(2.0 * k2, k2, -k3), -k2), x)
    # everything the Newton step needs is a polynomial in h0, side by side and in Estrin form
    # (short dependency chains): the residual, 1/q'(h0) = r/(1 + u) by its series, v and q''
    # at h0, and the phase rotation; the step then corrects them to first order in dh
    hh2 = h0 * h0
    res = fma(h0, fma(hh2, fma(hh2, fma(e6, h0, e5), fma(e4, h0, e3)), fma(e2, h0, v)), -gap)
    poly_u = fma(4.0 * e4 * r, hh2, fma(3.0 * k3, h0, 2.0 * k2))
    u = h0 * poly_u
    one_minus_u = fma(-h0, poly_u, 1.0)
    inv = r * fma(u * u, one_minus_u, one_minus_u)
    dp0 = fma(
        hh2, fma(hh2, fma(6.0 * e6, h0, 5.0 * e5), fma(4.0 * e4, h0, 3.0 * e3)),
        fma(2.0 * e2, h0, v),
    )  # fmt: skip
    pp0 = fma(hh2, fma(20.0 * e5, h0, 12.0 * e4), fma(6.0 * e3, h0, 2.0 * e2))
    xr = omega * h0
    x2 = xr * xr
    cx = fma(-x2, fma(-x2, 1.0 / 24.0, 0.5), 1.0)
    sx = xr * fma(-x2, fma(-x2, 1.0 / 120.0, 1.0 / 6.0), 1.0)
    c0r = fma(c, cx, -(s * sx))
    s0r = fma(s, cx, c * sx)
    dh = res * inv
    hf = fma(-res, inv, h0)
    av = abs(v)
    # accept when the step's error (derivative series: |dh| u^4; Newton and the first-order
    # corrections: ~|q''|/|v| dh^2) is far below one ulp of the time and q is provably
    # monotone on [0, hf] (|v(s) - v| < |v|/2): theta is then the first crossing
    ae2 = abs(e2)
    slope = hf * fma(
        hf, fma(hf, fma(hf, fma(hf, 6.0 * abs(e6), 5.0 * abs(e5)), 4.0 * abs(e4)),
                3.0 * abs(e3)), 2.0 * ae2,
    )  # fmt: skip
    uu = u * u
    err = fma(abs(dh), fma(uu, uu, 1e-13), dh * dh * fma(3.0, abs(e3), ae2) / av)
    # & rather than and: no branches, so a loop over many systems vectorizes
    ok = (0.0 < hf) & (hf <= horizon) & (hf < h_small) & (err <= 1e-17) & (slope < 0.5 * av)
    dphi = omega * dh
    return ok, hf, fma(-dh, pp0, dp0), fma(dphi, s0r, c0r), fma(-dphi, c0r, s0r)


@njit(cache=True, inline="always", error_model="numpy")
def fast_propagator(coefs, h):
    """g = Φ_01(h) and g' (degree 6 in h) for the tangent flow of a fast hop:
    Φ(h) = [[g' + 2ζg, g], [-g, g']]."""
    g0, g1, g2, g3, g4, g5, g6, d0, d1, d2, d3, d4, d5, d6 = coefs[25:]
    hp2 = h * h
    hp4 = hp2 * hp2
    g = fma(hp4, fma(hp2, g6, fma(g5, h, g4)), fma(hp2, fma(g3, h, g2), fma(g1, h, g0)))
    gd = fma(hp4, fma(hp2, d6, fma(d5, h, d4)), fma(hp2, fma(d3, h, d2), fma(d1, h, d0)))
    return g, gd


@njit(cache=True, inline="always", error_model="numpy")
def fast_matrix(coefs, zeta, h):
    """Φ(h) = [[m00, g], [-g, g']] of a fast hop as ``(m00, g, g')``, m00 = g' + 2ζg."""
    g, gd = fast_propagator(coefs, h)
    return fma(2.0 * zeta, g, gd), g, gd


@njit(cache=True, inline="always", error_model="numpy")
def fast_tangent(coefs, zeta, h, a0, a1, b0, b1):
    """The two (δq, δv) columns after a fast hop of length ``h``: [δq, δv] := Φ(h) [δq, δv]
    (:func:`fast_matrix`), every multiply-add fused in the source."""
    m00, g, gd = fast_matrix(coefs, zeta, h)
    return (
        fma(m00, a0, g * b0),
        fma(m00, a1, g * b1),
        fma(-g, a0, gd * b0),
        fma(-g, a1, gd * b1),
    )


@njit(cache=True, inline="always", error_model="numpy")
def saltation(coupling, jump, v, a0, a1, b0, b1):
    """δv after a switch of ``jump`` at velocity ``v`` (the two tangent columns): δv += C ΔM /
    v* · δq (paper eq. salt_matrix), fused in the source."""
    sal = coupling * jump / v
    return fma(sal, a0, b0), fma(sal, a1, b1)


@njit(cache=True, inline="always", error_model="numpy")
def slides(zeta, coupling, slide, q, v, c, mv, jump, direction, prev_q, prev_jump):
    """Whether a switch of ``jump`` in ``direction`` at ``q`` (output ``mv`` after it) enters a
    Filippov sliding motion: it undoes the previous switch at the same threshold, the flow pushes
    into the threshold from both sides and the excursion just begun lasts ``2|v|/|q''| <=
    slide`` (:func:`settle_switch`). Fused in the source, so every event loop decides alike."""
    if not (jump == -prev_jump and q == prev_q and jump != 0.0):
        return False
    a_now = fma(coupling, mv, fma(-2.0 * zeta, v, c - q))
    a_before = fma(-coupling, jump, a_now)
    return (
        direction * a_before > 0.0
        and direction * a_now < 0.0
        and 2.0 * abs(v) <= slide * abs(a_now)
    )


@njit(cache=True, fastmath=_CONTRACT, inline="always")
def hop(
    par, coefs, mp, e, q, v, tau, c, s, up, down, mv, tau_stop, tan_on, ntan,
    a0, a1, a2, b0, b1, b2, f0, f1, f2, integral,
):  # fmt: skip
    """One hop of the event loop (module docstring): from (q, v) at period time ``tau`` with
    the output ``mv`` to the first crossing of ``up`` (reached) or ``down`` (left below) on the
    exact solution, or to ``tau_stop`` (> ``tau``) if none comes first; fast short hop, Taylor
    hop or exact flight, the tangent columns propagated while ``tan_on``. Returns
    ``(direction, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral)``: direction +1 / -1 at a
    crossing (q set exactly on the threshold), 0 at ``tau_stop``. Shared by every event loop
    over piecewise-constant operators (the relay tables here, interacting spins in
    :mod:`oscillators.engines._switching_kernels`); inlined, so it costs no call."""
    zeta = par[P_ZETA]
    omega = par[P_OMEGA]
    coupling = par[P_C]
    phi0 = par[P_PHI0]
    amp_a = par[P_A]
    amp_b = par[P_B]
    h_taylor = par[P_HT]
    h_small = par[P_HS]
    horizon = tau_stop - tau
    force = coupling * mv
    mode = 0  # 1 Taylor hop to a switch, 2 Taylor hop to the stop, 0 exact flight, 3 fast hop
    direction = 0
    h = 0.0
    theta = 0.0
    tdir = 0
    if h_small > 0.0 and v != 0.0:
        # fast short hop (see the module docstring)
        theta = up if v > 0.0 else down
        gap = theta - q
        if abs(gap) < h_small * abs(v):
            ok, hf, v1, c1, s1 = fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon)
            if ok:
                if tan_on and ntan == 3:
                    m00, g, gd = fast_matrix(coefs, zeta, hf)
                    a0, a1, a2, b0, b1, b2 = _hop_tangent(
                        m00, g, -g, gd, c, s, c1, s1, omega, amp_a, amp_b, ntan,
                        a0, a1, a2, b0, b1, b2, f0, f1, f2,
                    )  # fmt: skip
                elif tan_on:
                    a0, a1, b0, b1 = fast_tangent(coefs, zeta, hf, a0, a1, b0, b1)
                direction = 1 if v > 0.0 else -1
                c = c1
                s = s1
                v = v1
                integral = fma(mv, hf, integral)
                q = theta
                tau += hf
                mode = 3
    if mode == 0 and h_taylor > 0.0:
        # general Taylor path: coefficients up to ORDER from the same linear forms
        e[0] = q
        e[1] = v
        for n in range(2, ORDER + 1):
            e[n] = (
                mp[n, TC_Q] * q
                + mp[n, TC_V] * v
                + mp[n, TC_F] * force
                + mp[n, TC_C] * c
                + mp[n, TC_S] * s
            )
        av = abs(v)
        if v > 0.0:
            tdir = 1
            theta = up
            gap = up - q
        elif v < 0.0:
            tdir = -1
            theta = down
            gap = q - down
        else:
            gap = np.inf
        disc = v * v + 4.0 * tdir * e[2] * gap
        if gap < h_taylor * av and disc > 0.0:
            # start from the root of the quadratic Taylor polynomial (stable form), then
            # Newton; stop once the next Newton error (~ |q''|/(2|v|) dh^2) is below 1e-17
            h = 2.0 * gap / (av + math.sqrt(disc))
            curv = abs(e[2]) + abs(e[3]) * h
            converged = False
            for _ in range(8):
                p, dp = _poly2(e, h)
                dh = (p - theta) / dp
                h -= dh
                if dh * dh * curv <= 1e-17 * av:
                    converged = True
                    break
            if converged and 0.0 < h <= h_taylor and _slope_bound(e, h) < 0.5 * av:
                mode = 1 if h <= horizon else 2
        if mode == 0 and horizon <= h_taylor:
            b = _excursion_bound(e, horizon)
            if q + b < up and q - b >= down:
                mode = 2
    if mode == 1 or mode == 2:
        hh = h if mode == 1 else horizon
        # reload e here, as when reference counting calls stood before this point: reusing the
        # Newton loop's products n·e[n] would fuse other multiply-adds (different last bits)
        _memory_barrier()
        p, dp = _poly2(e, hh)
        cx, sx = _rotation(omega * hh)
        c1 = c * cx - s * sx
        s1 = s * cx + c * sx
        if tan_on:
            m00 = mp[ORDER, 0]
            m01 = mp[ORDER, 1]
            m10 = mp[ORDER, 2]
            m11 = mp[ORDER, 3]
            for n in range(ORDER - 1, -1, -1):
                m00 = m00 * hh + mp[n, 0]
                m01 = m01 * hh + mp[n, 1]
                m10 = m10 * hh + mp[n, 2]
                m11 = m11 * hh + mp[n, 3]
            a0, a1, a2, b0, b1, b2 = _hop_tangent(
                m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b, ntan,
                a0, a1, a2, b0, b1, b2, f0, f1, f2,
            )  # fmt: skip
        c = c1
        s = s1
        v = dp
        integral += mv * hh  # M is constant over the hop
        if mode == 2:
            q = p
            tau = tau_stop
            return 0, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral
        q = theta
        tau += hh
        direction = tdir
    elif mode == 0:
        ph = phi0 + omega * tau
        c = math.cos(ph)
        s = math.sin(ph)
        hc, direction = scan_crossing(par, force, q, v, c, s, tau, horizon, up, down)
        hh = hc if direction != 0 else horizon
        ph1 = phi0 + omega * (tau + hh)
        c1 = math.cos(ph1)
        s1 = math.sin(ph1)
        q1, v1 = exact_step(q, v, c, s, c1, s1, force, hh, zeta, omega, amp_a, amp_b)
        if tan_on:
            m00, m01, m10, m11 = hom_matrix(hh, zeta)
            a0, a1, a2, b0, b1, b2 = _hop_tangent(
                m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b, ntan,
                a0, a1, a2, b0, b1, b2, f0, f1, f2,
            )  # fmt: skip
        c = c1
        s = s1
        v = v1
        integral += mv * hh
        if direction == 0:
            q = q1
            tau = tau_stop
            return 0, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral
        q = up if direction > 0 else down
        tau += hh
    return direction, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral


@njit(cache=True, fastmath=_CONTRACT, inline="always")
def settle_switch(
    par, st, ist, q, v, c, tau, mv, jump, direction, nsw, nsw_max, prev_q, prev_jump, tan_on,
    ntan, a0, a1, a2, b0, b1, b2, rec_on, sw, sw_count,
):  # fmt: skip
    """What follows a switch of ``jump`` in ``direction`` at ``q`` (the ``nsw``-th event; ``mv``
    the output after it), in every event loop: the sliding test, the switch budget, the
    saltation of the tangent columns and the record. Returns ``(status, b0, b1, b2, prev_q,
    prev_jump)`` with status 0 (go on) or the stop of :func:`advance_table` (1 record buffer
    full, 2 grazing, 3 budget spent, 4 sliding: jump and direction in ``st[S_JMP]``,
    ``st[S_DIR]``)."""
    zeta = par[P_ZETA]
    coupling = par[P_C]
    if slides(zeta, coupling, par[P_SL], q, v, c, mv, jump, direction, prev_q, prev_jump):
        st[S_JMP] = jump
        st[S_DIR] = direction
        return 4, b0, b1, b2, prev_q, prev_jump  # sliding: the caller integrates it
    prev_q = q
    prev_jump = jump
    if nsw >= nsw_max:
        # switch budget spent (the caller raises SlidingError or SwitchBudgetError); the
        # tangent and the record of this last switch are left out
        st[S_JMP] = jump
        st[S_DIR] = direction
        return 3, b0, b1, b2, prev_q, prev_jump
    if tan_on and coupling * jump != 0.0:
        if v == 0.0:
            return 2, b0, b1, b2, prev_q, prev_jump  # grazing: infinite saltation
        # saltation X = [[1,0,0],[C ΔM / v*, 1, 0],[0,0,1]]
        b0, b1 = saltation(coupling, jump, v, a0, a1, b0, b1)
        if ntan == 3:
            b2 += coupling * jump / v * a2
    if rec_on:
        i = sw_count[0]
        sw[i, 0] = par[P_TBASE] + ist[I_N] * par[P_T] + tau
        sw[i, 1] = q
        sw[i, 2] = v
        sw[i, 3] = jump
        sw_count[0] = i + 1
        if i + 1 >= sw.shape[0]:
            return 1, b0, b1, b2, prev_q, prev_jump
    return 0, b0, b1, b2, prev_q, prev_jump


# -- the event loop (one body for every table kind) ----------------------------------------------
@njit(cache=True, fastmath=_CONTRACT, **_LOOP_OPTIONS)
def advance_table(
    par, kind, tf, ti, bits, lay, st, ist, tau_stop, tan_on, y, ntan, e, mp, rec_on, sw, sw_count
):
    """Advance the kernel state (st, ist, table state) to period time ``tau_stop``.

    Switch records go to ``sw`` (rows: time, q, v, ΔM) while ``rec_on``. Returns 0 when
    ``tau_stop`` was reached, 1 if the record buffer filled up (state left right after the last
    recorded switch; call again to continue), 2 at a grazing switch (v* = 0) while ``tan_on``
    (state left right after that switch, tangent not updated by it), 3 when the switch count
    reaches ``ist[I_MAXSW]`` (the switch budget; state right after that switch, which is neither
    recorded nor applied to the tangent; its jump and direction in ``st[S_JMP]``,
    ``st[S_DIR]``), 4 at a switch where the motion enters a Filippov sliding motion (it
    reverses the previous switch at the same threshold with the opposite jump, the flow pushes
    into the threshold from both sides and the excursion just begun lasts ``2|v|/|q''| <=
    par[P_SL]``; state right after that switch, neither recorded nor applied to the tangent,
    its jump and direction in ``st[S_JMP]``, ``st[S_DIR]``; the caller integrates the slide,
    :mod:`oscillators.engines._sliding`). Tangent vectors (columns of ``y``, rows δq, δv,
    δφ) are propagated while ``tan_on``. ``st[S_UP]``, ``st[S_DN]`` and ``st[S_MV]`` must be current
    (:func:`_table_refresh`).
    """
    q = st[S_Q]
    v = st[S_V]
    tau = st[S_TAU]
    c = st[S_COS]
    s = st[S_SIN]
    up = st[S_UP]
    down = st[S_DN]
    mv = st[S_MV]
    nsw = ist[I_NSW]
    nsw_max = ist[I_MAXSW]
    # the fast hop's coefficients as locals (hop_coefficients)
    coefs = hop_coefficients(mp)
    integral = st[S_IM]
    # the tangent columns live in registers during the loop (y is 3×3; unused columns are zero)
    a0, a1, a2 = y[0, 0], y[0, 1], y[0, 2]
    b0, b1, b2 = y[1, 0], y[1, 1], y[1, 2]
    f0, f1, f2 = y[2, 0], y[2, 1], y[2, 2]
    status = 0
    # the previous switch (threshold, jump): a switch undoing it at the same threshold is a
    # zero-width group chattering, the candidate of a sliding motion
    prev_q = st[S_PQ]
    prev_jump = st[S_PJ]
    while True:
        horizon = tau_stop - tau
        if horizon <= 0.0:
            break
        direction, q, v, tau, c, s, a0, a1, a2, b0, b1, b2, integral = hop(
            par, coefs, mp, e, q, v, tau, c, s, up, down, mv, tau_stop, tan_on, ntan,
            a0, a1, a2, b0, b1, b2, f0, f1, f2, integral,
        )  # fmt: skip
        if direction == 0:
            break
        # the switch: every relay at this threshold flips at once
        jump = _table_switch(par, kind, tf, ti, bits, lay, st, ist, direction)
        up = st[S_UP]
        down = st[S_DN]
        mv = st[S_MV]
        nsw += 1
        status, b0, b1, b2, prev_q, prev_jump = settle_switch(
            par, st, ist, q, v, c, tau, mv, jump, direction, nsw, nsw_max, prev_q, prev_jump,
            tan_on, ntan, a0, a1, a2, b0, b1, b2, rec_on, sw, sw_count,
        )  # fmt: skip
        if status != 0:
            break
    st[S_Q] = q
    st[S_V] = v
    st[S_TAU] = tau
    st[S_COS] = c
    st[S_SIN] = s
    st[S_IM] = integral
    st[S_PQ] = prev_q
    st[S_PJ] = prev_jump
    ist[I_NSW] = nsw
    if tan_on:
        y[0, 0], y[0, 1], y[0, 2] = a0, a1, a2
        y[1, 0], y[1, 1], y[1, 2] = b0, b1, b2
    return status


@njit(cache=True)
def _wrap(par, st, ist):
    st[S_TAU] = 0.0
    st[S_COS] = math.cos(par[P_PHI0])
    st[S_SIN] = math.sin(par[P_PHI0])
    ist[I_N] += 1


@njit(cache=True)
def run_table(
    par,
    kind,
    tf,
    ti,
    bits,
    lay,
    st,
    ist,
    tgt_n,
    tgt_tau,
    i_start,
    out,
    rec_on,
    sw,
    sw_count,
    tan_on,
    y,
    ntan,
    mp,
):
    """Advance through the targets (period index, period time) from target ``i_start``.

    Row i of ``out`` (if ``out`` has rows) receives (q, v, M) at target i. Returns (status,
    next target index); status as :func:`advance_table` (0 done, 1 record buffer full, 2
    grazing switch with the tangent flow on, 3 switch budget spent, 4 sliding motion).
    """
    e = np.empty(ORDER + 1)
    period = par[P_T]
    sample = out.shape[0] > 0
    for i in range(i_start, tgt_n.shape[0]):
        while ist[I_N] < tgt_n[i]:
            status = advance_table(
                par, kind, tf, ti, bits, lay, st, ist, period, tan_on, y, ntan, e, mp, rec_on,
                sw, sw_count,
            )  # fmt: skip
            if status != 0:
                return status, i
            _wrap(par, st, ist)
        status = advance_table(
            par, kind, tf, ti, bits, lay, st, ist, tgt_tau[i], tan_on, y, ntan, e, mp, rec_on,
            sw, sw_count,
        )  # fmt: skip
        if status != 0:
            return status, i
        if sample:
            out[i, 0] = st[S_Q]
            out[i, 1] = st[S_V]
            out[i, 2] = st[S_MV]
    return 0, tgt_n.shape[0]


# -- building the kernel tables (Python) ----------------------------------------------------------
def nested_kernel_table(plan) -> tuple:
    """(tf, ti, bits, lay) for a :class:`~hysteresis.relay_table.NestedPlan` (kind 0)."""
    tf = np.concatenate([plan.up, plan.down, plan.mval]).astype(np.float64)
    lay = np.array([plan.up.size], dtype=np.int64)
    return tf, np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.uint64), lay


# One compiled entry point per table kind: the kind is a compile-time constant inside each, so
# LLVM folds the other kind's branches out of the hot loop (measured: a runtime kind costs the
# nested kernel a factor ~2 in register pressure and code size). Same body, no duplication.
@njit(cache=True)
def run_nested(
    par, tf, ti, bits, lay, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw, sw_count, tan_on, y,
    ntan, mp,
):  # fmt: skip
    """:func:`run_table` for the nested plan (kind 0)."""
    return run_table(
        par, KIND_NESTED, tf, ti, bits, lay, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw,
        sw_count, tan_on, y, ntan, mp,
    )  # fmt: skip


@njit(cache=True)
def run_heap(
    par, tf, ti, bits, lay, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw, sw_count, tan_on, y,
    ntan, mp,
):  # fmt: skip
    """:func:`run_table` for the bitset heaps (kind 1)."""
    return run_table(
        par, KIND_HEAP, tf, ti, bits, lay, st, ist, tgt_n, tgt_tau, i_start, out, rec_on, sw,
        sw_count, tan_on, y, ntan, mp,
    )  # fmt: skip
